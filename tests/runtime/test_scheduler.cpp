#include "../support/test_device.hpp"
#include "stream_test_reference.hpp"

#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <memory>
#include <random>

const cstreams::runtime::SourceSet& test_kernel_sources();

using namespace cstreams::runtime;
using cstreams::test::Pair;
using cstreams::test::Quad;

namespace {

const char* const program = "kernels/stream_test.cl";

PassSpec& add_square(StreamGraph& g, StreamId values, StreamId squares)
{
  return g.pass("square", {program, "test_square"})
      .launch_over(values)
      .write(squares)
      .arg(buffer_of(values))
      .arg(count_of(values))
      .arg(buffer_of(squares));
}

PassSpec& add_split(StreamGraph& g, StreamId pairs, StreamId squares, StreamId even, StreamId odd)
{
  return g.pass("split", {program, "test_split"})
      .launch_over(pairs)
      .read(squares)
      .emit(even)
      .emit(odd)
      .arg(buffer_of(pairs))
      .arg(count_of(pairs))
      .arg(buffer_of(squares));
}

// values -> (square) squares;  values -> (expand) pairs -> (cull) kept -> (split) even + odd.
// `split` reads the variable stream `kept`, so the scheduler must end a stage before it.
struct TestGraph {
  StreamGraph graph;
  StreamId values, squares, pairs, kept, even, odd;

  TestGraph(std::size_t n, std::size_t capacity)
  {
    values = graph.fixed("values", 4, n);
    squares = graph.fixed("squares", 4, n);
    pairs = graph.variable("pairs", 8, capacity);
    kept = graph.variable("kept", 8, capacity);
    even = graph.variable("even", 4, capacity);
    odd = graph.variable("odd", 16, capacity);
    // Declared out of order on purpose: the scheduler must put split last.
    add_split(graph, kept, squares, even, odd);
    graph.pass("expand", {program, "test_expand"})
        .launch_over(values)
        .emit(pairs)
        .arg(buffer_of(values))
        .arg(count_of(values));
    add_square(graph, values, squares);
    graph.pass("cull", {program, "test_keep"}).launch_over(pairs).cull(pairs, kept).arg(buffer_of(pairs)).arg(count_of(pairs));
  }
};

std::vector<std::uint32_t> random_values(std::size_t n, std::uint32_t seed)
{
  std::mt19937 rng(seed);
  std::vector<std::uint32_t> v(n);
  for (auto& x : v) x = rng();
  return v;
}

// The most memory a run of `g` holds (twice, from `values`) on a context of its own,
// every pass registering through the global counter; `check` sees the scheduler after.
template <class Check>
std::size_t global_counter_peak(const StreamGraph& g, StreamId values, const std::vector<std::uint32_t>& v, Check check)
{
  Context own(filter_from_environment());
  own.programs().add_sources(test_kernel_sources());
  Scheduler atomic(own, g, {Registration::global_atomic, true});
  atomic.upload(values, v);
  for (int frame = 0; frame < 2; ++frame) atomic.run();
  check(atomic);
  return own.memory_high_water();
}

template <class T> std::vector<T> sorted(std::vector<T> v)
{
  std::sort(v.begin(), v.end());
  return v;
}

// What test_beget emits from `values`: the next generation.
std::vector<std::uint32_t> begotten(const std::vector<std::uint32_t>& values)
{
  std::vector<std::uint32_t> next;
  for (const std::uint32_t v : values)
    for (std::uint32_t k = 0; k < cstreams::test::test_emit_count(v); ++k)
      next.push_back(cstreams::test::test_hash(v + k + 1));
  return next;
}

// One pass that begets `now`'s next generation into `next`, handing `now`'s buffer over.
StreamGraph begetting(StreamId& now, StreamId& next)
{
  StreamGraph g;
  now = g.variable("now", 4, 1024);
  next = g.variable("next", 4, 1024);
  g.pass("beget", {program, "test_beget"})
      .launch_over(now)
      .emit(next)
      .hand_over(now, next)
      .arg(buffer_of(now))
      .arg(count_of(now));
  return g;
}

void check_graph(std::size_t n, Registration registration, std::size_t capacity, std::uint32_t seed)
{
  auto& ctx = cstreams::test::device();
  TestGraph t(n, capacity);

  Scheduler scheduler(ctx, t.graph, {registration, true});
  CHECK(scheduler.execution_order() == std::vector<std::string>{"expand", "square", "cull", "split"});

  const auto values = random_values(n, seed);
  const auto expected = cstreams::test::reference(values);
  scheduler.upload(t.values, values);
  for (int frame = 0; frame < 2; ++frame) {
    scheduler.run();
    INFO("n = " << n << ", registration = " << to_string(registration) << ", capacity = " << capacity
                << ", frame = " << frame);
    auto pairs = scheduler.download<Pair>(t.pairs);
    auto kept = scheduler.download<Pair>(t.kept);
    auto even = scheduler.download<std::uint32_t>(t.even);
    auto odd = scheduler.download<Quad>(t.odd);
    if (registration == Registration::lock_free) {
      // Per-thread segments merged in thread order reproduce the sequential order.
      CHECK(pairs == expected.pairs);
      CHECK(kept == expected.kept);
      CHECK(even == expected.even);
      CHECK(odd == expected.odd);
    } else {
      CHECK(sorted(pairs) == sorted(expected.pairs));
      CHECK(sorted(kept) == sorted(expected.kept));
      CHECK(sorted(even) == sorted(expected.even));
      CHECK(sorted(odd) == sorted(expected.odd));
    }
    const auto& stats = scheduler.stats();
    if (frame == 1) {
      // Capacities grown in the first frame are kept: the steady state reruns nothing.
      for (const auto& p : stats.passes) CHECK(p.reruns == 0);
      CHECK(stats.readbacks == 3);  // one per stage: after expand, after cull, after split
      // Scratch is reported per pass: registration segments where there are any, cull flags.
      for (const auto& p : stats.passes) {
        // A device short of memory (rusticl at millions of items) gives idle flags back.
        if (p.name == "cull" && p.scratch_bytes > 0) CHECK(p.scratch_bytes >= pairs.size() * sizeof(std::uint32_t));
        if (n > 0 && p.name == "expand") CHECK((p.scratch_bytes > 0) == (registration != Registration::global_atomic));
      }
      // Segments go from one stage's passes to a later one's: the run counts each buffer
      // once, and what it keeps for the next.
      CHECK(stats.segment_bytes <= stats.scratch_bytes);
    }
  }
}

}  // namespace

TEST_CASE("the scheduler orders passes and matches the host for every registration", "[runtime][scheduler][quick]")
{
  for (auto registration : {Registration::lock_free, Registration::segmented_lock, Registration::global_atomic})
    for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(255), std::size_t(257), std::size_t(20000)})
      check_graph(n, registration, 1 << 16, std::uint32_t(n) + 1);
}

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

TEST_CASE("under any memory limit a stage either fits, giving back scratch, or fails naming the allocation",
          "[runtime][scheduler][quick]")
{
  // One stage: the odd values are culled (flags), then the expansion emits (segments);
  // short of memory, idle scratch goes back, the stage ends early, and a pass whose
  // segments do not fit registers through the global counter. So every limit that the
  // global counter's run fits fits; below it, a run may fail naming the allocation.
  const std::size_t n = 20000;
  StreamGraph g;
  const auto values = g.fixed("values", 4, n);
  const auto pairs = g.variable("pairs", 8, 16), odd = g.variable("odd values", 4, 16);
  g.pass("odd", {program, "test_flag_odd"}).launch_over(values).cull(values, odd).arg(buffer_of(values)).arg(count_of(values));
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  const auto v = random_values(n, 7);
  std::vector<std::uint32_t> odd_values;
  for (const auto x : v)
    if (x & 1u) odd_values.push_back(x);

  // Limits up to what the run holds with its scratch in buffers of their own.
  Scheduler reference(cstreams::test::device(), g, {Registration::segmented_lock, true, false});
  reference.upload(values, v);
  reference.run();
  const auto expected = sorted(reference.download<Pair>(pairs));
  std::size_t streams = 0;
  for (const auto& stream : reference.stats().streams) streams += stream.bytes;
  const std::size_t total = streams + reference.stats().scratch_bytes;
  const std::size_t floor = global_counter_peak(g, values, v, [](const Scheduler&) {});
  REQUIRE(floor < total);

  // Limits from the streams alone to the whole run, and closely above the global
  // counter's peak, where a stage fits only once the passes that overflowed give back
  // their segments.
  std::vector<std::size_t> limits;
  for (std::size_t limit = streams; limit <= total; limit += (total - streams) / 16) limits.push_back(limit);
  for (std::size_t k = 0; k < 8; ++k) limits.push_back(floor + k * (total - floor) / 64);
  unsigned fitted = 0;
  for (const std::size_t limit : limits) {
    INFO("limit " << limit << " of " << total << ", streams " << streams << ", the global counter's peak " << floor);
    Context limited(filter_from_environment());
    limited.programs().add_sources(test_kernel_sources());
    limited.set_memory_limit(limit);
    Scheduler s(limited, g, {Registration::segmented_lock, true});
    s.upload(values, v);
    try {
      for (int frame = 0; frame < 2; ++frame) {
        s.run();
        CHECK(sorted(s.download<Pair>(pairs)) == expected);
        CHECK(s.download<std::uint32_t>(odd) == odd_values);
      }
      ++fitted;
    } catch (const DeviceMemoryExhausted& e) {
      INFO(e.what());
      CHECK_THAT(e.what(), Catch::Contains("allocating"));
      CHECK(limit < floor);
    }
  }
  CHECK(fitted > 0);
}

TEST_CASE("short of memory for what a pass emits, it runs in slices of its input and gathers what the graph asks for",
          "[runtime][scheduler][quick]")
{
  // values -> (expand) pairs -> (split) even + odd, with squares written beside. Only
  // `even` is gathered; `odd`, the larger output, is what slices share out.
  const std::size_t n = 60000;
  StreamGraph g;
  const auto values = g.fixed("values", 4, n), squares = g.fixed("squares", 4, n);
  const auto pairs = g.variable("pairs", 8, 16), even = g.variable("even", 4, 16), odd = g.variable("odd", 16, 16);
  g.gather(even);
  g.pass("expand", {program, "test_expand"}).launch_over(values).emit(pairs).arg(buffer_of(values)).arg(count_of(values));
  add_square(g, values, squares);
  add_split(g, pairs, squares, even, odd);
  // split's input is every pair (the reference culls some first).
  struct Outputs {
    std::vector<Pair> pairs;
    std::vector<std::uint32_t> even;
    std::size_t odd = 0;
  };
  const auto expect = [](const std::vector<std::uint32_t>& v) {
    Outputs o;
    o.pairs = cstreams::test::reference(v).pairs;
    for (const auto& p : o.pairs) {
      const std::uint32_t sq = v[p[0]] * v[p[0]];
      if ((sq + p[1]) % 2u == 0u) o.even.push_back(sq + p[1]);
      else o.odd += p[1] % 3u + 1u;
    }
    return o;
  };
  const auto v = random_values(n, 11);
  const Outputs expected = expect(v);
  const std::size_t floor = global_counter_peak(g, values, v, [&](const Scheduler& atomic) {
    CHECK(atomic.stats().slices == 1);
    CHECK(sorted(atomic.download<std::uint32_t>(even)) == sorted(expected.even));
    CHECK(atomic.count(odd) == expected.odd);
  });
  const std::size_t odd_bytes = expected.odd * 16;
  REQUIRE(odd_bytes < floor);
  // The same values but for the last nine tenths, which expand to nothing.
  const std::uint32_t silent = cstreams::test::value_emitting(0);
  std::vector<std::uint32_t> few = v;
  std::fill(few.begin() + n / 10, few.end(), silent);
  const Outputs expected_few = expect(few);

  for (const double share : {0.5, 0.75}) {
    Context limited(filter_from_environment());
    limited.programs().add_sources(test_kernel_sources());
    const std::size_t limit = floor - std::size_t(share * double(odd_bytes));
    limited.set_memory_limit(limit);
    INFO("limit " << limit << ", the global counter's peak " << floor << ", odd items " << odd_bytes << " bytes");
    Scheduler s(limited, g, {Registration::segmented_lock, true});
    const auto check_run = [&](const Outputs& want, const char* input) {
      INFO(input);
      s.run();
      const RunStats& stats = s.stats();
      CHECK(limited.memory_high_water() <= limit);
      CHECK(sorted(s.download<std::uint32_t>(even)) == sorted(want.even));
      // The pairs were emitted before any slices, whole.
      CHECK(sorted(s.download<Pair>(pairs)) == sorted(want.pairs));
      CHECK(stats.streams[odd.index].items == want.odd);
      return stats.slices;
    };
    // The second run starts in as many slices as the first ended with.
    s.upload(values, v);
    unsigned first_slices = 0;
    for (int frame = 0; frame < 2; ++frame) {
      const unsigned slices = check_run(expected, "all values");
      CHECK(slices > 1);
      if (frame == 0) first_slices = slices;
      CHECK(slices == first_slices);
      CHECK(s.stats().sliced_pass == "split");
      // odd holds the last slice's.
      CHECK(s.count(odd) < expected.odd);
      CHECK_THROWS_WITH(s.download<Quad>(odd), Catch::Contains("slices") && Catch::Contains("gather"));
    }
    // A tenth of the work fits one slice; all of it takes its slices again.
    s.upload(values, few);
    CHECK(check_run(expected_few, "a tenth of the values") == 1);
    CHECK(s.stats().sliced_pass == "split");
    CHECK(s.download<Quad>(odd).size() == expected_few.odd);
    s.upload(values, v);
    CHECK(check_run(expected, "all values again") == first_slices);
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

namespace {

// values -> (expand, which lowers `least` to the least hash of each residue of the
// values mod m) pairs, after `clear` writes `least`; then `copy` copies `least`, behind
// the pairs where asked (a stage with no counters to read).
struct LoweringGraph {
  static constexpr std::size_t n = 10007, m = 61;
  StreamGraph g;
  StreamId values, least, copied, pairs;
};

LoweringGraph lowering_graph(bool copy_behind_pairs)
{
  const std::size_t n = LoweringGraph::n, m = LoweringGraph::m;
  LoweringGraph l;
  StreamGraph& g = l.g;
  l.values = g.fixed("values", 4, n);
  l.least = g.fixed("least", 4, m);
  l.copied = g.fixed("copied", 4, m);
  l.pairs = g.variable("pairs", 8, 16);
  // Declared reader first: the scheduler must run clear, expand, copy.
  auto& copy = g.pass("copy", {program, "test_copy"}).launch_items(m).read(l.least);
  if (copy_behind_pairs) copy.read(l.pairs);
  copy.write(l.copied).arg(buffer_of(l.least)).arg(value_of(cl_uint(m))).arg(buffer_of(l.copied));
  g.pass("expand", {program, "test_expand_lowering"})
      .launch_over(l.values)
      .emit(l.pairs)
      .lower(l.least)
      .arg(buffer_of(l.values))
      .arg(count_of(l.values))
      .arg(value_of(cl_uint(m)))
      .arg(buffer_of(l.least));
  g.pass("clear", {program, "test_clear_least"}).launch_items(m).write(l.least).arg(value_of(cl_uint(m))).arg(buffer_of(l.least));
  return l;
}

std::vector<std::uint32_t> least_hashes(const std::vector<std::uint32_t>& values)
{
  std::vector<std::uint32_t> least(LoweringGraph::m, 0xffffffffu);
  for (std::uint32_t x : values) least[x % least.size()] = std::min(least[x % least.size()], cstreams::test::test_hash(x));
  return least;
}

}  // namespace

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

// A fixed stream read back as a run ends (Scheduler::read_after_run): where every pass
// that writes it runs before the run's last counter read, it comes back with that read
// (no blocking read of its own), after the reruns that lower it again; else it is read
// once the run is done. Either way the read is for that run alone. The caller's work
// given for counter reads (Scheduler::on_counter_read) runs before each of them.
TEST_CASE("a stream read after a run comes back with its last counter read, after the reruns that write it",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t m = LoweringGraph::m;
  // Behind the pairs, `copied` is written after the last counter read: nothing brings
  // it back but a read of its own.
  const LoweringGraph l = lowering_graph(true);
  const auto v = random_values(LoweringGraph::n, 31);
  const std::vector<std::uint32_t> expected = least_hashes(v);
  // Blocking reads of a first run from a new scheduler, with the given reads after it.
  const auto first_run = [&](Registration registration, const std::vector<std::pair<StreamId, std::vector<std::uint32_t>*>>& reads) {
    Scheduler s(ctx, l.g, {registration, true});
    s.upload(l.values, v);
    for (auto& [stream, host] : reads) s.read_after_run(stream, host->data(), host->size());
    const std::uint64_t before = ctx.blocking_reads();
    s.run();
    REQUIRE(s.stats().passes.at(1).name == "expand");
    CHECK(s.stats().passes.at(1).reruns > 0);
    return ctx.blocking_reads() - before;
  };
  for (auto registration : {Registration::lock_free, Registration::segmented_lock}) {
    INFO(to_string(registration));
    const std::uint64_t alone = first_run(registration, {});
    std::vector<std::uint32_t> lowered(m, 7), copy(m, 7);
    CHECK(first_run(registration, {{l.least, &lowered}}) == alone);
    CHECK(lowered == expected);
    CHECK(first_run(registration, {{l.copied, &copy}}) == alone + 1);
    CHECK(copy == expected);

    Scheduler s(ctx, l.g, {registration, true});
    s.upload(l.values, v);
    std::vector<std::uint32_t> once(m, 7);
    s.read_after_run(l.least, once.data(), m);
    // The caller's work before each counter read: as many as the run made.
    unsigned before_reads = 0;
    s.on_counter_read([&] { ++before_reads; });
    s.run();
    CHECK(before_reads == s.stats().readbacks);
    CHECK(before_reads > 1);
    CHECK(once == expected);
    std::fill(once.begin(), once.end(), 7u);
    s.run();
    CHECK(once == std::vector<std::uint32_t>(m, 7u));
  }
  Scheduler s(ctx, l.g);
  std::vector<std::uint32_t> too_many(m + 1);
  CHECK_THROWS_WITH(s.read_after_run(l.least, too_many.data(), m + 1), Catch::Contains("which holds 61"));
  CHECK_THROWS_WITH(s.read_after_run(l.pairs, too_many.data(), 1), Catch::Contains("variable-length"));
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

namespace {

// The work list of test_tree_* (stream_test.cl) over `n` values, with the deepest leaf
// of each input in its extra state while `deepest` is set.
struct Tree {
  StreamId values, counted;
  ParamId deepest;
};

Tree add_tree(StreamGraph& g, std::size_t n, std::size_t round_items, std::size_t round_group)
{
  Tree t{g.fixed("values", 4, n), g.variable("counted", 8, 16), g.param("deepest", 4)};
  Worklist list{"test_tree_seed", "test_tree_round", 8, 4, 2 * round_items, round_group};
  list.extra_state_bytes = 4;
  list.extra_state_while = t.deepest;
  g.pass("tree", {program, "test_tree_finish"})
      .launch_over(t.values)
      .refine(list)
      .emit(t.counted)
      .arg(buffer_of(t.values))
      .arg(count_of(t.values))
      .arg(param_of(t.deepest));
  return t;
}

std::uint32_t tree_depth(std::uint32_t value) { return cstreams::test::test_hash(value ^ 0x9e3779b9u) % 12u; }

// Input i's leaves (2^depth a tree, two trees for odd values), and with `with_depth`
// the count shifted left by four bits with the depth below.
std::vector<Pair> tree_counts(const std::vector<std::uint32_t>& v, bool with_depth)
{
  std::vector<Pair> counts;
  for (std::uint32_t i = 0; i < v.size(); ++i) {
    const std::uint32_t leaves = (v[i] & 1u ? 2u : 1u) << tree_depth(v[i]);
    counts.push_back({i, with_depth ? leaves << 4 | tree_depth(v[i]) : leaves});
  }
  return counts;
}

// Items over all rounds: a tree of depth d holds 2^(d+1) - 1 of them.
std::uint64_t tree_items(const std::vector<std::uint32_t>& v)
{
  std::uint64_t items = 0;
  for (const std::uint32_t value : v) items += (value & 1u ? 2u : 1u) * ((std::uint64_t(2) << tree_depth(value)) - 1);
  return items;
}

}  // namespace

TEST_CASE("a work list runs its rounds on the device, grows when it overflows and goes on, losing no item",
          "[runtime][scheduler][worklist][quick]")
{
  // Odd inputs are seeded with two first items (test_tree_seed), so the seed's own
  // appends count, and can overflow the list, too.
  // On a device that ends loops early (asked for here), rounds go over exactly their
  // items, read back one by one.
  Context limited(filter_from_environment(), 0, 4096);
  limited.programs().add_sources(test_kernel_sources());
  const bool bounded = GENERATE(false, true);
  // Rounds in the context's groups, and in small groups of their own.
  const std::size_t round_group = GENERATE(std::size_t(0), std::size_t(32));
  auto& ctx = bounded ? limited : cstreams::test::device();
  for (const std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(3001)}) {
    StreamGraph g;
    const Tree tree_streams = add_tree(g, n, ctx.work_group_size(), round_group);
    Scheduler s(ctx, g);
    s.set(tree_streams.deepest, cl_uint(0));
    const auto v = random_values(n, 23);
    const std::vector<Pair> expected = tree_counts(v, false);
    const std::uint64_t items = tree_items(v);
    unsigned deepest = 0;
    for (const std::uint32_t value : v) deepest = std::max(deepest, tree_depth(value) + 1);
    s.upload(tree_streams.values, v);
    for (int frame = 0; frame < 2; ++frame) {
      INFO("n = " << n << ", frame " << frame << (bounded ? ", bounded loops" : "") << ", round group " << round_group);
      s.run();
      CHECK(sorted(s.download<Pair>(tree_streams.counted)) == expected);
      const PassStats& tree = s.stats().passes.at(0);
      CHECK(tree.rounds == deepest);
      CHECK(tree.list_items == items);
      if (n > 1000) CHECK((frame == 0 ? tree.reruns > 0 : tree.reruns == 0));  // a list sized for the inputs overflows once
      if (n == 0) CHECK(tree.launches == 1);  // nothing to seed: only the emitting kernel
      if (bounded && n > 0) CHECK(s.stats().readbacks >= deepest);
      // One launch a round, the seed and the finish; an overflowing round runs once
      // more, and an overflowing seed once more with the round that found it so.
      if (bounded && n > 0) CHECK(tree.launches <= 2 + deepest + 2 * tree.reruns);
    }
  }
}

// The counts after a batch of rounds come back with the stage's counters, so a run that
// the last runs' rounds settle waits for one read; one that needs more rounds goes on
// from where its batch ended, and the pass emits again from the settled state.
TEST_CASE("a work list's counts come back with its stage's counters, and rounds beyond the last runs' go on",
          "[runtime][scheduler][worklist][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t n = 3001;
  const std::vector<std::uint32_t> deep = random_values(n, 37);
  std::vector<std::uint32_t> shallow;
  for (std::uint32_t seed = 41; shallow.size() < n; ++seed)
    for (const std::uint32_t value : random_values(n, seed))
      if (tree_depth(value) < 4 && shallow.size() < n) shallow.push_back(value);
  const auto rounds_of = [](const std::vector<std::uint32_t>& v) {
    unsigned deepest = 0;
    for (const std::uint32_t value : v) deepest = std::max(deepest, tree_depth(value) + 1);
    return deepest;
  };
  REQUIRE(rounds_of(shallow) < rounds_of(deep));
  StreamGraph g;
  const Tree tree_streams = add_tree(g, n, ctx.work_group_size(), 0);
  Scheduler s(ctx, g);
  s.set(tree_streams.deepest, cl_uint(0));
  // After the deep trees, shallow ones take a first batch as long as the deep ones'
  // (the most of the last runs'): their rounds end within it.
  const std::vector<std::pair<const std::vector<std::uint32_t>*, bool>> runs = {
      {&shallow, false}, {&shallow, true}, {&deep, false}, {&deep, true}, {&shallow, true}};
  for (const auto& [v, within_first_batch] : runs) {
    s.upload(tree_streams.values, *v);
    s.run();
    INFO((v == &deep ? "deep" : "shallow") << " trees" << (within_first_batch ? ", within the first batch" : ""));
    CHECK(sorted(s.download<Pair>(tree_streams.counted)) == tree_counts(*v, false));
    const PassStats& tree = s.stats().passes.at(0);
    CHECK(tree.rounds == rounds_of(*v));
    CHECK(tree.list_items == tree_items(*v));
    if (ctx.loop_trip_limit() != 0) CHECK(s.stats().readbacks >= tree.rounds);
    else if (within_first_batch) CHECK(s.stats().readbacks == 1);
    else CHECK(s.stats().readbacks > 1);
  }
}

// An optional mode's state (refine.cl's earliest box starts, kept only for steps that
// report earliest times alone) costs nothing while the mode is off.
TEST_CASE("a work list holds its extra state only while its parameter is set", "[runtime][scheduler][worklist][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t n = 3001;
  StreamGraph g;
  const Tree tree_streams = add_tree(g, n, ctx.work_group_size(), 0);
  Scheduler s(ctx, g);
  const auto v = random_values(n, 29);
  s.upload(tree_streams.values, v);
  const auto run = [&](cl_uint deepest) {
    s.set(tree_streams.deepest, deepest);
    s.run();
    CHECK(sorted(s.download<Pair>(tree_streams.counted)) == tree_counts(v, deepest != 0));
    return s.stats().passes.at(0).scratch_bytes;
  };
  run(0);  // the list grows to its size
  const std::size_t without = run(0);
  CHECK(run(1) == without + 4 * n);
  CHECK(run(0) == without + 4 * n);  // held, as the state is, until memory runs short
}

// Short of memory for its lists, a work list runs in slices of its inputs; its
// statistics add up the slices, as a step's would without them.
TEST_CASE("a work list run in slices reports the rounds and items of all of them", "[runtime][scheduler][worklist][quick]")
{
  const std::size_t n = 3001;
  const auto v = random_values(n, 31);
  const std::uint64_t items = tree_items(v);
  std::size_t peak = 0;
  unsigned whole_rounds = 0;
  for (const double share : {1.0, 0.5}) {
    Context context(filter_from_environment());
    context.programs().add_sources(test_kernel_sources());
    if (share < 1) context.set_memory_limit(std::size_t(share * double(peak)));
    StreamGraph g;
    const Tree tree_streams = add_tree(g, n, context.work_group_size(), 0);
    g.gather(tree_streams.counted);
    Scheduler s(context, g);
    s.set(tree_streams.deepest, cl_uint(0));
    s.upload(tree_streams.values, v);
    for (int frame = 0; frame < 2; ++frame) s.run();
    INFO("share " << share << " of the peak, " << peak << " bytes");
    // A slice's kernels number its inputs from 0: the counts alone must match.
    const auto leaves = [](const std::vector<Pair>& counted) {
      std::vector<std::uint32_t> c;
      for (const Pair& p : counted) c.push_back(p[1]);
      return sorted(c);
    };
    CHECK(leaves(s.download<Pair>(tree_streams.counted)) == leaves(tree_counts(v, false)));
    const PassStats& tree = s.stats().passes.at(0);
    CHECK(tree.list_items == items);
    if (share < 1) {
      CHECK(s.stats().slices > 1);
      CHECK(tree.rounds > whole_rounds);
    }
    peak = context.memory_high_water();
    whole_rounds = tree.rounds;
  }
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

TEST_CASE("a pass hands its input's buffer over to what it emits, and the device holds one of them",
          "[runtime][scheduler][quick]")
{
  auto& ctx = cstreams::test::device();
  for (const auto registration : {Registration::segmented_lock, Registration::global_atomic, Registration::lock_free}) {
    INFO("registration = " << to_string(registration));
    StreamId now, next;
    Scheduler s(ctx, begetting(now, next), {registration, true});
    // Generations grow about 2.6 times: the input's buffer soon holds too little and
    // a bigger one replaces it; bursts of 40 overflow a group's first segments.
    auto values = random_values(3000, 17);
    s.upload(now, values);
    for (int generation = 0; generation < 4; ++generation) {
      INFO("generation " << generation);
      s.run();
      values = begotten(values);
      CHECK(sorted(s.download<std::uint32_t>(next)) == sorted(values));
      const auto& streams = s.stats().streams;
      if (registration == Registration::segmented_lock) {
        CHECK(s.count(now) == 0);
        CHECK(streams.at(now.index).bytes == 0);
      }
      CHECK(streams.at(next.index).bytes >= values.size() * 4);
      // The input is spent: reading it again would lose what it held.
      if (registration == Registration::segmented_lock)
        CHECK_THROWS_WITH(s.run(), Catch::Contains("stream now gave its buffer to next"));
      s.swap(now, next);
    }
    // A smaller generation, uploaded, is packed into the buffer it came from.
    const std::size_t held = s.capacity(now);
    values = random_values(500, 19);
    s.upload(now, values);
    s.run();
    CHECK(sorted(s.download<std::uint32_t>(next)) == sorted(begotten(values)));
    if (registration == Registration::segmented_lock) CHECK(s.capacity(next) == held);
  }

  StreamGraph shared;
  const auto a = shared.variable("a", 4, 1), b = shared.variable("b", 4, 1), c = shared.variable("c", 4, 1);
  shared.pass("p", {program, "k"}).launch_over(a).emit(b).hand_over(a, b);
  shared.pass("q", {program, "k"}).launch_over(a).emit(c);
  CHECK_THROWS_WITH(shared.schedule(), Catch::Contains("pass q reads it too"));
  StreamGraph sizes;
  const auto x = sizes.variable("x", 4, 1), y = sizes.variable("y", 8, 1);
  sizes.pass("p", {program, "k"}).launch_over(x).emit(y).hand_over(x, y);
  CHECK_THROWS_WITH(sizes.schedule(), Catch::Contains("with items of the same size"));
}

// Short of memory, the pass registers through the global counter, straight into a buffer
// of the output's own; its input is spent all the same and goes back once the pass is
// done, as a hand-over leaves it, so that the passes after it have that room.
TEST_CASE("short of memory for segments, a pass that hands over still leaves the device one of the buffers",
          "[runtime][scheduler][quick]")
{
  StreamId now, next;
  const StreamGraph g = begetting(now, next);
  const auto values = random_values(30000, 23);
  const std::size_t floor = global_counter_peak(g, now, values, [](const Scheduler&) {});
  Context limited(filter_from_environment());
  limited.programs().add_sources(test_kernel_sources());
  limited.set_memory_limit(floor);
  INFO("limit " << floor << ", the global counter's peak");
  Scheduler s(limited, g, {Registration::segmented_lock, true});
  // The second run finds the output's buffer from the first.
  for (int run = 0; run < 2; ++run) {
    INFO("run " << run);
    s.upload(now, values);
    s.run();
    CHECK(s.stats().passes.at(0).segment_bytes == 0);
    CHECK(sorted(s.download<std::uint32_t>(next)) == sorted(begotten(values)));
    CHECK(s.stats().streams.at(now.index).bytes == 0);
    CHECK(s.count(now) == 0);
    CHECK_THROWS_WITH(s.run(), Catch::Contains("stream now gave its buffer to next"));
  }
}

TEST_CASE("invalid graphs are rejected with the names involved", "[runtime][scheduler][quick]")
{
  StreamGraph g;
  auto a = g.variable("a", 4, 1);
  auto b = g.variable("b", 4, 1);
  auto f = g.fixed("f", 4, 1);
  g.pass("p", {program, "k"}).launch_over(a).emit(b);
  g.pass("q", {program, "k"}).launch_over(b).emit(a);
  CHECK_THROWS_WITH(g.schedule(), Catch::Contains("cycle") && Catch::Contains("p") && Catch::Contains("q"));

  StreamGraph two;
  auto x = two.fixed("x", 4, 1);
  auto y = two.variable("y", 4, 1);
  two.pass("p", {program, "k"}).launch_over(x).emit(y);
  two.pass("q", {program, "k"}).launch_over(x).emit(y);
  CHECK_THROWS_WITH(two.schedule(), Catch::Contains("stream y is written by both p and q"));

  StreamGraph self;
  auto z = self.variable("z", 4, 1);
  self.pass("p", {program, "k"}).launch_over(z).emit(z);
  CHECK_THROWS_WITH(self.schedule(), Catch::Contains("both reads and writes stream z"));

  StreamGraph fixed_emit;
  auto u = fixed_emit.fixed("u", 4, 1);
  auto v = fixed_emit.fixed("v", 4, 1);
  fixed_emit.pass("p", {program, "k"}).launch_over(u).emit(v);
  CHECK_THROWS_WITH(fixed_emit.schedule(), Catch::Contains("emits into fixed-length stream v"));

  CHECK_THROWS_WITH(StreamGraph().fixed("odd", 6, 1), Catch::Contains("multiple of 4"));

  StreamGraph lives_on;
  const StreamId fixed = lives_on.fixed("fixed", 4, 1), kept = lives_on.variable("kept", 4, 1);
  CHECK_THROWS_WITH(lives_on.within_run(fixed), Catch::Contains("stream fixed is fixed-length"));
  lives_on.gather(kept);
  CHECK_THROWS_WITH(lives_on.within_run(kept), Catch::Contains("stream kept is gathered"));

  StreamGraph update_variable;
  auto w = update_variable.variable("w", 4, 1);
  update_variable.pass("p", {program, "k"}).launch_over(w).update(w);
  CHECK_THROWS_WITH(update_variable.schedule(), Catch::Contains("updates variable-length stream w"));

  StreamGraph update_and_emit;
  auto fx = update_and_emit.fixed("fx", 4, 1);
  auto out = update_and_emit.variable("out", 4, 1);
  update_and_emit.pass("p", {program, "k"}).launch_over(fx).update(fx).emit(out);
  CHECK_THROWS_WITH(update_and_emit.schedule(), Catch::Contains("may be rerun"));

  StreamGraph lower_variable;
  auto lv = lower_variable.variable("lv", 4, 1);
  lower_variable.pass("p", {program, "k"}).launch_items(4).lower(lv);
  CHECK_THROWS_WITH(lower_variable.schedule(), Catch::Contains("lowers variable-length stream lv"));

  StreamGraph wide_variant;
  auto wv = wide_variant.fixed("wv", 4, 1);
  wide_variant.pass("p", {program, "k"}).launch_over(wv).update(wv).instead_while(wide_variant.param("mode", 8), "k2");
  CHECK_THROWS_WITH(wide_variant.schedule(), Catch::Contains("pass p launches k2 while a parameter is set"));

  StreamGraph list_without_input;
  list_without_input.pass("p", {program, "k"}).launch_items(4).refine({"seed", "round", 8, 4, 64});
  CHECK_THROWS_WITH(list_without_input.schedule(), Catch::Contains("pass p refines a work list but lacks"));

  StreamGraph extra_behind_wide_param;
  auto inputs = extra_behind_wide_param.fixed("inputs", 4, 1);
  Worklist gated{"seed", "round", 8, 4, 64};
  gated.extra_state_bytes = 4;
  gated.extra_state_while = extra_behind_wide_param.param("mode", 8);
  extra_behind_wide_param.pass("p", {program, "k"}).launch_over(inputs).refine(gated);
  CHECK_THROWS_WITH(extra_behind_wide_param.schedule(), Catch::Contains("not behind a 4-byte parameter"));

  StreamGraph stop_unwritten;
  auto flag = stop_unwritten.fixed("flag", 4, 1);
  stop_unwritten.pass("p", {program, "k"}).launch_items(4).read(flag).stop_if(flag);
  CHECK_THROWS_WITH(stop_unwritten.schedule(), Catch::Contains("pass p stops the run on a flag it does not write"));
  (void)f;
}
