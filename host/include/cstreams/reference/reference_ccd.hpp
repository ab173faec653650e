#pragma once
#include <cstreams/geometry/bvh.hpp>
#include <cstreams/contacts.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/reference/reference_solver.hpp>
#include <cstreams/scene/scene.hpp>
#include <cstreams/geometry/topology.hpp>

#include <cstdint>
#include <vector>

namespace cstreams {

// One step of a scene: every object's positions at the start and end of the step.
struct Step {
  const Scene* scene = nullptr;
  std::vector<std::vector<Vec3>> x0, x1;  // per object
};
// Reads frames `frame` and `frame + 1` of every object; a static object stays put.
Step load_step(const Scene& scene, std::size_t frame);

// Feature pairs to test, for one ordered pair of objects: vertices of `object_a`
// against faces of `object_b`, and edges of `object_a` against edges of `object_b`
// (edge pairs only when object_a <= object_b).
struct CandidateBlock {
  std::uint32_t object_a = 0, object_b = 0;
  std::vector<VertexFace> vf;
  std::vector<EdgeEdge> ee;
};
struct Candidates {
  std::vector<CandidateBlock> blocks;  // sorted by (object_a, object_b); pairs sorted inside
  std::size_t vf_count() const;
  std::size_t ee_count() const;
  friend bool operator==(const Candidates& a, const Candidates& b);
};

enum class BroadPhase { bvh, brute_force };
// Double: the host's own outward-rounded boxes. Single: the device's float boxes
// (float_bounds), so the candidates are exactly those a device pipeline must find.
enum class BoundsPrecision { double_, single };

struct ReferenceOptions {
  BroadPhase broad_phase = BroadPhase::bvh;
  BoundsPrecision bounds = BoundsPrecision::double_;
  ReferenceSolverOptions solver;  // its min_separation also inflates the BVs
  // The tolerance of the solver the candidates go to, relative to their coordinates
  // (the device's: SolverOptions::tolerance): feature pairs that stay more than 3 of it
  // (and the separation) apart through the step are left out.
  double tolerance = 1e-5;
};

// The host broad phase: swept 18-DOPs, triangle pairs of overlapping BVs (non-adjacent
// within an object), their feature pairs by ownership less those whose points stay
// apart through the step (as the device's decomposition, broad_phase.cl), and orphans
// of self-colliding objects culled by their swept BVs. BVH traversal and brute force
// give the same set.
Candidates reference_broad_phase(const Step& step, const ReferenceOptions& options = {});

// Runs the reference solver on every candidate (in parallel) and returns the
// colliding ones in canonical order.
std::vector<Contact> reference_narrow_phase(const Step& step, const Candidates& candidates,
                                            const ReferenceSolverOptions& options = {});

std::vector<Contact> reference_ccd(const Step& step, const ReferenceOptions& options = {});

// The query of one feature pair, in the solver's point order.
Query vertex_face_query(const Step& step, std::uint32_t object_a, std::uint32_t object_b, VertexFace pair);
Query edge_edge_query(const Step& step, std::uint32_t object_a, std::uint32_t object_b, EdgeEdge pair);
Contact make_contact(const Step& step, std::uint32_t object_a, std::uint32_t object_b, VertexFace pair, double toi);
Contact make_contact(const Step& step, std::uint32_t object_a, std::uint32_t object_b, EdgeEdge pair, double toi);

}  // namespace cstreams
