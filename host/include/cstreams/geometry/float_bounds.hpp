#pragma once
#include <cstreams/geometry/bvh.hpp>
#include <cstreams/geometry/topology.hpp>

#include <array>
#include <vector>

namespace cstreams {

// An 18-DOP in single precision, as the device keeps it (cl_kernels/ccd/bounds.h):
// conservative for the exact double positions it was computed from.
struct Kdop18f {
  std::array<float, 9> lo;
  std::array<float, 9> hi;
  friend bool operator==(const Kdop18f& a, const Kdop18f& b) { return a.lo == b.lo && a.hi == b.hi; }
  bool contains(const Kdop18& exact) const;
  bool overlaps(const Kdop18f& other) const;
};

// Swept single-precision bounds of one mesh over a step, and its BVH's node boxes.
struct FloatBounds {
  std::vector<Kdop18f> faces, edges, vertices, nodes;
};

// The host's twin of the device computation (cl_kernels/ccd/bounds.cl): the same float
// operations in the same order, so that it equals the device's boxes bit for bit.
FloatBounds float_bounds(const Topology& topology, const Bvh& bvh, const std::vector<Vec3>& x0,
                         const std::vector<Vec3>& x1, float separation);

// Positions rounded to float (3 a vertex), and whether that changed none of them:
// single-precision kernels then take the floats as the exact input (far tighter bounds).
struct FloatPositions {
  std::vector<float> rounded;
  bool exact = false;
};

// Rounds positions to float (an InputError for a non-finite or out-of-range one).
std::vector<float> to_float_positions(const std::vector<Vec3>& x);
// The halves of that: the check, and the rounding to nearest, into a new array or into
// `out` (3 floats a vertex).
void check_float_positions(PositionSpan x);
// The first position with a coordinate that is not a finite float (x.size(): none), for
// a message that names it once a check has failed.
std::size_t first_not_float(PositionSpan x);
FloatPositions rounded_positions(const std::vector<Vec3>& x);
// Rounding into `out` checks as it goes, in the same pass: whether every coordinate is
// a finite float (else `out` is of no use, and check_float_positions() names the first
// that is not) and whether the floats are the input itself (FloatPositions::exact).
// Where `copy` is given, x is copied there in the same pass. Large inputs are rounded
// on several threads.
struct FloatRounding {
  bool finite = true, exact = true;
};
FloatRounding round_to_float(PositionSpan x, float* out, Vec3* copy = nullptr);

}  // namespace cstreams
