// The scheduler short of device memory: stages that fit or fail naming the allocation,
// passes in slices, and buffers handed over from a pass's input to its output.
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
