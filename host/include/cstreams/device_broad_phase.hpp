#pragma once
#include <cstreams/device_bvh.hpp>
#include <cstreams/narrow_phase.hpp>
#include <cstreams/reference_ccd.hpp>

#include <memory>
#include <optional>

namespace cstreams {

// The broad phase of one self-colliding mesh on a device, as one stream graph: swept
// float bounds and BVH refit (DeviceBvh's passes), BVTT traversal from a fixed seed
// front to non-adjacent triangle pairs, their decomposition into vertex-face and
// edge-edge pairs by feature ownership with the cull by feature bounds, and the cull of
// the orphan pairs (uploaded once). Its candidates equal the host's
// reference_broad_phase with BoundsPrecision::single exactly. With `narrow_phase`
// the graph goes on to the elementary tests over every candidate stream (single
// precision only, on the float positions already on the device) and the contacts.
// The topology is kept by reference and must outlive this object.
class DeviceBroadPhase {
public:
  DeviceBroadPhase(runtime::Context& context, const Topology& topology, const Bvh& bvh, float separation,
                   runtime::Registration registration = runtime::Registration::segmented_lock,
                   std::optional<SolverOptions> narrow_phase = std::nullopt);
  ~DeviceBroadPhase();

  // Runs one step; the result is in canonical order (one block, object 0 against itself).
  Candidates run(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1);
  // The last run's contacts (object 0 against itself), canonical order; needs a narrow phase.
  std::vector<Contact> contacts() const;
  runtime::Scheduler& scheduler() { return *scheduler_; }

private:
  struct Streams;
  std::unique_ptr<Streams> streams_;
  std::unique_ptr<runtime::Scheduler> scheduler_;
  const Topology& topology_;
  bool narrow_phase_;
};

// BVTT node pairs from which traversal starts: (root, root) expanded without bounds
// tests, breadth first, until there are at least `target` pairs or only leaf pairs are
// left. Depth-first traversal from every seed meets exactly the pairs that traversal
// from the root meets.
std::vector<std::array<std::int32_t, 2>> seed_front(const Bvh& bvh, std::size_t target);

}  // namespace cstreams
