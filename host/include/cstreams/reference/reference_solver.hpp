#pragma once
#include <cstreams/geometry/mesh.hpp>

#include <array>
#include <cstddef>

namespace cstreams {

// The host's oracle for one elementary test. It never misses a collision: it bounds
// the contact function over boxes of (t, u, v) with interval arithmetic rounded
// outward after every operation (so the bounds hold for the exact real function at
// the box corners) and with the fact that the function is multilinear in (t, u, v)
// (so its range over a box lies within the hull of its corner values). Boxes whose
// bounds exclude zero are dropped; the earliest remaining box is split until its
// bounds are within the tolerance, and its lower t is the time of impact. Running out
// of boxes to split is answered "collision" at the earliest t still possible.
// Boxes are searched depth first, earlier half first, skipping boxes that start after
// (or less than time_resolution before) the earliest contact found; the reported time
// is never later than the first contact, and at most time_resolution (plus the
// tolerance's share) earlier.
struct ReferenceSolverOptions {
  // Co-domain tolerance, relative to the largest coordinate of the query: a box whose
  // image fits in a cube of this size around zero is a contact.
  double tolerance = 1e-8;
  // Contacts closer than this distance count as collisions (0: exact touching only).
  double min_separation = 0;
  // How close to the first contact the reported time must be.
  double time_resolution = 1e-6;
  std::size_t max_boxes = 1000000;
};

struct CcdResult {
  bool collides = false;
  double toi = 1;           // a lower bound on the first time of contact when collides
  bool hit_limit = false;   // max_boxes ran out; the answer is the conservative one
};

// Queries are the eight points of the architecture page's order:
//   vertex-face: p(t0), f0(t0), f1(t0), f2(t0), p(t1), f0(t1), f1(t1), f2(t1)
//   edge-edge:   a0(t0), a1(t0), b0(t0), b1(t0), a0(t1), a1(t1), b0(t1), b1(t1)
using Query = std::array<Vec3, 8>;
CcdResult vertex_face_reference(const Query& q, const ReferenceSolverOptions& options = {});
CcdResult edge_edge_reference(const Query& q, const ReferenceSolverOptions& options = {});

}  // namespace cstreams
