// The run loop against host computations: passes in order and in stages, in-place updates,
// minimums, variants, passes behind a parameter, launches over several streams, and the
// run's figures. Reruns are in test_flush.cpp, registration in test_registrar.cpp,
// memory in test_scratch.cpp, test_late_packing.cpp and test_slices.cpp, reads after a
// run in test_run_reads.cpp, invalid graphs in test_stream_graph.cpp.
#include "scheduler_graphs.hpp"
#include "checked_graph.hpp"

#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <memory>
#include <random>

using namespace cstreams::runtime;
using namespace cstreams::test;
using cstreams::test::Pair;
using cstreams::test::Quad;

TEST_CASE("the scheduler orders passes and matches the host for every registration", "[runtime][scheduler][quick]")
{
  for (auto registration : {Registration::lock_free, Registration::segmented_lock, Registration::global_atomic})
    for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(255), std::size_t(257), std::size_t(20000)})
      check_graph(n, registration, 1 << 16, std::uint32_t(n) + 1);
}

// The figures are gathered once asked for, so that a caller's next launch need not wait
// for them: they still describe the streams as the run left them.
TEST_CASE("a run's figures describe its streams as it ended, whatever changed them before they were asked for",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  StreamGraph g;
  auto values = g.fixed("values", 4, 0);
  auto pairs = g.variable("pairs", 8, 1);
  auto spare = g.variable("spare", 8, 1);
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  Scheduler s(ctx, g);
  const auto expected = cstreams::test::reference(random_values(3000, 5)).pairs;
  for (const bool swapped : {false, true}) {
    INFO((swapped ? "pairs swapped after the run" : "nothing changed after the run"));
    s.upload(values, random_values(3000, 5));
    s.run();
    const std::size_t bytes = s.buffer(pairs).bytes();
    if (swapped) s.swap(pairs, spare);
    CHECK(s.count(swapped ? spare : pairs) == expected.size());
    const RunStats& stats = s.stats();
    REQUIRE(stats.streams.size() == 3);
    CHECK(stats.streams[1].name == "pairs");
    CHECK(stats.streams[1].count == expected.size());
    CHECK(stats.streams[1].items == expected.size());
    CHECK(stats.streams[1].bytes == bytes);
    CHECK(stats.streams[2].count == 0);
    REQUIRE(stats.passes.size() == 1);
    CHECK(stats.passes[0].name == "expand");
    if (swapped) s.swap(pairs, spare);
  }
}

TEST_CASE("passes update a fixed stream in place, in declaration order, before its readers", "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  StreamGraph g;
  const std::size_t n = 10007;
  auto values = g.fixed("values", 4, n);
  auto squares = g.fixed("squares", 4, n);
  auto pairs = g.variable("pairs", 8, 16);
  // Declared reader first and updates out of dependency order: the scheduler must run
  // square, plus_one, times_two, expand.
  g.pass("expand", {program, "test_expand"}).launch_over(squares).emit(pairs).arg(buffer_of(squares)).arg(count_of(squares));
  g.pass("square", {program, "test_square"})
      .launch_over(values)
      .write(squares)
      .arg(buffer_of(values))
      .arg(count_of(values))
      .arg(buffer_of(squares));
  g.pass("plus_one", {program, "test_plus_one"}).launch_over(squares).update(squares).arg(buffer_of(squares)).arg(count_of(squares));
  g.pass("times_two", {program, "test_times_two"}).launch_over(squares).update(squares).arg(buffer_of(squares)).arg(count_of(squares));
  for (auto registration : {Registration::lock_free, Registration::segmented_lock}) {
    Scheduler s(ctx, g, {registration, true});
    CHECK(s.execution_order() == std::vector<std::string>{"square", "plus_one", "times_two", "expand"});
    const auto v = random_values(n, 17);
    s.upload(values, v);
    s.run();
    std::vector<std::uint32_t> expected(n);
    for (std::size_t i = 0; i < n; ++i) expected[i] = (v[i] * v[i] + 1u) * 2u;
    CHECK(s.download<std::uint32_t>(squares) == expected);
    CHECK(sorted(s.download<Pair>(pairs)) == sorted(cstreams::test::reference(expected).pairs));
  }
}

// A pass that emits may take a running minimum into a fixed stream (PassSpec::lower):
// it runs after the stream's writer and before its reader, and growing what it emits
// runs it again, which leaves the same minimums.
TEST_CASE("a pass that emits lowers a fixed stream to minimums, after its writer, through its reruns",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  const LoweringGraph l = lowering_graph(false);
  for (auto registration : {Registration::lock_free, Registration::segmented_lock}) {
    Scheduler s(ctx, l.g, {registration, true});
    CHECK(s.execution_order() == std::vector<std::string>{"clear", "expand", "copy"});
    const auto v = random_values(LoweringGraph::n, 23);
    s.upload(l.values, v);
    s.run();
    REQUIRE(s.stats().passes.at(1).name == "expand");
    CHECK(s.stats().passes.at(1).reruns > 0);
    const std::vector<std::uint32_t> expected = least_hashes(v);
    CHECK(s.download<std::uint32_t>(l.least) == expected);
    CHECK(s.download<std::uint32_t>(l.copied) == expected);
    CHECK(sorted(s.download<Pair>(l.pairs)) == sorted(cstreams::test::reference(v).pairs));
  }
}

// A pass launches another kernel of its program while a parameter is set
// (PassSpec::instead_while), with the same arguments, and its own again once it is not.
TEST_CASE("a pass launches its variant kernel while its parameter is set", "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t n = 1000;
  StreamGraph g;
  const ParamId doubling = g.param("doubling", 4);
  auto values = g.fixed("values", 4, n);
  auto pairs = g.variable("pairs", 8, 16);
  g.pass("bump", {program, "test_plus_one"})
      .launch_over(values)
      .update(values)
      .instead_while(doubling, "test_times_two")
      .arg(buffer_of(values))
      .arg(count_of(values));
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  Scheduler s(ctx, g, {Registration::segmented_lock, true});
  const auto v = random_values(n, 29);
  std::vector<std::uint32_t> expected = v;
  s.upload(values, v);
  for (const cl_uint doubled : {0u, 1u, 1u, 0u}) {
    INFO("doubling " << doubled);
    s.set(doubling, doubled);
    s.run();
    for (auto& x : expected) x = doubled ? 2u * x : x + 1u;
    CHECK(s.download<std::uint32_t>(values) == expected);
    CHECK(sorted(s.download<Pair>(pairs)) == sorted(cstreams::test::reference(expected).pairs));
  }
}

// A pass behind a parameter (PassSpec::only_while): skipped while it is 0, its output
// keeping what it held and the pass launching nothing; run while it is set; refused
// where the pass emits, or the parameter is not four bytes.
TEST_CASE("a pass runs only while its parameter is set, and its output keeps what it held otherwise",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t n = 1000;
  // values -> (square, only while `wanted`) squares
  const auto add_square_while = [&](StreamGraph& graph, ParamId wanted) {
    const StreamId values = graph.fixed("values", 4, n), squares = graph.fixed("squares", 4, n);
    add_square(graph, values, squares).only_while(wanted);
    return std::pair{values, squares};
  };
  StreamGraph g;
  const ParamId wanted = g.param("squares wanted", 4);
  const auto [values, squares] = add_square_while(g, wanted);
  auto pairs = g.variable("pairs", 8, 16);
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  Scheduler s(ctx, g, {Registration::segmented_lock, true});
  const auto first = random_values(n, 5), second = random_values(n, 6);
  std::vector<std::uint32_t> first_squares(n);
  for (std::size_t i = 0; i < n; ++i) first_squares[i] = first[i] * first[i];
  const auto launches_of_square = [&] {
    for (const auto& p : s.stats().passes)
      if (p.name == "square") return p.launches;
    return 0u;
  };
  s.upload(values, first);
  s.set(wanted, cl_uint(1));
  s.run();
  CHECK(launches_of_square() == 1);
  CHECK(s.download<std::uint32_t>(squares) == first_squares);
  s.upload(values, second);
  s.set(wanted, cl_uint(0));
  s.run();
  CHECK(launches_of_square() == 0);
  CHECK(s.download<std::uint32_t>(squares) == first_squares);
  CHECK(sorted(s.download<Pair>(pairs)) == sorted(cstreams::test::reference(second).pairs));

  StreamGraph emitting;
  auto v = emitting.fixed("values", 4, n);
  auto out = emitting.variable("pairs", 8, 16);
  const ParamId flag = emitting.param("flag", 4);
  emitting.pass("expand", {program, "test_expand"}).launch_over(v).emit(out).only_while(flag).arg(buffer_of(v)).arg(count_of(v));
  CHECK_THROWS_WITH(Scheduler(ctx, emitting, {}), Catch::Contains("expand") && Catch::Contains("parameter"));
  StreamGraph eight_bytes;
  add_square_while(eight_bytes, eight_bytes.param("wide", 8));
  CHECK_THROWS_WITH(Scheduler(ctx, eight_bytes, {}), Catch::Contains("square") && Catch::Contains("parameter"));
}

TEST_CASE("a pass launched over several streams gets a work-item for each of their items", "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  StreamGraph g;
  const auto a = g.fixed("a", 4, 0), b = g.fixed("b", 4, 0);
  const auto both = g.variable("both", 4, 16);
  g.pass("concatenate", {program, "test_concatenate"})
      .launch_over({a, b})
      .emit(both)
      .arg(buffer_of(a))
      .arg(count_of(a))
      .arg(buffer_of(b))
      .arg(count_of(b));
  Scheduler s(ctx, g);
  for (const auto& [na, nb] : {std::pair<std::size_t, std::size_t>{1000, 333}, {0, 77}, {5000, 0}}) {
    const auto va = random_values(na, 5), vb = random_values(nb, 6);
    s.upload(a, va);
    s.upload(b, vb);
    s.run();
    auto expected = va;
    expected.insert(expected.end(), vb.begin(), vb.end());
    CHECK(sorted(s.download<std::uint32_t>(both)) == sorted(expected));
  }
}
