// Registration (scheduler/registrar.cpp): segments planned from the last run and what
// spills past them, groups of a pass's own size, spill pools that grow, and passes that
// register through the global counter.
#include "scheduler_graphs.hpp"

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

// One pass that expands values into pairs, through segmented locks, in groups of
// `group` work-items (0: the context's). run(v) runs `v`, checks every item and the
// merge's order by group, and returns the pass's reruns.
struct SegmentedExpansion {
  static constexpr std::size_t n = 20000;
  Context& ctx = cstreams::test::device();
  const std::size_t wg;
  StreamGraph g;
  const StreamId values = g.fixed("values", 4, n), pairs = g.variable("pairs", 8, 1);
  std::unique_ptr<Scheduler> s;

  explicit SegmentedExpansion(std::size_t group = 0)
      : wg(group ? std::min(group, ctx.work_group_size()) : ctx.work_group_size())
  {
    g.pass("expand", {program, "test_expand"})
        .launch_over(values)
        .work_group(group)
        .emit(pairs)
        .arg(buffer_of(values))
        .arg(count_of(values));
    s = std::make_unique<Scheduler>(ctx, g, SchedulerOptions{Registration::segmented_lock, true});
  }

  std::size_t run(const std::vector<std::uint32_t>& v)
  {
    s->upload(values, v);
    s->run();
    const auto got = s->download<Pair>(pairs);
    CHECK(sorted(got) == sorted(cstreams::test::reference(v).pairs));
    CHECK(std::is_sorted(got.begin(), got.end(), [&](const Pair& a, const Pair& b) { return a[0] / wg < b[0] / wg; }));
    return s->stats().passes.at(0).reruns;
  }
};

TEST_CASE("segmented-lock segments follow the last run, and what they cannot hold spills into its group's place",
          "[runtime][scheduler][quick]")
{
  SegmentedExpansion e;
  const std::size_t n = e.n, wg = e.wg;
  const std::uint32_t burst = cstreams::test::value_emitting(40);

  auto v = random_values(n, 5);
  e.run(v);
  CHECK(e.run(v) == 0);  // planned from the same counts
  // One group bursts far past its plan's eighth more: the spill pool holds the rest.
  for (std::size_t i = 3 * wg; i < 3 * wg + 12; ++i) v[i] = burst;
  CHECK(e.run(v) == 0);
  // Half the groups burst: more than the pool holds (twice what spilled last run, at
  // least 16 items a work-item of one group), so the pass runs again, planned from this
  // run's counts.
  for (std::size_t i = 0; i < n / 2; ++i) v[i] = burst;
  CHECK(e.run(v) == 1);
  CHECK(e.run(v) == 0);
}

// A pass in groups of its own (a kernel heavy in registers) has a segment a group of
// them: a segment a group of the context's would leave groups without one.
TEST_CASE("a pass launched in smaller groups than the context's registers in a segment for each of them",
          "[runtime][scheduler][quick]")
{
  SegmentedExpansion e(std::max<std::size_t>(cstreams::test::device().work_group_size() / 4, 1));
  const std::size_t n = e.n, wg = e.wg;
  REQUIRE(wg * 4 == e.ctx.work_group_size());
  auto v = random_values(n, 7);
  e.run(v);
  CHECK(e.run(v) == 0);
  for (std::size_t i = 5 * wg; i < 5 * wg + 12; ++i) v[i] = cstreams::test::value_emitting(40);
  CHECK(e.run(v) == 0);
  for (std::size_t i = 0; i < n / 2; ++i) v[i] = cstreams::test::value_emitting(40);
  CHECK(e.run(v) == 1);
  CHECK(e.run(v) == 0);
}

TEST_CASE("a spill pool that overflowed grows: steps that each outgrow the last alike rerun once",
          "[runtime][scheduler][quick]")
{
  SegmentedExpansion e;
  const std::size_t n = e.n, wg = e.wg;
  // Each step, half a group's values more burst (40 items each, where their plan holds
  // a few): more spills than a pool of 16 items for each of a group's work-items holds,
  // the least a planned pool holds, and what a pool of 16 items a group held here.
  auto v = random_values(n, 61);
  e.run(v);
  CHECK(e.run(v) == 0);
  std::size_t first = 0, later = 0;
  for (std::size_t step = 1; step <= 4; ++step) {
    for (std::size_t i = 2 * wg + (step - 1) * wg / 2; i < 2 * wg + step * wg / 2 && i < n; ++i)
      v[i] = cstreams::test::value_emitting(40);
    (step == 1 ? first : later) += e.run(v);
  }
  CHECK(first <= 1);
  CHECK(later == 0);
}

// A front that grows a fifth a step spills far past the least pool every step; the pool
// takes what the last step spilled (its count goes on past the pool), so only the first
// such step runs twice, where a pool growing fourfold from its least had rerun the pass
// in every step.
TEST_CASE("a spill pool takes twice what spilled: steps that each outgrow the last as much rerun only the first",
          "[runtime][scheduler][quick]")
{
  SegmentedExpansion e;
  const std::size_t n = e.n;
  auto v = random_values(n, 67);
  e.run(v);
  CHECK(e.run(v) == 0);
  // An eighth of the values more burst each step: 40 items each, a hundred thousand
  // spilled items a step, against a least pool of 16 items a work-item of one group.
  std::vector<std::size_t> reruns;
  for (std::size_t step = 0; step < 4; ++step) {
    for (std::size_t i = step * n / 8; i < (step + 1) * n / 8; ++i) v[i] = cstreams::test::value_emitting(40);
    reruns.push_back(e.run(v));
  }
  CHECK(reruns == std::vector<std::size_t>{1, 0, 0, 0});
}

TEST_CASE("a pass that emits in any order registers through the global counter, losing no item and launching less",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  const auto v = random_values(30011, 5);
  const auto expected = cstreams::test::reference(v).pairs;
  for (auto registration : {Registration::segmented_lock, Registration::lock_free})
    for (std::size_t capacity : {std::size_t(1), std::size_t(1) << 17}) {
      INFO("registration = " << to_string(registration) << ", capacity = " << capacity);
      // Steady launches of a settled run of the expansion, with and without the order.
      std::uint64_t launches[2];
      for (const bool any_order : {false, true}) {
        StreamGraph g;
        const StreamId values = g.fixed("values", 4, v.size()), pairs = g.variable("pairs", 8, capacity);
        auto& expand = g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs);
        expand.arg(buffer_of(values)).arg(count_of(values));
        if (any_order) expand.emits_in_any_order();
        Scheduler s(ctx, g, {registration, true});
        s.upload(values, v);
        s.run();
        CHECK(sorted(s.download<Pair>(pairs)) == sorted(expected));
        const std::uint64_t before = ctx.kernel_launches();
        s.run();
        launches[any_order] = ctx.kernel_launches() - before;
        CHECK(sorted(s.download<Pair>(pairs)) == sorted(expected));
        CHECK(s.stats().passes.at(0).reruns == 0);
        if (any_order) CHECK(s.stats().passes.at(0).segment_bytes == 0);
      }
      // The segments' scan and merge (lock-free: scan and interleaved merge) are gone.
      CHECK(launches[1] < launches[0]);
      CHECK(launches[1] == 1);
    }
}
