// Runs in slices (scheduler/slices.cpp): short of memory for what a pass emits, the rest
// of the graph runs over slices of its input and gathers what the graph asks for.
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
