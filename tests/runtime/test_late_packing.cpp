// Outputs packed late (scheduler/late_packing.cpp): buffers handed over from a pass's
// input to its output, and inputs that go back once read.
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
