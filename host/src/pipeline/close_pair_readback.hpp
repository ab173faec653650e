#pragma once
// A proximity step's pairs as the user gets them: the close-pairs stream read in one
// transfer into pinned memory, its ids made local to their objects, in canonical order.
// Its host memory is kept from one step to the next, so that a step of as many pairs
// as the last touches no fresh pages.
#include "feature_ids.hpp"

#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/proximity.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <vector>

namespace cstreams {

class ClosePairReadback {
public:
  ClosePairReadback(runtime::Context& context, const SceneLayout& layout, const FeatureIds& ids)
      : context_(context), layout_(layout), ids_(ids)
  {
  }

  void read(const runtime::Scheduler& scheduler, runtime::StreamId close_pairs, std::vector<ClosePair>& out);

private:
  runtime::Context& context_;
  const SceneLayout& layout_;
  const FeatureIds& ids_;
  runtime::HostStaging records_;  // proximity.cl's records as read
};

}  // namespace cstreams
