#pragma once
// Scheduler::State, the run loop, and the parts it owns. Private to the runtime:
// scheduler.cpp, the public API, calls it; run_loop.cpp holds its members.
#include "../step_arena.hpp"
#include "binding.hpp"
#include "counters.hpp"
#include "flush.hpp"
#include "graph_layout.hpp"
#include "late_packing.hpp"
#include "pass_runner.hpp"
#include "registrar.hpp"
#include "run_reads.hpp"
#include "scratch.hpp"
#include "slices.hpp"
#include "states.hpp"
#include "statistics.hpp"
#include "stream_buffers.hpp"
#include "work_list.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace cstreams::runtime {

// The run loop: passes executed in order, in stages that end where a pass reads what
// the stage has yet to count, each stage flushed (Flush); the parts below own the rest
// (docs/ARCHITECTURE.md draws them). Owns executing a pass (its launch, its work list's
// rounds) and the stages; decides nothing about memory, registration or reruns.
struct Scheduler::State final : PassRunner {
  State(Context& c, StreamGraph g, SchedulerOptions o)
      : context(c), graph(std::move(g)), options(o), arena(c),
        buffers(c, graph, arena, streams, tl()),
        scratch(c, arena, buffers, passes, busy, running, o.step_arena), slots(lay_out()),
        counters(c, passes, slots, tl()), registrar(c, o.registration, buffers, scratch, counters, tl()),
        slices({c, *this, counters, registrar, scratch, buffers, passes, busy, stats}),
        packer(buffers, scratch, registrar, counters, arena, passes, slices.sliced_pass()),
        flush({*this, counters, registrar, packer, scratch, buffers, run_reads, passes, busy, stats})
  {
  }

  Context& context;
  StreamGraph graph;
  SchedulerOptions options;
  Timeline timeline;
  RunStats stats;
  // Whether `stats` still waits for the last run's figures, collected on the first
  // call for them (Scheduler::stats) rather than as the run ends: a caller's next
  // launch then goes first.
  bool stats_pending = false;
  std::vector<StreamState> streams;
  std::vector<PassState> passes;  // execution order
  std::vector<std::vector<unsigned char>> params;
  // Passes whose scratch may hold what is still needed: while a stage runs, its passes
  // and the pass being executed; once its counters are read, those that overflowed.
  std::vector<const PassState*> busy;
  bool running = false;  // within run()
  StepArena arena;
  StreamBuffers buffers;
  Scratch scratch;
  std::uint32_t slots;  // counter words of the streams and emitters
  Counters counters;
  Registrar registrar;
  RunReads run_reads{context};  // Scheduler::read_after_run
  Slices slices;
  LatePacker packer;
  Flush flush;

  Timeline* tl() { return options.profile ? &timeline : nullptr; }
  const StreamSpec& spec(StreamId s) const { return graph.stream(s); }
  StreamState& state(StreamId s) { return streams.at(s.index); }

  std::uint32_t lay_out()
  {
    params.resize(graph.params().size());
    return runtime::lay_out(context, graph, options.registration, buffers, passes);
  }

  // Whether a 4-byte parameter is set and not 0.
  bool nonzero(ParamId param) const
  {
    const auto& bytes = params.at(param.index);
    return bytes.size() == 4 && (bytes[0] | bytes[1] | bytes[2] | bytes[3]) != 0;
  }
  bool skipped(const PassSpec& spec) const override { return spec.conditional() && !nonzero(spec.runs_while); }

  // Where a launch's arguments come from (scheduler/binding.hpp).
  Bindings bindings() const
  {
    return {graph, streams, params, counters.device(), registrar.no_plan(), registrar.planner()};
  }
  // The kernel an execution of p launches: its variant while the variant's parameter is set.
  const Kernel& active(const PassState& p) const
  {
    return p.active(!p.spec->variant_kernel.empty() && nonzero(p.spec->variant_while));
  }

  // A stream that memory pressure or a new run took comes back at its size.
  void restore(StreamId s)
  {
    auto& st = state(s);
    if (st.released > st.capacity) scratch.with_memory([&] { buffers.grow(s, st.released, false); });
    st.released = 0;
  }

  ListHost list_host(const PassState& p) override;
  void execute(PassState& p, Redo redo) override;
  void launch(PassState& p, std::size_t n, std::size_t global, std::size_t wg);
  void take_outputs(PassState& p, std::size_t n);
  void run();
  void start_run();
  Failure end_stage(std::vector<PassState*>& stage) override;
  Failure step(PassState& p, std::vector<PassState*>& stage) override;
  bool needs_new_stage(const PassState& p) const
  {
    return std::any_of(p.inputs.begin(), p.inputs.end(),
                       [&](StreamId s) { return spec(s).variable && !streams.at(s.index).known; });
  }
  void stop_if_raised(const PassSpec& pass);

  // Before a change to what the last run's figures describe (a stream's size or buffer,
  // the idle scratch).
  void settle_stats()
  {
    if (!stats_pending) return;
    stats_pending = false;
    collect_stats(stats, {graph, timeline, registrar.shared_scratch_bytes(), scratch.idle_segments(), arena, streams,
                          passes});
  }
};

}  // namespace cstreams::runtime
