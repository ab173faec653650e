// The device solvers against exact ground truth, on the device tests select
// (CSTREAMS_DEVICE; pocl in CI): constructed degenerate cases, the refinement's cuts, and
// the cubic test's bound.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"
#include "narrow_phase_cases.hpp"

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
using namespace cstreams::test;

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
