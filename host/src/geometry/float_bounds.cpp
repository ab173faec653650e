#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cstreams {

namespace {

// Must match cl_kernels/ccd/bounds.h operation for operation.
float fdown(float x) { return x - (std::fabs(x) * 0x1p-23f + FLT_MIN); }
float fup(float x) { return x + (std::fabs(x) * 0x1p-23f + FLT_MIN); }

Kdop18f empty_dop()
{
  Kdop18f d;
  d.lo.fill(std::numeric_limits<float>::infinity());
  d.hi.fill(-std::numeric_limits<float>::infinity());
  return d;
}

void add(Kdop18f& d, float x, float y, float z)
{
  const float xl = fdown(x), xh = fup(x), yl = fdown(y), yh = fup(y), zl = fdown(z), zh = fup(z);
  const float l[9] = {xl, yl, zl, fdown(xl + yl), fdown(xl - yh), fdown(yl + zl), fdown(yl - zh), fdown(zl + xl),
                      fdown(zl - xh)};
  const float h[9] = {xh, yh, zh, fup(xh + yh), fup(xh - yl), fup(yh + zh), fup(yh - zl), fup(zh + xh), fup(zh - xl)};
  for (int k = 0; k < 9; ++k) {
    d.lo[std::size_t(k)] = std::fmin(d.lo[std::size_t(k)], l[k]);
    d.hi[std::size_t(k)] = std::fmax(d.hi[std::size_t(k)], h[k]);
  }
}

void inflate(Kdop18f& d, float separation)
{
  if (separation <= 0) return;
  const float diagonal = fup(separation * 1.41421366f);
  for (std::size_t k = 0; k < 9; ++k) {
    const float grow = k < 3 ? separation : diagonal;
    d.lo[k] = fdown(d.lo[k] - grow);
    d.hi[k] = fup(d.hi[k] + grow);
  }
}

// Coordinates a task rounds or checks: below this many in all, one thread does the
// whole (a task's start costs more than a block takes).
constexpr std::size_t coordinates_a_task = 3 * 8192;

// Whether coordinates [begin, end) of d are all finite floats: one pass without
// branches (NaN fails the comparison too), which the compiler vectorizes. With a branch
// a coordinate, 1.5M triangles' positions took 3 ms to check.
bool finite_floats(const double* d, std::size_t begin, std::size_t end)
{
  bool bad = false;
  for (std::size_t j = begin; j < end; ++j) bad |= !(std::fabs(d[j]) <= double(FLT_MAX));
  return !bad;
}

}  // namespace

void check_float_positions(PositionSpan x)
{
  // In blocks over several threads, as round_to_float() rounds: positions uploaded
  // ahead are checked as they are given, on the caller's path (two of n-body's
  // frames, 73K vertices each, took 0.13 ms longer to check in one thread than to round
  // in blocks).
  const double* d = x.coordinates();
  const std::size_t n = 3 * x.size();
  const bool finite =
      n < 2 * coordinates_a_task
          ? finite_floats(d, 0, n)
          : tbb::parallel_reduce(
                tbb::blocked_range<std::size_t>(0, n, coordinates_a_task), true,
                [&](const tbb::blocked_range<std::size_t>& r, bool all) { return all && finite_floats(d, r.begin(), r.end()); },
                [](bool a, bool b) { return a && b; });
  // Only bad input looks for the vertex to name.
  if (finite) return;
  const std::size_t i = first_not_float(x);
  if (i < x.size()) throw InputError("vertex " + std::to_string(i) + " has a coordinate that is not a finite float");
}

std::size_t first_not_float(PositionSpan x)
{
  const double* d = x.coordinates();
  std::size_t i = 0;
  while (i < x.size() && finite_floats(d, 3 * i, 3 * i + 3)) ++i;
  return i;
}

namespace {

// Rounds coordinates [begin, end) of d into out, testing as it goes, and copies them
// to `copy` where there is one.
FloatRounding round_range(const double* d, float* out, double* copy, std::size_t begin, std::size_t end)
{
  if (copy) std::copy(d + begin, d + end, copy + begin);
  std::size_t j = begin;
  FloatRounding r;
#if defined(__SSE2__)
  // GCC 12 leaves the loop below scalar (it vectorizes the rounding, not the tests that
  // follow it): a repeated n-body step (74K vertices, both ends) spent 0.8 ms of host
  // time a step rounding and checking positions in two passes on the H100's host.
  const __m128d magnitude = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffff)), most = _mm_set1_pd(FLT_MAX);
  __m128d inexact = _mm_setzero_pd(), bad = _mm_setzero_pd();
  for (; j + 4 <= end; j += 4) {
    const __m128d a = _mm_loadu_pd(d + j), b = _mm_loadu_pd(d + j + 2);
    const __m128 fa = _mm_cvtpd_ps(a), fb = _mm_cvtpd_ps(b);
    _mm_storeu_ps(out + j, _mm_movelh_ps(fa, fb));
    inexact = _mm_or_pd(inexact, _mm_or_pd(_mm_cmpneq_pd(_mm_cvtps_pd(fa), a), _mm_cmpneq_pd(_mm_cvtps_pd(fb), b)));
    // Not below or at FLT_MAX in magnitude: NaN too (an unordered comparison).
    bad = _mm_or_pd(bad, _mm_or_pd(_mm_cmpnle_pd(_mm_and_pd(a, magnitude), most),
                                   _mm_cmpnle_pd(_mm_and_pd(b, magnitude), most)));
  }
  r.exact = _mm_movemask_pd(inexact) == 0;
  r.finite = _mm_movemask_pd(bad) == 0;
#endif
  for (; j < end; ++j) {
    const float f = static_cast<float>(d[j]);
    out[j] = f;
    r.exact &= double(f) == d[j];
    r.finite &= std::fabs(d[j]) <= double(FLT_MAX);
  }
  return r;
}

}  // namespace

FloatRounding round_to_float(PositionSpan x, float* out, Vec3* copy)
{
  const double* d = x.coordinates();
  double* c = copy ? copy->data() : nullptr;
  const std::size_t n = 3 * x.size();
  if (n < 2 * coordinates_a_task) return round_range(d, out, c, 0, n);
  // Positions given just before a step are on its path: a cloth-ball frame (46.6K
  // vertices) took 100-160 us in one thread on the H100's host, 35-60 us in blocks.
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, coordinates_a_task), FloatRounding{},
      [&](const tbb::blocked_range<std::size_t>& r, FloatRounding sum) {
        const FloatRounding part = round_range(d, out, c, r.begin(), r.end());
        return FloatRounding{sum.finite && part.finite, sum.exact && part.exact};
      },
      [](FloatRounding a, FloatRounding b) { return FloatRounding{a.finite && b.finite, a.exact && b.exact}; });
}

FloatPositions rounded_positions(const std::vector<Vec3>& x)
{
  FloatPositions f;
  f.rounded.resize(3 * x.size());
  f.exact = round_to_float(x, f.rounded.data()).exact;
  return f;
}

std::vector<float> to_float_positions(const std::vector<Vec3>& x)
{
  check_float_positions(x);
  return rounded_positions(x).rounded;
}

namespace {

Kdop18f swept(const std::vector<float>& x0, const std::vector<float>& x1, const std::uint32_t* v, int count,
              float separation)
{
  Kdop18f d = empty_dop();
  for (int i = 0; i < count; ++i) {
    add(d, x0[3 * v[i]], x0[3 * v[i] + 1], x0[3 * v[i] + 2]);
    add(d, x1[3 * v[i]], x1[3 * v[i] + 1], x1[3 * v[i] + 2]);
  }
  inflate(d, separation);
  return d;
}

}  // namespace

bool Kdop18f::contains(const Kdop18& exact) const
{
  for (std::size_t k = 0; k < 9; ++k)
    if (double(lo[k]) > exact.lo[k] || double(hi[k]) < exact.hi[k]) return false;
  return true;
}

bool Kdop18f::overlaps(const Kdop18f& o) const
{
  for (std::size_t k = 0; k < 9; ++k)
    if (lo[k] > o.hi[k] || o.lo[k] > hi[k]) return false;
  return true;
}

FloatBounds float_bounds(const Topology& t, const Bvh& bvh, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1,
                         float separation)
{
  const auto f0 = to_float_positions(x0), f1 = to_float_positions(x1);
  FloatBounds b;
  for (const Face& f : t.faces) b.faces.push_back(swept(f0, f1, f.data(), 3, separation));
  for (const Edge& e : t.edges) b.edges.push_back(swept(f0, f1, e.data(), 2, separation));
  for (std::uint32_t v = 0; v < t.vertex_count; ++v) b.vertices.push_back(swept(f0, f1, &v, 1, separation));
  b.nodes.resize(bvh.nodes.size());
  for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
    const BvhNode& n = bvh.nodes[i];
    if (n.left < 0) {
      b.nodes[i] = b.faces[std::size_t(n.face)];
      continue;
    }
    const Kdop18f &l = b.nodes[std::size_t(n.left)], &r = b.nodes[std::size_t(n.left) + 1];
    for (std::size_t k = 0; k < 9; ++k) {
      b.nodes[i].lo[k] = std::fmin(l.lo[k], r.lo[k]);
      b.nodes[i].hi[k] = std::fmax(l.hi[k], r.hi[k]);
    }
  }
  return b;
}

}  // namespace cstreams
