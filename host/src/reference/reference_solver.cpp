#include <cstreams/reference/reference_solver.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cstreams {

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

// A closed interval; every operation rounds its bounds one step outward, which covers
// the half-ulp error of round-to-nearest.
struct Interval {
  double lo, hi;
};
// |x| * 2^-52 is at least one ulp of x (and exact: a power-of-two scaling), so after
// the subtraction rounds to nearest the result is still half an ulp below x; the
// 2^-1022 term covers results that underflowed to zero. Cheaper than nextafter.
inline double down(double x) { return x - (std::abs(x) * 0x1p-52 + 0x1p-1022); }
inline double up(double x) { return x + (std::abs(x) * 0x1p-52 + 0x1p-1022); }
inline Interval exact(double x) { return {x, x}; }
inline Interval operator+(Interval a, Interval b) { return {down(a.lo + b.lo), up(a.hi + b.hi)}; }
inline Interval operator-(Interval a, Interval b) { return {down(a.lo - b.hi), up(a.hi - b.lo)}; }
inline Interval operator*(Interval a, double s)
{
  const double x = a.lo * s, y = a.hi * s;
  return {down(std::min(x, y)), up(std::max(x, y))};
}

struct IVec3 {
  Interval c[3];
};
inline IVec3 operator+(const IVec3& a, const IVec3& b) { return {{a.c[0] + b.c[0], a.c[1] + b.c[1], a.c[2] + b.c[2]}}; }
inline IVec3 operator-(const IVec3& a, const IVec3& b) { return {{a.c[0] - b.c[0], a.c[1] - b.c[1], a.c[2] - b.c[2]}}; }
inline IVec3 operator*(const IVec3& a, double s) { return {{a.c[0] * s, a.c[1] * s, a.c[2] * s}}; }
inline IVec3 ivec(const Vec3& v) { return {{exact(v.x()), exact(v.y()), exact(v.z())}}; }

// One box of the (t, u, v) domain.
struct Box {
  double t0, t1, u0, u1, v0, v1;
  double width(int axis) const { return axis == 0 ? t1 - t0 : axis == 1 ? u1 - u0 : v1 - v0; }
};

// The contact function of a query, evaluated with intervals at exact parameters.
// Vertex-face: F = p - f0 - u (f1 - f0) - v (f2 - f0); edge-edge:
// F = a0 + u (a1 - a0) - b0 - v (b1 - b0); every point moves as x0 + t (x1 - x0).
class ContactFunction {
public:
  ContactFunction(const Query& q, bool vertex_face) : vertex_face_(vertex_face)
  {
    for (int i = 0; i < 4; ++i) {
      start_[i] = ivec(q[std::size_t(i)]);
      motion_[i] = ivec(q[std::size_t(i) + 4]) - start_[i];
    }
  }

  // Encloses F over the box in `image`, or says the box can be dropped because F
  // cannot come within `separation` of zero on it.
  // `split` receives the parameter (0 t, 1 u, 2 v) along which F varies most over the
  // box: halving that one shrinks the image fastest.
  bool bounds(const Box& b, double separation, IVec3& image, int& split) const
  {
    IVec3 corner[8];
    Vec3 mid[2][4];
    int c = 0;
    for (int it = 0; it < 2; ++it) {
      const double t = it ? b.t1 : b.t0;
      IVec3 x[4];
      for (int i = 0; i < 4; ++i) {
        x[i] = start_[i] + motion_[i] * t;
        mid[it][i] = Vec3(x[i].c[0].lo, x[i].c[1].lo, x[i].c[2].lo);
      }
      for (double u : {b.u0, b.u1})
        for (double v : {b.v0, b.v1})
          corner[c++] = vertex_face_ ? x[0] - x[1] - (x[2] - x[1]) * u - (x[3] - x[1]) * v
                                     : x[0] + (x[1] - x[0]) * u - x[2] - (x[3] - x[2]) * v;
    }
    IVec3 hull{{{inf, -inf}, {inf, -inf}, {inf, -inf}}};
    Vec3 centre = Vec3::Zero();
    for (const IVec3& f : corner)
      for (int k = 0; k < 3; ++k) {
        hull.c[k].lo = std::min(hull.c[k].lo, f.c[k].lo);
        hull.c[k].hi = std::max(hull.c[k].hi, f.c[k].hi);
        centre[k] += 0.0625 * (f.c[k].lo + f.c[k].hi);
      }
    image = hull;
    // Corner c has t = c>>2, u = (c>>1)&1, v = c&1.
    double spread[3] = {0, 0, 0};
    for (int c0 = 0; c0 < 8; ++c0)
      for (int axis = 0; axis < 3; ++axis) {
        const int bit = 4 >> axis;
        if (c0 & bit) continue;
        for (int k = 0; k < 3; ++k)
          spread[axis] = std::max(spread[axis], std::abs(corner[c0 | bit].c[k].lo - corner[c0].c[k].lo));
      }
    split = int(std::max_element(spread, spread + 3) - spread);
    for (int k = 0; k < 3; ++k)
      if (hull.c[k].lo > separation || hull.c[k].hi < -separation) return false;

    // Any direction d separates rigorously when every corner's dot product with d is
    // bounded away from zero, so directions may be guessed: the value of F at the
    // box's centre (pointing away from a near miss) and the normal of the face or of
    // the two edges at mid-step. They drop near misses while the box is still coarse.
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = 0.5 * (mid[0][i] + mid[1][i]);
    const Vec3 normal = vertex_face_ ? (p[2] - p[1]).cross(p[3] - p[1]) : (p[1] - p[0]).cross(p[3] - p[2]);
    for (const Vec3& d : {centre, normal}) {
      if (!d.allFinite() || d.isZero(0)) continue;
      double lo = inf, hi = -inf;
      for (const IVec3& f : corner) {
        const Interval dot = f.c[0] * d.x() + f.c[1] * d.y() + f.c[2] * d.z();
        lo = std::min(lo, dot.lo);
        hi = std::max(hi, dot.hi);
      }
      const double reach = up(separation * up(d.lpNorm<1>()));
      if (lo > reach || hi < -reach) return false;
    }
    return true;
  }

private:
  bool vertex_face_;
  IVec3 start_[4], motion_[4];
};

double query_scale(const Query& q)
{
  double s = 0;
  for (const auto& p : q) s = std::max(s, p.cwiseAbs().maxCoeff());
  return std::max(s, std::numeric_limits<double>::min());
}

CcdResult solve(const Query& q, bool vertex_face, const ReferenceSolverOptions& options)
{
  const ContactFunction f(q, vertex_face);
  const double tolerance = options.tolerance * query_scale(q);
  const double resolution = options.time_resolution;
  // The per-axis box test with the separation as half-width contains the ball of that
  // radius, so it never drops a box that comes within min_separation.
  const double separation = options.min_separation;
  // Depth first, earlier half first; boxes starting after the earliest contact found
  // (or less than `resolution` before it) are not refined. A contact reported after
  // such a skip is moved `resolution` earlier, so it stays a lower bound.
  std::vector<Box> stack{{0, 1, 0, 1, 0, 1}};
  double best = 2;
  bool skipped = false;
  std::size_t examined = 0;
  IVec3 image;
  auto result = [&](bool limit) {
    if (best > 1) return CcdResult{false, 1, false};
    return CcdResult{true, skipped ? std::max(0.0, down(best - resolution)) : best, limit};
  };
  while (!stack.empty()) {
    Box b = stack.back();
    stack.pop_back();
    if (b.t0 >= best) continue;
    if (b.t0 >= best - resolution) {
      skipped = true;
      continue;
    }
    // Only the part before best - resolution can still matter; bounds hold for any
    // box, so the rest is cut off instead of refined (along a line of contacts that
    // would otherwise take a box per point of the line).
    if (b.t1 > best - resolution) {
      b.t1 = best - resolution;
      skipped = true;
    }
    if (vertex_face && b.u0 + b.v0 > 1) continue;  // outside the triangle u + v <= 1
    int axis = 0;
    if (!f.bounds(b, separation, image, axis)) continue;
    double image_width = 0;
    for (int k = 0; k < 3; ++k) image_width = std::max(image_width, image.c[k].hi - image.c[k].lo);
    if (image_width <= tolerance) {
      best = b.t0;
      continue;
    }
    if (++examined >= options.max_boxes) {
      for (const Box& rest : stack) best = std::min(best, rest.t0);
      best = std::min(best, b.t0);
      return result(true);
    }
    Box lo = b, hi = b;
    if (axis == 0) {
      const double m = 0.5 * (b.t0 + b.t1);
      lo.t1 = hi.t0 = m;
    } else if (axis == 1) {
      const double m = 0.5 * (b.u0 + b.u1);
      lo.u1 = hi.u0 = m;
    } else {
      const double m = 0.5 * (b.v0 + b.v1);
      lo.v1 = hi.v0 = m;
    }
    // A box too small to halve in doubles cannot be refined further: it is a contact.
    if (lo.width(axis) == 0 || hi.width(axis) == 0) {
      best = b.t0;
      continue;
    }
    stack.push_back(hi);
    stack.push_back(lo);
  }
  return result(false);
}

}  // namespace

CcdResult vertex_face_reference(const Query& q, const ReferenceSolverOptions& options)
{
  return solve(q, true, options);
}

CcdResult edge_edge_reference(const Query& q, const ReferenceSolverOptions& options)
{
  return solve(q, false, options);
}

}  // namespace cstreams
