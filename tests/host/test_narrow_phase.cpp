// The device solvers against exact ground truth, on the device tests select
// (CSTREAMS_DEVICE; pocl in CI).
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"

#include <cstreams/datasets/datasets.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>

using namespace cstreams;

namespace {

// The precisions the solvers run in on the test device.
std::vector<Precision> precisions()
{
  std::vector<Precision> p{Precision::single};
  if (cstreams::test::device().device().fp64) p.push_back(Precision::double_);
  return p;
}

struct Tally {
  std::size_t queries = 0, positives = 0, false_negatives = 0, false_positives = 0, filtered = 0, late = 0;
};

Tally run(DeviceSolver& solver, const Dataset& d)
{
  const auto results = solver.solve(d.kind, d.queries);
  Tally t;
  for (std::size_t i = 0; i < results.size(); ++i) {
    ++t.queries;
    t.positives += d.collides[i];
    t.filtered += results[i].status == QueryStatus::filtered;
    if (d.collides[i] && !results[i].collides()) {
      ++t.false_negatives;
      UNSCOPED_INFO(d.name << " " << (d.kind == ContactKind::vertex_face ? "vf" : "ee") << " query " << i << " missed");
    }
    t.false_positives += !d.collides[i] && results[i].collides();
    if (d.collides[i] && results[i].collides() && !std::isnan(d.exact_toi[i]) &&
        (long double)results[i].toi > d.exact_toi[i])
      ++t.late;
  }
  return t;
}

SolverOptions conservative(Precision p)
{
  SolverOptions o;
  o.precision = p;
  return o;
}

// Points of a query: x[0..3] at t = 0, x[4..7] at t = 1.
Query query(std::initializer_list<Vec3> at0, std::initializer_list<Vec3> at1)
{
  Query q;
  std::size_t i = 0;
  for (const auto& p : at0) q[i++] = p;
  for (const auto& p : at1) q[i++] = p;
  return q;
}

const Vec3 A(0, 0, 0), B(1, 0, 0), C(0, 1, 0);  // a face in the z = 0 plane

Dataset constructed(ContactKind kind)
{
  Dataset d;
  d.name = "constructed";
  d.kind = kind;
  return d;
}

void add(Dataset& d, const Query& q, bool collides)
{
  d.queries.push_back(q);
  d.collides.push_back(collides);
  d.exact_toi.push_back(std::nanl(""));
}

// Degenerate configurations with known answers (true: the features touch in [0, 1]).
Dataset hard_vertex_face()
{
  Dataset d = constructed(ContactKind::vertex_face);
  const Vec3 in(0.25, 0.25, 0);
  add(d, query({in + Vec3(0, 0, 1), A, B, C}, {in - Vec3(0, 0, 1), A, B, C}), true);         // straight through
  add(d, query({in, A, B, C}, {in + Vec3(0, 0, 1), A, B, C}), true);                        // touching at t = 0
  add(d, query({in + Vec3(0, 0, 1), A, B, C}, {in, A, B, C}), true);                        // touching at t = 1
  add(d, query({in, A, B, C}, {in, A, B, C}), true);                                        // no motion, touching
  add(d, query({in + Vec3(0, 0, 0.5), A, B, C}, {in + Vec3(0, 0, 0.5), A, B, C}), false);   // no motion, apart
  add(d, query({Vec3(-1, 0.25, 0), A, B, C}, {Vec3(2, 0.25, 0), A, B, C}), true);           // slides across, in plane
  add(d, query({Vec3(-1, 2, 0), A, B, C}, {Vec3(2, 2, 0), A, B, C}), false);                // slides beside, in plane
  add(d, query({Vec3(-1, 0, 0), A, B, C}, {Vec3(2, 0, 0), A, B, C}), true);                 // slides along an edge
  add(d, query({Vec3(0.5, 0.5, 0), A, B, C}, {Vec3(0.5, 0.5, 0), A, B, C}), true);          // resting on an edge
  add(d, query({in + Vec3(0, 0, 1), A, B, C}, {in + Vec3(0, 0, 1), A + Vec3(0, 0, 2), B + Vec3(0, 0, 2), C + Vec3(0, 0, 2)}), true);
  // Tangential: the face tilts through the vertex and back only at one instant is not
  // linear; instead the vertex grazes the face's corner at t = 0.5 (a double root).
  add(d, query({Vec3(-0.5, -0.5, 1), A, B, C}, {Vec3(0.5, 0.5, -1), A, B, C}), true);
  add(d, query({Vec3(-0.5, -0.5, 1), A, B, C}, {Vec3(0.5 - 1e-3, 0.5 + 1e-3, -1), A, B, C}), false);  // just outside
  add(d, query({Vec3(-0.5, -0.5, 1), A, B, C}, {Vec3(0.5 + 2e-3, 0.5 + 2e-3, -1), A, B, C}), true);   // just inside
  const Vec3 far(3, 3, 0);
  add(d, query({far + Vec3(0, 0, 1), A, B, C}, {far - Vec3(0, 0, 1), A, B, C}), false);    // passes the plane outside
  // Zero-area faces: collinear, and all three corners at one point.
  add(d, query({Vec3(0.5, 0, 1), A, B, 2 * B}, {Vec3(0.5, 0, -1), A, B, 2 * B}), true);
  add(d, query({Vec3(0.5, 0.2, 1), A, B, 2 * B}, {Vec3(0.5, 0.2, -1), A, B, 2 * B}), false);
  add(d, query({Vec3(0, 0, 1), A, A, A}, {Vec3(0, 0, -1), A, A, A}), true);
  return d;
}

Dataset hard_edge_edge()
{
  Dataset d = constructed(ContactKind::edge_edge);
  const Vec3 up(0, 0, 1);
  add(d, query({A, B, Vec3(0.5, -1, 1), Vec3(0.5, 1, 1)}, {A, B, Vec3(0.5, -1, -1), Vec3(0.5, 1, -1)}), true);  // crossing
  add(d, query({A, B, A + up, B + up}, {A, B, A - up, B - up}), true);                              // parallel, overlapping
  add(d, query({A, B, A + up + 2 * B, B + up + 2 * B}, {A, B, A - up + 2 * B, B - up + 2 * B}), false);  // parallel, apart
  add(d, query({A, B, 0.5 * B, 1.5 * B}, {A, B, 0.5 * B, 1.5 * B}), true);                          // collinear overlap
  add(d, query({A, B, 2 * B, 3 * B}, {A, B, 2 * B, 3 * B}), false);                                 // collinear apart
  add(d, query({A, B, 2 * B, 3 * B}, {A, B, 0.5 * B, 1.5 * B}), true);                              // collinear sliding in
  add(d, query({A, B, B, B + C}, {A, B, B + up, B + C + up}), true);                                // touching at t = 0
  add(d, query({A, B, Vec3(0.5, -1, 1), Vec3(0.5, 1, 1)}, {A, B, Vec3(0.5, -1, 0), Vec3(0.5, 1, 0)}), true);   // at t = 1
  add(d, query({A, B, Vec3(2, -1, 1), Vec3(2, 1, 1)}, {A, B, Vec3(2, -1, -1), Vec3(2, 1, -1)}), false);  // misses the end
  add(d, query({A, B, Vec3(1, -1, 1), Vec3(1, 1, 1)}, {A, B, Vec3(1, -1, -1), Vec3(1, 1, -1)}), true);   // hits the end point
  add(d, query({A, B, Vec3(0.5, 0, 1), Vec3(0.5, 0, 1)}, {A, B, Vec3(0.5, 0, -1), Vec3(0.5, 0, -1)}), true);  // zero-length edge
  add(d, query({A, A, Vec3(0, -1, 1), Vec3(0, 1, 1)}, {A, A, Vec3(0, -1, -1), Vec3(0, 1, -1)}), true);    // both degenerate-ish
  add(d, query({A, B, C, C + up}, {A, B, C, C + up}), false);                                       // no motion, apart
  return d;
}

// x + shift computed exactly, checked with the error term of TwoSum.
bool exact_sum(double x, double shift, double& sum)
{
  sum = x + shift;
  const double bb = sum - x;
  return (x - (sum - bb)) + (shift - bb) == 0;
}

// The queries scaled by powers of two (exact) and translated where the sum is exact.
Dataset transformed(const Dataset& d, double scale, double shift, std::size_t& kept)
{
  Dataset out;
  out.name = d.name;
  out.kind = d.kind;
  kept = 0;
  for (std::size_t i = 0; i < d.queries.size(); ++i) {
    Query q = d.queries[i];
    bool exact = true;
    for (auto& p : q)
      for (int k = 0; k < 3; ++k) {
        const double scaled = p[k] * scale;
        exact &= std::isfinite(scaled) && scaled / scale == p[k];
        exact &= exact_sum(scaled, shift, p[k]);
      }
    if (!exact) continue;
    ++kept;
    out.queries.push_back(q);
    out.collides.push_back(d.collides[i]);
    out.exact_toi.push_back(d.exact_toi[i]);
  }
  return out;
}

std::vector<Dataset> handmade() { return discover_datasets(cstreams::test::benchmark_path("sample-queries")); }

}  // namespace

TEST_CASE("constructed degenerate cases: the conservative solver misses none", "[narrow][quick]")
{
  for (Precision p : precisions()) {
    DeviceSolver solver(cstreams::test::device(), conservative(p));
    for (const Dataset& d : {hard_vertex_face(), hard_edge_edge()}) {
      INFO(to_string(p) << " " << (d.kind == ContactKind::vertex_face ? "vertex-face" : "edge-edge"));
      const auto results = solver.solve(d.kind, d.queries);
      for (std::size_t i = 0; i < d.queries.size(); ++i) {
        INFO("query " << i);
        if (d.collides[i]) CHECK(results[i].collides());
        // Clearly separated cases (all at distances far above the tolerance) stay separate.
        else CHECK_FALSE(results[i].collides());
        // The oracle agrees with the construction.
        const CcdResult oracle = d.kind == ContactKind::vertex_face ? vertex_face_reference(d.queries[i])
                                                                    : edge_edge_reference(d.queries[i]);
        CHECK(oracle.collides == bool(d.collides[i]));
      }
    }
  }
}

namespace {

// Cuts n random boxes, from sides of 1 down to sides below what `levels` halvings of
// this precision can still cut, `levels` halvings at once (tests/kernels/cut_pieces.cl),
// and checks that every box cut is tiled by its pieces: along each parameter the
// pieces' bounds partition the box's side, each piece spans one part of each partition,
// and no two pieces span the same three parts. A contact can hide in no gap.
template <class Real> void check_cut_pieces(runtime::Context& device, const runtime::Kernel& kernel, int levels)
{
  const std::size_t n = 2000, pieces = std::size_t(1) << levels;
  std::mt19937 rng{std::uint32_t(levels)};
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Real> boxes(6 * n), spreads(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) {
      const double side = std::pow(10.0, -(std::numeric_limits<Real>::digits10 + 2) * unit(rng) * unit(rng));
      const Real lo = Real((1 - side) * unit(rng));
      boxes[6 * i + 2 * j] = lo;
      boxes[6 * i + 2 * j + 1] = std::max(std::nextafter(lo, Real(2)), std::min(Real(1), Real(lo + side)));
      spreads[3 * i + j] = Real(unit(rng));
    }
  runtime::Buffer in(device, boxes.size() * sizeof(Real), "boxes"), sp(device, spreads.size() * sizeof(Real), "spreads"),
      plans(device, n * 4, "plans"), out(device, n * pieces * 6 * sizeof(Real), "pieces");
  device.write(in, boxes.data(), boxes.size() * sizeof(Real));
  device.write(sp, spreads.data(), spreads.size() * sizeof(Real));
  kernel.set_args(in, sp, cl_uint(n), cl_int(levels), plans, out);
  device.launch(kernel, n, 0);
  std::vector<cl_uint> plan(n);
  std::vector<Real> piece(n * pieces * 6);
  device.read(plans, plan.data(), n * 4);
  device.read(out, piece.data(), piece.size() * sizeof(Real));
  std::size_t cut = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Real* b = &boxes[6 * i];
    const Real shortest = std::min({b[1] - b[0], b[3] - b[2], b[5] - b[4]});
    INFO("box " << i << ", shortest side " << shortest << ", " << levels << " halvings");
    if (shortest > Real(1e-3)) REQUIRE(plan[i] != 0);
    if (plan[i] == 0) continue;
    ++cut;
    const Real* p = &piece[6 * i * pieces];
    std::set<Real> bounds[3];
    for (std::size_t k = 0; k < pieces; ++k)
      for (int j = 0; j < 3; ++j) {
        REQUIRE(p[6 * k + 2 * j] < p[6 * k + 2 * j + 1]);
        bounds[j].insert(p[6 * k + 2 * j]);
        bounds[j].insert(p[6 * k + 2 * j + 1]);
      }
    std::size_t cells = 1;
    for (int j = 0; j < 3; ++j) {
      REQUIRE(*bounds[j].begin() == b[2 * j]);
      REQUIRE(*bounds[j].rbegin() == b[2 * j + 1]);
      cells *= bounds[j].size() - 1;
    }
    REQUIRE(cells == pieces);
    std::set<std::tuple<long, long, long>> spanned;
    for (std::size_t k = 0; k < pieces; ++k) {
      long part[3];
      for (int j = 0; j < 3; ++j) {
        const auto lo = bounds[j].find(p[6 * k + 2 * j]), hi = bounds[j].find(p[6 * k + 2 * j + 1]);
        REQUIRE(std::next(lo) == hi);
        part[j] = long(std::distance(bounds[j].begin(), lo));
      }
      spanned.emplace(part[0], part[1], part[2]);
    }
    REQUIRE(spanned.size() == pieces);
    // The first piece starts the box, the way the refinement's earliest start needs.
    CHECK(p[0] == b[0]);
    // The first halving is along the parameter F varies most with, as a single one is.
    const Real* s = &spreads[3 * i];
    const int most = int(std::max_element(s, s + 3) - s);
    CHECK(bounds[most].size() > 2);
  }
  CHECK(cut > n / 2);
  CHECK(cut < n);
}

}  // namespace

TEST_CASE("a box the refinement cuts into pieces at once is tiled by them", "[narrow][quick]")
{
  auto& device = cstreams::test::device();
  device.programs().add_sources(ccd_kernel_sources());
  for (Precision p : precisions())
    for (int levels : {1, 2, 3}) {
      INFO(to_string(p));
      const bool in_double = p == Precision::double_;
      const runtime::Kernel kernel = device.programs().kernel(
          "kernels/cut_pieces.cl", "test_cut_pieces", in_double ? "-DCS_REAL_DOUBLE=1" : "-DCS_REAL_DOUBLE=0");
      if (in_double) check_cut_pieces<double>(device, kernel, levels);
      else check_cut_pieces<float>(device, kernel, levels);
    }
}

namespace {

// Queries whose features meet at a random time in (0, 1): a vertex through a point of
// its moving face, or two edges through one point, the other ends moving at random.
std::vector<Query> meeting_queries(ContactKind kind, std::size_t n, std::uint32_t seed)
{
  std::mt19937 rng{seed};
  std::uniform_real_distribution<double> unit(0, 1), wide(-1, 1);
  const auto random_point = [&] { return Vec3(wide(rng), wide(rng), wide(rng)); };
  std::vector<Query> out;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = unit(rng);
    Query q;
    // Points 1..3 (the face, or point 1 and the second edge's ends 2, 3) move at random.
    for (int k = 1; k < 4; ++k) {
      q[k] = random_point();
      q[k + 4] = q[k] + 0.5 * random_point();
    }
    const auto at = [&](int k) { return q[k] + t * (q[k + 4] - q[k]); };
    const Vec3 velocity = 0.5 * random_point();
    if (kind == ContactKind::vertex_face) {
      double u = unit(rng), v = unit(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      const Vec3 meet = at(1) + u * (at(2) - at(1)) + v * (at(3) - at(1));
      q[0] = meet - t * velocity;
      q[4] = q[0] + velocity;
    } else {
      // Edge 0-1 passes at time t through the point of edge 2-3 at parameter u.
      const double u = unit(rng), s = unit(rng);
      const Vec3 meet = at(2) + u * (at(3) - at(2)), other = at(1);
      // Point 0 at time t lies on the line from point 1 through the meeting point.
      const Vec3 p0 = other + (meet - other) / std::max(s, 0.05);
      q[0] = p0 - t * velocity;
      q[4] = q[0] + velocity;
    }
    out.push_back(q);
  }
  return out;
}

// The cubic test and cs_apart_until on the same queries (tests/kernels/apart_until.cl):
// per query, the cubic's time (2: none) and the bound.
template <class Real>
std::pair<std::vector<Real>, std::vector<Real>> cubic_and_bound(runtime::Context& device, const runtime::Kernel& kernel,
                                                              ContactKind kind, const std::vector<Query>& queries,
                                                              double tolerance)
{
  const std::size_t n = queries.size();
  std::vector<Real> in(24 * n), times(n), until(n);
  for (std::size_t i = 0; i < n; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 3; ++k) in[24 * i + 3 * j + k] = Real(queries[i][j][k]);
  runtime::Buffer queries_buffer(device, in.size() * sizeof(Real), "queries"),
      times_buffer(device, n * sizeof(Real), "times"), until_buffer(device, n * sizeof(Real), "until");
  device.write(queries_buffer, in.data(), in.size() * sizeof(Real));
  kernel.set_args(queries_buffer, cl_uint(n), cl_uint(kind == ContactKind::vertex_face), Real(tolerance), times_buffer,
                  until_buffer);
  device.launch(kernel, n, 0);
  device.read(times_buffer, times.data(), n * sizeof(Real));
  device.read(until_buffer, until.data(), n * sizeof(Real));
  return {times, until};
}

template <class Real> void check_apart_until(runtime::Context& device, const runtime::Kernel& kernel)
{
  std::vector<Dataset> sets = handmade();
  const std::string funnel = cstreams::test::benchmark_path("scalable-ccd-sample/cloth-funnel");
  for (ContactKind kind : {ContactKind::vertex_face, ContactKind::edge_edge}) {
    sets.push_back(real_step_dataset(funnel, kind));
    Dataset meeting;
    meeting.name = "meeting";
    meeting.kind = kind;
    meeting.queries = meeting_queries(kind, 4000, kind == ContactKind::vertex_face ? 5 : 6);
    sets.push_back(meeting);
  }
  const double tolerance = SolverOptions().tolerance;
  std::size_t contacts = 0, bounded_contacts = 0, apart_through = 0;
  for (const Dataset& d : sets) {
    const auto [times, until] = cubic_and_bound<Real>(device, kernel, d.kind, d.queries, tolerance);
    for (std::size_t i = 0; i < d.queries.size(); ++i) {
      INFO(d.name << (d.kind == ContactKind::vertex_face ? " vf" : " ee") << " query " << i);
      apart_through += until[i] > 1;
      if (times[i] > 1) continue;
      ++contacts;
      bounded_contacts += until[i] > 0;
      REQUIRE(until[i] <= times[i]);
    }
  }
  INFO(contacts << " contacts, " << bounded_contacts << " of them after a time the bound gives; " << apart_through
                << " queries apart through the step");
  CHECK(bounded_contacts > contacts / 8);
  CHECK(apart_through > 0);
}

}  // namespace

// The cubic test skips a pair whose features' boxes stay apart through the step, and,
// in steps that report earliest times alone, until its objects already have a contact
// no later (cs_apart_until in ccd/cubic.h): the bound must never pass a contact the
// cubic test finds, on the hard cases, a real step and queries whose features meet at
// any time.
TEST_CASE("the cubic test finds no contact before the time its features' boxes stay apart until", "[narrow][quick]")
{
  auto& device = cstreams::test::device();
  device.programs().add_sources(ccd_kernel_sources());
  for (Precision p : precisions()) {
    INFO(to_string(p));
    SolverOptions options;
    options.solver = Solver::cubic;
    options.precision = p;
    const runtime::Kernel kernel =
        device.programs().kernel("kernels/apart_until.cl", "test_apart_until", solver_build_options(options));
    if (p == Precision::double_) check_apart_until<double>(device, kernel);
    else check_apart_until<float>(device, kernel);
  }
}

TEST_CASE("without 64-bit atomics the conservative solver in double precision rounds its times down to float",
          "[narrow][quick]")
{
  runtime::Context hd(runtime::apply_profile(runtime::select_device(runtime::filter_from_environment()), "hd5870"));
  REQUIRE(!hd.device().int64_atomics);
  SolverOptions options;
  options.precision = Precision::double_;
  if (!hd.device().fp64) {
    CHECK_THROWS_WITH(DeviceSolver(hd, options), Catch::Contains("neither cl_khr_fp64 nor cl_amd_fp64"));
    return;
  }
  runtime::Context plain(runtime::filter_from_environment());
  if (!plain.device().int64_atomics) return;  // nothing to compare with
  DeviceSolver with(plain, options), without(hd, options);
  for (const auto& d : discover_datasets(cstreams::test::benchmark_path("sample-queries/unit-tests"))) {
    const auto a = with.solve(d.kind, d.queries), b = without.solve(d.kind, d.queries);
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < d.queries.size(); ++i) {
      INFO(d.name << " query " << i);
      REQUIRE(a[i].collides() == b[i].collides());
      if (!a[i].collides()) continue;
      ++colliding;
      // Never later, and as early only as rounding down to float makes it.
      CHECK(b[i].toi <= a[i].toi);
      CHECK(a[i].toi - b[i].toi <= 1e-6);
    }
    CHECK(colliding > 0);
  }
}

TEST_CASE("the time of impact is a lower bound of the first contact", "[narrow][quick]")
{
  // The vertex reaches the plane z = 0 at t = 0.3 exactly (0.3 in [0, 1] is not
  // representable: both solvers must answer at or below it).
  const Vec3 in(0.25, 0.25, 0);
  const Query q = query({in + Vec3(0, 0, 0.3), A, B, C}, {in - Vec3(0, 0, 0.7), A, B, C});
  for (Precision p : precisions()) {
    auto o = conservative(p);
    DeviceSolver solver(cstreams::test::device(), o);
    const auto r = solver.solve(ContactKind::vertex_face, {q});
    REQUIRE(r[0].collides());
    CHECK(r[0].toi <= 0.3);
    CHECK(r[0].toi > 0.29);
  }
}

TEST_CASE("a vertex crossing a face: the time of impact is within the tolerance below the exact one",
          "[narrow][quick]")
{
  // The vertex falls through the face's plane at t = k / 64 exactly, at a point inside
  // the face, while both drift sideways; every coordinate is exact in float. The
  // answer may be early by the tolerance twice at most: once for the box it is found
  // in, once for the boxes just before it that are not refined.
  Dataset d = constructed(ContactKind::vertex_face);
  std::vector<double> exact;
  for (int k = 3; k < 62; k += 2) {
    const Vec3 in((k % 7 + 1) / 32.0, (k % 5 + 1) / 32.0, 0), drift(k / 128.0, -k / 256.0, 0);
    const Vec3 top = in + Vec3(0, 0, k / 32.0), bottom = in + Vec3(0, 0, k / 32.0 - 2);  // z = k / 32 - 2 t
    add(d, query({top, A, B, C}, {bottom + drift, A + drift, B + drift, C + drift}), true);
    exact.push_back(k / 64.0);
  }
  for (Precision p : precisions()) {
    const SolverOptions o = conservative(p);
    DeviceSolver solver(cstreams::test::device(), o);
    const auto r = solver.solve(d.kind, d.queries);
    for (std::size_t i = 0; i < r.size(); ++i) {
      INFO(to_string(p) << ", exact time " << exact[i]);
      REQUIRE(r[i].collides());
      CHECK(r[i].toi <= exact[i]);
      CHECK(r[i].toi >= exact[i] - 2 * o.tolerance);
    }
  }
}

TEST_CASE("queries with NaN, infinite or (in single precision) too large coordinates are rejected", "[narrow][quick]")
{
  const Vec3 in(0.25, 0.25, 0);
  Query q = query({in + Vec3(0, 0, 1), A, B, C}, {in - Vec3(0, 0, 1), A, B, C});
  DeviceSolver solver(cstreams::test::device(), conservative(Precision::single));
  q[5].y() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(solver.solve(ContactKind::vertex_face, {q, q}), Catch::Contains("query 0 has a NaN"));
  q[5].y() = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(solver.solve(ContactKind::vertex_face, {q}), InputError);
  q[5].y() = 1e300;
  CHECK_THROWS_WITH(solver.solve(ContactKind::vertex_face, {q}), Catch::Contains("too large for the single-precision"));
}

// Features that coincide for the whole step (a duplicated vertex against a face whose
// first vertex it duplicates, an edge against its duplicate) touch at 0, which the
// refinement finds at the first corner of its first box.
TEST_CASE("features that coincide touch at time 0", "[narrow][quick]")
{
  const Vec3 move(0.25, -0.125, 0.5);
  const Query on_vertex = query({A, A, B, C}, {A + move, A + move, B + move, C + move});
  const Query on_edge = query({A, B, A, B}, {A + move, B + move, A + move, B + move});
  for (Precision p : precisions()) {
    INFO(to_string(p));
    DeviceSolver solver(cstreams::test::device(), conservative(p));
    const auto vf = solver.solve(ContactKind::vertex_face, {on_vertex});
    const auto ee = solver.solve(ContactKind::edge_edge, {on_edge});
    REQUIRE(vf[0].collides());
    REQUIRE(ee[0].collides());
    CHECK(vf[0].toi == 0);
    CHECK(ee[0].toi == 0);
  }
}

// Single precision takes queries whose coordinates are all floats as the exact input
// (the solver checks that rounding changed none): a vertex one ulp above a face far from
// the origin passes it. Moved by 2^-40, under half an ulp, the same coordinates round to
// the same floats but are bounded within half an ulp, which reaches the face: the
// conservative answer is then a contact.
TEST_CASE("in single precision, queries given in floats are solved as given", "[narrow][quick]")
{
  const Vec3 far(1024, 1024, 1024), in(0.25, 0.25, 0), above(0, 0, 0x1p-13);  // an ulp at 1024
  const Query floats = query({far + in + above, far + A, far + B, far + C},
                             {far + in + above + Vec3(0.125, 0, 0), far + A, far + B, far + C});
  Query rounded = floats;
  rounded[0].z() += 0x1p-40;
  rounded[4].z() += 0x1p-40;
  DeviceSolver solver(cstreams::test::device(), conservative(Precision::single));
  CHECK_FALSE(solver.solve(ContactKind::vertex_face, {floats})[0].collides());
  CHECK(solver.solve(ContactKind::vertex_face, {rounded})[0].collides());
}

TEST_CASE("a minimum separation makes near misses collide", "[narrow][quick]")
{
  const Vec3 in(0.25, 0.25, 0);
  const Query q = query({in + Vec3(0, 0, 0.01), A, B, C}, {in + Vec3(0.1, 0, 0.01), A, B, C});  // 0.01 above
  for (Precision p : precisions()) {
    auto o = conservative(p);
    DeviceSolver plain(cstreams::test::device(), o);
    CHECK_FALSE(plain.solve(ContactKind::vertex_face, {q})[0].collides());
    o.min_separation = 0.02;
    DeviceSolver separated(cstreams::test::device(), o);
    CHECK(separated.solve(ContactKind::vertex_face, {q})[0].collides());
  }
  // A separation above 1 (scene units) is honoured too: the vertex passes 1.5 above.
  const Query far = query({in + Vec3(0, 0, 1.5), A, B, C}, {in + Vec3(0.1, 0, 1.5), A, B, C});
  for (Precision p : precisions()) {
    auto o = conservative(p);
    o.min_separation = 1.5;
    DeviceSolver separated(cstreams::test::device(), o);
    CHECK(separated.solve(ContactKind::vertex_face, {far})[0].collides());
  }
}

TEST_CASE("the unit-test queries: conservative misses none, cubic is measured", "[narrow][quick]")
{
  const auto sets = discover_datasets(cstreams::test::benchmark_path("sample-queries/unit-tests"));
  for (Precision p : precisions())
    for (const auto& d : sets) {
      DeviceSolver solver(cstreams::test::device(), conservative(p));
      const Tally t = run(solver, d);
      CHECK(t.false_negatives == 0);
      CHECK(t.positives > 0);
    }
  SolverOptions cubic;
  cubic.solver = Solver::cubic;
  DeviceSolver solver(cstreams::test::device(), cubic);
  std::size_t found = 0, positives = 0;
  for (const auto& d : sets) {
    const Tally t = run(solver, d);
    found += t.positives - t.false_negatives;
    positives += t.positives;
  }
  // The cubic solver is allowed misses in degenerate cases, but not to be blind.
  CHECK(found > positives / 2);
}

// Without a minimum separation, refinement starts from the times at which a query's
// points can be coplanar (coplanarity.h). In double, the vertex-face times of
// cloth-funnel and rod-twist and the edge-edge times of rod-twist came to within 1e-8 of
// the exact ones, where the search over the whole step answered up to 0.045, 0.0025 and
// 0.0083 early. (One edge-edge query of cloth-funnel still answers 0.46 early.)
TEST_CASE("in double the conservative solver's times on real steps are within 1e-8 of the exact ones",
          "[narrow][quick]")
{
  const auto& device = cstreams::test::device().device();
  if (!device.fp64) return;
  // Without 64-bit atomics a query's earliest time is kept rounded down to float
  // (refine.cl), one step of 2^-24 below 1.
  const double within = 1e-8 + (device.int64_atomics ? 0 : 0x1p-23);
  DeviceSolver solver(cstreams::test::device(), conservative(Precision::double_));
  const std::pair<cstreams::test::RealStep, ContactKind> sets[] = {
      {cstreams::test::real_steps[0], ContactKind::vertex_face},
      {cstreams::test::real_steps[1], ContactKind::vertex_face},
      {cstreams::test::real_steps[1], ContactKind::edge_edge}};
  for (const auto& [step, kind] : sets) {
    const Dataset d =
        real_step_dataset(cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + step.scene), kind);
    const auto results = solver.solve(d.kind, d.queries);
    std::size_t timed = 0;
    long double worst = 0;
    for (std::size_t i = 0; i < results.size(); ++i) {
      if (!d.collides[i] || std::isnan(d.exact_toi[i])) continue;
      REQUIRE(results[i].collides());
      ++timed;
      worst = std::max(worst, d.exact_toi[i] - (long double)results[i].toi);
    }
    INFO(d.name << (kind == ContactKind::vertex_face ? " vf: " : " ee: ") << timed
                << " timed contacts, earliest by at most " << double(worst));
    CHECK(timed > 0);
    CHECK(worst >= 0);
    CHECK(worst < within);
  }
}

TEST_CASE("all 7,279 hand-made queries: the conservative solver misses none", "[narrow][slow]")
{
  const auto sets = handmade();
  for (Precision p : precisions()) {
    DeviceSolver solver(cstreams::test::device(), conservative(p));
    Tally total;
    for (const auto& d : sets) {
      const Tally t = run(solver, d);
      total.queries += t.queries;
      total.false_negatives += t.false_negatives;
      total.filtered += t.filtered;
    }
    INFO(to_string(p));
    CHECK(total.queries == 7279);
    CHECK(total.false_negatives == 0);
    CHECK(total.filtered > 0);  // the filter does cull, and (above) never a true contact
  }
}

TEST_CASE("scaled and translated hand-made queries: the conservative solver misses none", "[narrow][slow]")
{
  const auto sets = handmade();
  for (Precision p : precisions()) {
    DeviceSolver solver(cstreams::test::device(), conservative(p));
    for (double scale : {0x1p-13, 0x1p13})  // 1.2e-4 and 8.2e3, exact
      for (double shift : {0.0, 1e4}) {
        std::size_t kept_total = 0, missed = 0;
        for (const auto& d : sets) {
          std::size_t kept = 0;
          const Dataset moved = transformed(d, scale, shift, kept);
          kept_total += kept;
          missed += run(solver, moved).false_negatives;
        }
        INFO(to_string(p) << " scale " << scale << " shift " << shift << ": " << kept_total << " exact queries");
        CHECK(kept_total > 0);
        CHECK(missed == 0);
      }
  }
}

TEST_CASE("real simulation steps: the conservative solver misses none and is never late", "[narrow][slow]")
{
  for (const auto& s : cstreams::test::real_steps) {
    const std::string folder = cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene);
    for (Precision p : precisions()) {
      DeviceSolver solver(cstreams::test::device(), conservative(p));
      for (auto kind : {ContactKind::vertex_face, ContactKind::edge_edge}) {
        const Dataset d = real_step_dataset(folder, kind);
        const Tally t = run(solver, d);
        INFO(d.name << " " << to_string(p));
        CHECK(t.false_negatives == 0);
        CHECK(t.late == 0);
      }
    }
  }
}
