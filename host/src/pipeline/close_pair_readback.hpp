#pragma once
// A proximity step's pairs as the user gets them: the close-pairs stream read in one
// transfer, its ids made local to their objects, in canonical order.
#include "feature_ids.hpp"

#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/proximity.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <vector>

namespace cstreams {

void read_close_pairs(runtime::Scheduler& scheduler, runtime::StreamId close_pairs, const SceneLayout& layout,
                      const FeatureIds& ids, std::vector<ClosePair>& out);

}  // namespace cstreams
