#pragma once
// Graphs of the test kernels (tests/kernels/stream_test.cl) and what the scheduler's
// test files check them with.
#include "../support/test_device.hpp"
#include "stream_test_reference.hpp"

#include <cstreams/runtime/scheduler.hpp>

#include <algorithm>
#include <random>
#include <vector>

const cstreams::runtime::SourceSet& test_kernel_sources();

namespace cstreams::test {

using namespace cstreams::runtime;

inline const char* const program = "kernels/stream_test.cl";

inline PassSpec& add_square(StreamGraph& g, StreamId values, StreamId squares)
{
  return g.pass("square", {program, "test_square"})
      .launch_over(values)
      .write(squares)
      .arg(buffer_of(values))
      .arg(count_of(values))
      .arg(buffer_of(squares));
}

inline PassSpec& add_split(StreamGraph& g, StreamId pairs, StreamId squares, StreamId even, StreamId odd)
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

inline std::vector<std::uint32_t> random_values(std::size_t n, std::uint32_t seed)
{
  std::mt19937 rng(seed);
  std::vector<std::uint32_t> v(n);
  for (auto& x : v) x = rng();
  return v;
}

// The most memory a run of `g` holds (twice, from `values`) on a context of its own,
// every pass registering through the global counter; `check` sees the scheduler after.
template <class Check>
inline std::size_t global_counter_peak(const StreamGraph& g, StreamId values, const std::vector<std::uint32_t>& v, Check check)
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
inline std::vector<std::uint32_t> begotten(const std::vector<std::uint32_t>& values)
{
  std::vector<std::uint32_t> next;
  for (const std::uint32_t v : values)
    for (std::uint32_t k = 0; k < cstreams::test::test_emit_count(v); ++k)
      next.push_back(cstreams::test::test_hash(v + k + 1));
  return next;
}

// One pass that begets `now`'s next generation into `next`, handing `now`'s buffer over.
inline StreamGraph begetting(StreamId& now, StreamId& next)
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


// values -> (expand, which lowers `least` to the least hash of each residue of the
// values mod m) pairs, after `clear` writes `least`; then `copy` copies `least`, behind
// the pairs where asked (a stage with no counters to read).
struct LoweringGraph {
  static constexpr std::size_t n = 10007, m = 61;
  StreamGraph g;
  StreamId values, least, copied, pairs;
};

inline LoweringGraph lowering_graph(bool copy_behind_pairs)
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

inline std::vector<std::uint32_t> least_hashes(const std::vector<std::uint32_t>& values)
{
  std::vector<std::uint32_t> least(LoweringGraph::m, 0xffffffffu);
  for (std::uint32_t x : values) least[x % least.size()] = std::min(least[x % least.size()], cstreams::test::test_hash(x));
  return least;
}

}  // namespace cstreams::test
