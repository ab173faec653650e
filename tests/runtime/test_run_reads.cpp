// Fixed streams read back as a run ends (runtime/src/scheduler/run_reads.*).
#include "scheduler_graphs.hpp"

#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

using namespace cstreams::runtime;
using namespace cstreams::test;

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
