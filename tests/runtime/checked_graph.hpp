#pragma once
// A graph of every kind of pass (expand, square, cull, split) run twice against the host's
// reference: the items of every output, in order where lock-free registration keeps it,
// and a second run that reruns nothing. Shared by the run loop's and the flush's tests.
#include "scheduler_graphs.hpp"

#include <cstreams/runtime/scheduler.hpp>

#include <catch2/catch.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cstreams::test {

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

inline void check_graph(std::size_t n, Registration registration, std::size_t capacity, std::uint32_t seed)
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

}  // namespace cstreams::test
