// Memory within a run (scheduler/scratch.cpp): the step arena that what lives within a
// run shares, idle segments handed from stage to stage, and stages under a memory limit
// that fit by giving scratch back or fail naming the allocation.
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
