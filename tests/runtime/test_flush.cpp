// The flush (scheduler/flush.cpp): outputs that outgrow their streams grow and their
// passes run again, losing no item, from tiny capacities to millions of items.
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

TEST_CASE("tiny capacities grow and rerun without losing an item", "[runtime][scheduler][quick]")
{
  for (auto registration : {Registration::lock_free, Registration::segmented_lock, Registration::global_atomic})
    for (std::size_t capacity : {std::size_t(0), std::size_t(1), std::size_t(37)})
      check_graph(30011, registration, capacity, 99);
}

TEST_CASE("random sizes up to millions of items", "[runtime][scheduler][slow]")
{
  std::mt19937 rng(2011);
  std::uniform_int_distribution<std::size_t> size(0, 3'000'000);
  for (auto registration : {Registration::lock_free, Registration::segmented_lock, Registration::global_atomic}) {
    check_graph(size(rng), registration, 1, std::uint32_t(rng()));
    check_graph(size(rng), registration, 1 << 20, std::uint32_t(rng()));
  }
}

TEST_CASE("overflow reruns are counted and capacities reported", "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  StreamGraph g;
  auto values = g.fixed("values", 4, 0);
  auto pairs = g.variable("pairs", 8, 1);
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  Scheduler s(ctx, g, {Registration::segmented_lock, true});
  s.upload(values, random_values(5000, 3));
  s.run();
  const auto expected = cstreams::test::reference(random_values(5000, 3)).pairs;
  CHECK(s.count(pairs) == expected.size());
  CHECK(s.capacity(pairs) >= expected.size());
  REQUIRE(s.stats().passes.size() == 1);
  CHECK(s.stats().passes[0].reruns >= 1);
  CHECK(s.stats().passes[0].device_ns > 0);
  CHECK(s.stats().streams[1].bytes >= expected.size() * 8);
  CHECK(s.stats().streams[1].peak_bytes >= s.stats().streams[1].bytes);
  CHECK(s.stats().scratch_bytes > 0);

  // A smaller capacity keeps the items that still fit.
  const auto all = s.download<Pair>(pairs);
  const std::size_t half = all.size() / 2;
  s.set_capacity(pairs, half);
  CHECK(s.capacity(pairs) == half);
  CHECK(s.download<Pair>(pairs) == std::vector<Pair>(all.begin(), all.begin() + std::ptrdiff_t(half)));
}
