#pragma once
// What the host writes into a scene's streams: topology, trees and the positions the
// scene starts from once, and each object's new positions per step.
#include <cstreams/detector.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstdint>
#include <vector>

namespace cstreams {

// Writes everything the graph reads that does not change from step to step, static
// objects' bounds included (computed once by the host's float twin of the device), and
// the positions the scene starts from. Returns whether each object's positions are
// floats (FloatPositions::exact).
std::vector<bool> upload_scene(runtime::Scheduler& scheduler, const CcdGraph& graph, const SceneLayout& layout,
                               const SceneDescription& scene, double min_separation);

// The checks a moving object's positions from a caller must pass (an InputError naming
// the object): all of them, or all but that of the coordinates (which rounding to float
// makes in the same pass, round_to_float()).
void check_positions(const SceneDescription& scene, std::uint32_t object, PositionSpan x);
void check_moving_object(const SceneDescription& scene, std::uint32_t object, PositionSpan x);

}  // namespace cstreams
