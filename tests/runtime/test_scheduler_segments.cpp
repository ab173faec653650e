// Registration segments planned from the last run, their spill pools, and the step arena
// that what lives within a run shares.
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

// Values expand into pairs; in the next stage a pass copies the pairs' first words, one
// per pair: half the bytes.
struct ExpandThenCopy {
  StreamGraph g;
  StreamId values, pairs, words;
  explicit ExpandThenCopy(std::size_t n)
  {
    values = g.fixed("values", 4, n);
    const auto none = g.fixed("none", 4, 0);
    pairs = g.variable("pairs", 8, 16);
    words = g.variable("words", 4, 16);
    g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
    g.pass("copy", {program, "test_concatenate"})
        .launch_over({pairs, none})
        .emit(words)
        .arg(buffer_of(pairs))
        .arg(count_of(pairs))
        .arg(buffer_of(none))
        .arg(count_of(none));
  }
  void check_words(const Scheduler& s) const
  {
    const auto p = s.download<Pair>(pairs);
    std::vector<std::uint32_t> expected(p.size());
    std::memcpy(expected.data(), p.data(), expected.size() * sizeof(std::uint32_t));
    CHECK(sorted(s.download<std::uint32_t>(words)) == sorted(expected));
  }
};

TEST_CASE("what lives within a run shares one buffer: a settled run holds less, allocates nothing, emits the same",
          "[runtime][scheduler][quick]")
{
  // expand's segments and its pairs live in the first stage, the pairs, copy's
  // segments and its words in the second: in the step arena the second stage's take
  // the first's segments' place. Each on a context of its own, so that what is in use
  // is the scheduler's. The pairs are compared as sets: the words copy the first half of
  // the pairs' words in the order the pairs were emitted, which a GPU does not keep
  // within a work-group.
  const std::size_t n = 200000;
  const ExpandThenCopy e(n);
  const auto values = random_values(n, 47);
  const auto settled = [&](bool arena, std::vector<Pair>& pairs) {
    Context own(filter_from_environment());
    own.programs().add_sources(test_kernel_sources());
    Scheduler s(own, e.g, {Registration::segmented_lock, true, arena});
    s.upload(e.values, values);
    for (int frame = 0; frame < 4; ++frame) s.run();
    own.reset_memory_high_water();
    s.run();
    e.check_words(s);
    pairs = sorted(s.download<Pair>(e.pairs));
    CHECK(own.memory_high_water() == own.memory_in_use());
    return own.memory_in_use();
  };
  std::vector<Pair> in_arena, apart;
  const std::size_t with = settled(true, in_arena), without = settled(false, apart);
  INFO("held with the arena " << with << ", without " << without);
  CHECK(in_arena == sorted(cstreams::test::reference(values).pairs));
  CHECK(in_arena == apart);
  CHECK(with < without);
}

TEST_CASE("a stream that lives within its run goes back once read, and its reader's later outputs take its place",
          "[runtime][scheduler][quick]")
{
  // values -> (expand) pairs -> (cull) kept -> (tag and copy) tags + copies. Nothing
  // after tag-and-copy reads kept; marked so, kept goes back once tags (the smaller
  // output, first) is packed, and copies, as large as kept, packs where kept was.
  // Settled runs on contexts of their own, so that the peaks are the scheduler's.
  const std::size_t n = 200000;
  const auto values = random_values(n, 53);
  const std::vector<Pair> kept = sorted(cstreams::test::reference(values).kept);
  std::vector<std::uint32_t> tags;
  for (const Pair& p : kept)
    if (p[1] % 4 == 0) tags.push_back(p[0]);
  const auto settled = [&](bool within) {
    StreamGraph g;
    const StreamId in = g.fixed("values", 4, n), pairs = g.variable("pairs", 8, 16), culled = g.variable("kept", 8, 16),
                   tagged = g.variable("tags", 4, 16), copies = g.variable("copies", 8, 16);
    g.pass("expand", {program, "test_expand"}).launch_over(in).emit(pairs).arg(buffer_of(in)).arg(count_of(in));
    g.pass("cull", {program, "test_keep"}).launch_over(pairs).cull(pairs, culled).arg(buffer_of(pairs)).arg(count_of(pairs));
    g.pass("tag and copy", {program, "test_tag_and_copy"})
        .launch_over(culled)
        .emit(tagged)
        .emit(copies)
        .arg(buffer_of(culled))
        .arg(count_of(culled));
    if (within) g.within_run(culled);
    Context own(filter_from_environment());
    own.programs().add_sources(test_kernel_sources());
    Scheduler s(own, g, {Registration::segmented_lock, true});
    s.upload(in, values);
    for (int frame = 0; frame < 4; ++frame) s.run();
    own.reset_memory_high_water();
    s.run();
    CHECK(sorted(s.download<std::uint32_t>(tagged)) == sorted(tags));
    CHECK(sorted(s.download<Pair>(copies)) == kept);
    if (within) CHECK_THROWS_WITH(s.download<Pair>(culled), Catch::Contains("kept") && Catch::Contains("within a run"));
    else CHECK(sorted(s.download<Pair>(culled)) == kept);
    return own.memory_high_water();
  };
  const std::size_t with = settled(true), without = settled(false);
  INFO("peak with kept within its run " << with << ", without " << without);
  CHECK(with < without);
}

TEST_CASE("a later stage's pass registers into the segments an earlier stage's pass held", "[runtime][scheduler][quick]")
{
  // Without the step arena: segments go through the pool of idle buffers.
  auto& ctx = cstreams::test::device();
  const std::size_t n = 20000;
  const ExpandThenCopy e(n);
  // Segmented lock, the default: segments follow what each group emitted, so a burst of
  // every value asks for several times the usual segments. (Lock-free ones hold the
  // busiest work-item's items for every work-item, a burst's size already.)
  Scheduler s(ctx, e.g, {Registration::segmented_lock, true, false});
  s.upload(e.values, random_values(n, 41));
  for (int frame = 0; frame < 3; ++frame) {
    s.run();
    e.check_words(s);
  }
  const auto& stats = s.stats();
  const std::size_t expand = stats.passes.at(0).segment_bytes, copy = stats.passes.at(1).segment_bytes;
  CHECK(copy > 0);
  CHECK(copy <= expand);  // the same buffer, taken again
  CHECK(stats.segment_bytes == expand);

  // A burst (every value emits 40 pairs) takes larger segments; once it has passed,
  // they go back.
  const std::uint32_t burst = cstreams::test::value_emitting(40);
  s.upload(e.values, std::vector<std::uint32_t>(n, burst));
  s.run();
  CHECK(s.stats().segment_bytes > 4 * expand);
  s.upload(e.values, random_values(n, 41));
  s.run();
  s.run();
  CHECK(s.stats().segment_bytes <= 2 * expand + (1u << 20));

  // Between runs no pass holds anything in its scratch: all of it may go back (for
  // device work outside the graph short of memory), and the next run allocates it again.
  const std::size_t held = ctx.memory_in_use(), segments = s.stats().segment_bytes;
  REQUIRE(s.release_idle_scratch());
  CHECK(ctx.memory_in_use() + segments <= held);
  CHECK_FALSE(s.release_idle_scratch());
  s.run();
  e.check_words(s);
}

TEST_CASE("a pass that outgrows the idle segments gives them back before it takes larger ones",
          "[runtime][scheduler][quick]")
{
  // Without the step arena: segments go through the pool of idle buffers.
  auto& ctx = cstreams::test::device();
  const std::size_t n = 200000;
  const ExpandThenCopy e(n);
  Scheduler s(ctx, e.g, {Registration::segmented_lock, true, false});
  s.upload(e.values, random_values(n, 43));
  for (int frame = 0; frame < 3; ++frame) s.run();
  const std::size_t pool = s.stats().segment_bytes;
  // Every value emits 40 pairs: both stages need several times the pool's segments.
  const std::uint32_t burst = cstreams::test::value_emitting(40);
  s.upload(e.values, std::vector<std::uint32_t>(n, burst));
  ctx.reset_memory_high_water();
  s.run();
  const std::size_t held = ctx.memory_in_use();
  REQUIRE(s.stats().segment_bytes > 4 * pool);
  // At its peak the device held what it holds now, the burst's segments among them, but
  // not the pool the burst outgrew, which used to stay idle while the larger segments
  // were taken.
  INFO("pool " << pool << ", held " << held);
  CHECK(ctx.memory_high_water() < held + pool / 2);
  e.check_words(s);
}
