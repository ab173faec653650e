#pragma once
// A proximity step's pairs as the user gets them: the close-pairs stream sorted on the
// device, read in one transfer into pinned memory, its ids made local to their objects.
// Sorted by global ids, the pairs of a scene of one object (the array API's) are in
// canonical order; those of several objects are sorted again on the host. Host memory
// is kept from one step to the next, so that a step of as many pairs as the last
// touches no fresh pages.
#include "feature_ids.hpp"

#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/proximity.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <vector>

namespace cstreams {

class ClosePairReadback {
public:
  ClosePairReadback(runtime::Context& context, const SceneLayout& layout, const FeatureIds& ids)
      : context_(context), layout_(layout), ids_(ids), sorter_(context, 4)
  {
  }

  // Sorts the stream in its buffer (the step no longer reads it); `stats` receives the
  // sort's device time (with `profile`) and launches.
  void read(const runtime::Scheduler& scheduler, runtime::StreamId close_pairs, bool profile,
            runtime::PassStats& stats, std::vector<ClosePair>& out);

private:
  runtime::Context& context_;
  const SceneLayout& layout_;
  const FeatureIds& ids_;
  runtime::Sorter sorter_;
  runtime::HostStaging records_;  // proximity.cl's records as read
};

}  // namespace cstreams
