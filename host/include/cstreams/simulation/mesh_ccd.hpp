#pragma once
// What an implicit contact solver calls many times a step, on its arrays: the earliest
// time of impact of a linear motion V0 -> V1, whether the motion is free of collisions,
// and how far along it a step may go (ipc-toolkit's is_step_collision_free and
// compute_collision_free_stepsize).
//
//   cstreams::runtime::Context device("nvidia");
//   cstreams::MeshCcd ccd(device, cstreams::CollisionMesh(V_rest, F));
//   double alpha = ccd.collision_free_stepsize(V0, V1);  // in [0, 1]
//   V = V0 + alpha * (V1 - V0);                          // no pair comes closer than 0
//
// One MeshCcd keeps its BVH and its BVTT front between calls, so the repeated calls of
// a line search on nearby motions stay on the warm path. Arrays are #V x 3, double or
// float, either storage order; a bad one is an InputError naming it, and changes
// nothing.
#include <cstreams/detector.hpp>
#include <cstreams/simulation/collision_mesh.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace cstreams {

// One call's parameters, as ipc-toolkit's narrow phase names them.
struct CcdParameters {
  // Pairs closer than this collide (units of V). The solvers measure it in the max
  // norm: no pair closer than it is missed, and one up to sqrt(3) times as far apart
  // may collide (ipc-toolkit measures it in the Euclidean norm).
  double min_distance = 0;
  // Relative to a pair's largest coordinate: the conservative solver's co-domain
  // tolerance (SolverOptions::tolerance).
  double tolerance = 1e-5;
  // Per query; a query that reaches it collides at the earliest time it still allows.
  std::uint32_t max_iterations = 100000;
  double tmax = 1;  // only the part [0, tmax] of the motion is checked
};

// ipc-toolkit's DEFAULT_CCD_CONSERVATIVE_RESCALING.
constexpr double default_conservative_rescaling = 0.8;

struct MeshCcdOptions {
  Solver solver = Solver::conservative;  // never misses a collision; the cubic can
  Precision precision = Precision::single;
  FrontMode front = FrontMode::exact;
  bool profile = false;  // per-pass device times in stats()
};

class MeshCcd {
public:
  MeshCcd(runtime::Context& device, CollisionMesh mesh, MeshCcdOptions options = {});
  ~MeshCcd();
  MeshCcd(const MeshCcd&) = delete;
  MeshCcd& operator=(const MeshCcd&) = delete;

  // The earliest time in [0, tmax] at which two features of the mesh come within
  // min_distance, moving linearly from V0 to V1; 1 where none does. Never later than
  // the exact time (with the conservative solver), at most a tolerance earlier.
  template <typename A, typename B>
  double toi(const Eigen::MatrixBase<A>& V0, const Eigen::MatrixBase<B>& V1, const CcdParameters& parameters = {})
  {
    return toi(start(V0), end(V1), parameters);
  }
  double toi(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, const CcdParameters& parameters = {});

  // Whether no two features come within min_distance anywhere along V0 -> V1.
  // Conservative: a motion reported free is free; one that passes closer than a
  // tolerance may be reported not free.
  template <typename A, typename B>
  bool is_step_collision_free(const Eigen::MatrixBase<A>& V0, const Eigen::MatrixBase<B>& V1, double min_distance = 0)
  {
    return is_step_collision_free(start(V0), end(V1), min_distance);
  }
  bool is_step_collision_free(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, double min_distance = 0);

  // ipc-toolkit's compute_collision_free_stepsize: a step size in [0, 1] such that
  // V0 + alpha (V1 - V0) keeps every pair farther apart than min_distance all along;
  // 1 for a full step, 0 for none (V0 itself in contact). Where the motion collides,
  // alpha is the earliest time of impact times `conservative_rescaling`, so the step
  // ends short of the contact rather than on it.
  template <typename A, typename B>
  double collision_free_stepsize(const Eigen::MatrixBase<A>& V0, const Eigen::MatrixBase<B>& V1,
                                 double min_distance = 0,
                                 double conservative_rescaling = default_conservative_rescaling)
  {
    return collision_free_stepsize(start(V0), end(V1), min_distance, conservative_rescaling);
  }
  double collision_free_stepsize(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, double min_distance = 0,
                                 double conservative_rescaling = default_conservative_rescaling);

  std::size_t vertex_count() const;
  const CollisionMesh& mesh() const;
  // The last call's statistics (device time with profile, front, candidates).
  const DetectorStats& stats() const;

private:
  // The arrays where they lie as the detector reads them, else copies in memory kept
  // from call to call (positions_view).
  template <typename A> PositionSpan start(const Eigen::MatrixBase<A>& V0)
  {
    return positions_view(V0, "V0", vertex_count(), copies(0));
  }
  template <typename A> PositionSpan end(const Eigen::MatrixBase<A>& V1)
  {
    return positions_view(V1, "V1", vertex_count(), copies(1));
  }
  std::vector<Vec3>& copies(int end);
  double toi(PositionSpan V0, PositionSpan V1, const CcdParameters& parameters);
  bool is_step_collision_free(PositionSpan V0, PositionSpan V1, double min_distance);
  double collision_free_stepsize(PositionSpan V0, PositionSpan V1, double min_distance, double conservative_rescaling);

  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cstreams
