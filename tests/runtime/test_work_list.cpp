// Work lists (scheduler/work_list.cpp): rounds on the device, growth and replay, counts
// with the stage's counters, extra state behind a parameter, and slices.
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

namespace {

// The work list of test_tree_* (stream_test.cl) over `n` values, with the deepest leaf
// of each input in its extra state while `deepest` is set.
struct Tree {
  StreamId values, counted;
  ParamId deepest;
};

Tree add_tree(StreamGraph& g, std::size_t n, std::size_t round_items, std::size_t round_group,
              std::size_t most_bytes = 0)
{
  Tree t{g.fixed("values", 4, n), g.variable("counted", 8, 16), g.param("deepest", 4)};
  Worklist list{"test_tree_seed", "test_tree_round", 8, 4, 2 * round_items, round_group};
  list.most_bytes = most_bytes;
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
// report earliest times alone) costs nothing while the mode is off. In the step arena the
// state goes back with its stage, so a run without the mode holds none of it again;
// without the arena it is held from run to run, as the lists are, until memory runs short.
TEST_CASE("a work list holds its extra state only while its parameter is set", "[runtime][scheduler][worklist][quick]")
{
  auto& ctx = cstreams::test::device();
  const std::size_t n = 3001;
  for (const bool arena : {true, false}) {
    INFO((arena ? "in the step arena" : "without the step arena"));
    StreamGraph g;
    const Tree tree_streams = add_tree(g, n, ctx.work_group_size(), 0);
    Scheduler s(ctx, g, {Registration::segmented_lock, true, arena});
    const auto v = random_values(n, 29);
    s.upload(tree_streams.values, v);
    const auto run = [&](cl_uint deepest) {
      s.set(tree_streams.deepest, deepest);
      s.run();
      CHECK(sorted(s.download<Pair>(tree_streams.counted)) == tree_counts(v, deepest != 0));
      return s.stats().passes.at(0).scratch_bytes;
    };
    // The lists grow to their size, then (in the arena) settle at what a run needs.
    run(0);
    run(0);
    const std::size_t without = run(0);
    CHECK(run(1) == without + 4 * n);
    CHECK(run(0) == (arena ? without : without + 4 * n));
  }
}

// In the step arena a work list's state and lists take the place of what an earlier
// stage held and gave back (here an expansion's segments, in the stage before the list's
// pass, which reads its output), so a settled run holds less than one whose lists are
// buffers of their own, and counts the same. Each on a context of its own, so that what
// is in use is the scheduler's.
TEST_CASE("a work list in the step arena takes the place an earlier stage gave back",
          "[runtime][scheduler][worklist][quick]")
{
  const std::size_t n = 2000, m = 200000;
  const auto v = random_values(n, 31), w = random_values(m, 37);
  const auto settled = [&](bool arena) {
    Context own(filter_from_environment());
    own.programs().add_sources(test_kernel_sources());
    StreamGraph g;
    const StreamId values = g.fixed("values", 4, n), more = g.fixed("more", 4, m);
    const StreamId pairs = g.variable("pairs", 8, 16), counted = g.variable("counted", 8, 16);
    const ParamId deepest = g.param("deepest", 4);
    g.pass("expand", {program, "test_expand"}).launch_over(more).emit(pairs).arg(buffer_of(more)).arg(count_of(more));
    Worklist list{"test_tree_seed", "test_tree_round", 8, 4, 2 * own.work_group_size(), 0};
    g.pass("tree", {program, "test_tree_finish"})
        .launch_over(values)
        .read(pairs)
        .refine(list)
        .emit(counted)
        .arg(buffer_of(values))
        .arg(count_of(values))
        .arg(param_of(deepest));
    Scheduler s(own, g, {Registration::segmented_lock, true, arena});
    s.upload(values, v);
    s.upload(more, w);
    s.set(deepest, cl_uint(0));
    for (int frame = 0; frame < 4; ++frame) s.run();
    own.reset_memory_high_water();
    s.run();
    CHECK(sorted(s.download<Pair>(counted)) == tree_counts(v, false));
    CHECK(sorted(s.download<Pair>(pairs)) == sorted(cstreams::test::reference(w).pairs));
    const std::size_t list_bytes = s.stats().passes.at(1).scratch_bytes;
    return std::pair{own.memory_high_water(), list_bytes};
  };
  const auto [with, list_bytes] = settled(true);
  const std::size_t without = settled(false).first;
  INFO("high water with the arena " << with << ", without " << without << "; the work list held " << list_bytes);
  // The list's memory is shared but for what it holds beyond the segments' place.
  CHECK(with + list_bytes / 2 < without);
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

// A work list that may take less than its inputs need (Worklist::most_bytes) runs in
// slices of them, as where the device has no memory left, and the slices together
// count every leaf; the next run starts in slices at once. A single input is refined
// whole whatever the list may take. The kernels the slices run are built with the
// scheduler: a step that slices compiles nothing.
TEST_CASE("a work list held under its most bytes runs in slices, losing no item",
          "[runtime][scheduler][worklist][quick]")
{
  const std::size_t n = 3001;
  const auto v = random_values(n, 37);
  const auto leaves = [](const std::vector<Pair>& counted) {
    std::vector<std::uint32_t> c;
    for (const Pair& p : counted) c.push_back(p[1]);
    return sorted(c);
  };
  // The state (4 bytes an input) and two lists of 8-byte items for the inputs: about
  // 66 KB for all of them, 23 KB for a slice of 1024.
  for (const std::size_t most : {std::size_t(0), std::size_t(40000)}) {
    INFO("most bytes " << most);
    auto& ctx = cstreams::test::device();
    StreamGraph g;
    const Tree tree_streams = add_tree(g, n, ctx.work_group_size(), 0, most);
    g.gather(tree_streams.counted);
    Scheduler s(ctx, g);
    s.set(tree_streams.deepest, cl_uint(0));
    s.upload(tree_streams.values, v);
    const std::size_t programs = ctx.programs().programs_built();
    for (int frame = 0; frame < 2; ++frame) {
      s.run();
      CHECK(ctx.programs().programs_built() == programs);
      CHECK(leaves(s.download<Pair>(tree_streams.counted)) == leaves(tree_counts(v, false)));
      CHECK(s.stats().passes.at(0).list_items == tree_items(v));
      if (most) CHECK(s.stats().slices >= 2);
      else CHECK(s.stats().slices == 1);
    }
    s.upload(tree_streams.values, std::vector<std::uint32_t>{v[0]});
    s.run();
    CHECK(leaves(s.download<Pair>(tree_streams.counted)) == leaves(tree_counts({v[0]}, false)));
  }
}
