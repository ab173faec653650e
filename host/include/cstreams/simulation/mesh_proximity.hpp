#pragma once
// What a barrier's active set asks at every Newton iteration, on a simulator's arrays:
// every pair of the mesh closer than dhat at positions V, with its distance and which
// features are closest (ipc-toolkit's distance types), or just the broad phase's
// candidate pairs.
//
//   cstreams::MeshProximity proximity(device, cstreams::CollisionMesh(V_rest, F));
//   for (const cstreams::ClosePair& p : proximity.close_pairs(V, dhat)) ...
//
// Adjacent features (sharing a vertex) are never paired. Segments and points (the
// mesh's edges in no face and vertices in neither) pair with everything as their
// degenerate faces (ObjectDescription::segments). Distances are computed in the
// options' precision; a pair is reported where its distance is below dhat, or above it
// by at most 16 units of rounding at the pair's coordinates (2^-48 of their magnitude
// in double, 2^-19 in single), so that none closer than dhat is missed. One object
// keeps its BVH and front between calls, for the iterations' nearby positions.
#include <cstreams/detector.hpp>
#include <cstreams/simulation/collision_mesh.hpp>

#include <memory>
#include <vector>

namespace cstreams {

struct MeshProximityOptions {
  Precision precision = Precision::double_;  // single where the device has no fp64
  FrontMode front = FrontMode::exact;
  bool profile = false;  // per-pass device times in stats()
};

class MeshProximity {
public:
  MeshProximity(runtime::Context& device, CollisionMesh mesh, MeshProximityOptions options = {});
  ~MeshProximity();
  MeshProximity(const MeshProximity&) = delete;
  MeshProximity& operator=(const MeshProximity&) = delete;

  // Every vertex-face and edge-edge pair closer than dhat at V, in canonical order:
  // valid until the next call (copy them to keep them).
  template <typename A> const std::vector<ClosePair>& close_pairs(const Eigen::MatrixBase<A>& V, double dhat)
  {
    return close_pairs(positions_view(V, "V", vertex_count(), copy()), dhat);
  }
  const std::vector<ClosePair>& close_pairs(const std::vector<Vec3>& V, double dhat);

  // The broad phase's pairs at V: vertex-face and edge-edge pairs whose features'
  // boxes come within `radius` of each other (boxes inflated by radius / 2 overlap,
  // as ipc-toolkit's inflation radius), sorted.
  template <typename A> CandidateBlock candidates(const Eigen::MatrixBase<A>& V, double radius)
  {
    return candidates(positions_view(V, "V", vertex_count(), copy()), radius);
  }
  CandidateBlock candidates(const std::vector<Vec3>& V, double radius);

  std::size_t vertex_count() const;
  const CollisionMesh& mesh() const;
  const DetectorStats& stats() const;  // the last call's

private:
  // The Eigen calls' V where it must be copied (positions_view), in memory kept from
  // call to call.
  std::vector<Vec3>& copy();
  const std::vector<ClosePair>& close_pairs(PositionSpan V, double dhat);
  CandidateBlock candidates(PositionSpan V, double radius);

  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cstreams
