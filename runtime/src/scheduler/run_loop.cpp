#include "run_loop.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <exception>
#include <functional>

namespace cstreams::runtime {

// What a pass's work list borrows from the scheduler while its rounds run.
ListHost Scheduler::State::list_host(const PassState& p)
{
  return ListHost{context,
                  tl(),
                  counters.device(),
                  counters.list_counts(*p.list),
                  [this](Buffer& buffer, std::size_t& at, std::size_t bytes, const char* label) {
                    scratch.take_stage_scratch(buffer, at, bytes, label);
                  },
                  [this](Buffer& buffer, std::size_t& at) {
                    scratch.drop_stage_scratch(buffer, at);
                    buffer = Buffer();
                  },
                  [this, &p](const Kernel& k) { return bind_own_args(bindings(), *p.spec, k); },
                  p.spec->worklist->extra_state_bytes > 0 && nonzero(p.spec->worklist->extra_state_while),
                  stats.readbacks};
}

void Scheduler::State::execute(PassState& p, Redo redo)
{
  p.ran = true;
  if (!run_reads.empty())
    for (StreamId s : pass_outputs(*p.spec)) run_reads.requeue(s);
  std::size_t n = p.spec->launches_over_stream() ? state(p.spec->over).count : p.spec->items;
  for (StreamId s : p.spec->also_over) n += state(s).count;
  const std::size_t wg = work_group_of(*p.spec, context);
  const std::size_t global = round_up(n, wg);
  if (p.list && !p.list->settled) {
    ListHost host = list_host(p);
    refine(*p.spec, *p.list, p.stats, n, host);
    p.list->settled = true;
  }
  if (redo == Redo::full) launch(p, n, global, wg);
  registrar.register_outputs(p, n, global, wg);
}

// Sets the pass up to emit (its registration, its outputs' buffers, its segments or
// the global counter) and launches its kernel over `global` work-items.
void Scheduler::State::launch(PassState& p, std::size_t n, std::size_t global, std::size_t wg)
{
  // Once a run has fallen back it stays there: its reruns must not try segments again.
  p.mode = p.atomic_this_run ? Registration::global_atomic : registrar.registration_of(*p.spec);
  // Outputs that memory pressure or a new run took come back at their size before
  // any segments are taken: the segments then fit beside them, or the pass registers
  // through the global counter (a handed-over output gets its buffer once packed).
  for (auto& e : p.emitters)
    if (e.handed_from == StreamId{} && !(scratch.late() && state(e.stream).transient)) restore(e.stream);
  if (p.spec->culls()) restore(p.spec->cull_target);
  registrar.set_up(p, global);
  take_outputs(p, n);
  bind_args(bindings(), p, active(p));
  context.launch(active(p), global, wg, tl(), p.spec->name);
  ++p.stats.launches;
}

// Once the pass's registration is set up: the buffers its outputs and cull flags need
// before its kernel runs.
void Scheduler::State::take_outputs(PassState& p, std::size_t n)
{
  // Outputs the segments left to the global counter come back now; those that pack
  // late get their buffer once packed.
  for (auto& e : p.emitters) {
    if (!registrar.packs_late(p, e)) restore(e.stream);
    state(e.stream).released = 0;
  }
  if (p.spec->culls()) scratch.take_stage_scratch(p.keep, p.keep_at, n * sizeof(cl_uint), "cull flags");
  // Without segments to hand over, the output needs its own buffer: as large as the
  // input, a first guess that saves a rerun where the output is about its size.
  for (auto& e : p.emitters) {
    if (e.handed_from == StreamId{} || Registrar::hands_over(p, e)) continue;
    const std::size_t guess = state(e.stream).base + state(e.handed_from).count;
    if (state(e.stream).capacity < guess) scratch.with_memory([&] { buffers.grow(e.stream, guess); });
  }
}

void Scheduler::State::run()
{
  start_run();
  // However the run ends (a stop, an error), no pass's scratch is busy afterwards:
  // allocations between runs may take it.
  struct Idle {
    State& s;
    ~Idle()
    {
      s.busy.clear();
      s.running = false;
      s.buffers.set_from_arena(false);
    }
  } idle{*this};
  run_reads.requeue_all();
  running = true;
  buffers.set_from_arena(scratch.use_arena());
  for (auto& st : streams) {
    st.earlier = 0;
    st.partial = false;
  }
  std::vector<PassState*> stage;
  Failure failure;
  for (std::size_t i = 0; i < passes.size() && !failure; ++i) {
    if (i == slices.sliced_pass()) {
      if (!(failure = end_stage(stage))) failure.pass = i;
      break;
    }
    failure = step(passes[i], stage);
  }
  if (!failure) failure = end_stage(stage);
  if (failure) slices.go_on(failure);
  run_reads.finish([this](StreamId stream) -> const Buffer& { return state(stream).buffer; }, tl());
  scratch.end_run();
  stats_pending = true;
}

void Scheduler::State::start_run()
{
  timeline.clear();
  stats = RunStats{};
  stats_pending = false;
  for (auto& p : passes) {
    p.stats = PassStats{p.spec->name};
    p.atomic_this_run = false;
    p.handed_over = false;
    p.ran = false;
    if (p.list) {
      p.list->restart();
      p.list->held_bytes = 0;
    }
    for (auto& e : p.emitters) {
      e.segment_bytes = 0;
      e.exact_plan = false;
    }
  }
  scratch.start_run();
  for (auto& st : streams) st.peak_bytes = st.buffer.bytes();
  for (const auto& p : passes)
    for (const auto& handover : p.spec->handovers)
      if (!state(handover.first).handed_to.empty())
        throw Error("pass " + p.spec->name + " cannot run: stream " + spec(handover.first).name +
                    " gave its buffer to " + state(handover.first).handed_to +
                    " in the last run; upload to it or swap it first");
  for (const auto& p : passes)
    for (StreamId s : pass_outputs(*p.spec))
      if (spec(s).variable) state(s).known = false;
  counters.start_run();
}

// Flushes the stage and empties it; short of memory for a pass's outputs where the
// run may go on in slices from that pass, says so.
Failure Scheduler::State::end_stage(std::vector<PassState*>& stage)
{
  try {
    flush.run(stage);
  } catch (const DeviceMemoryExhausted&) {
    if (flush.failed_pass() == SIZE_MAX) throw;
    stage.clear();
    return {std::current_exception(), flush.failed_pass()};
  }
  stage.clear();
  return {};
}

// Executes pass `p` in the current stage; short of memory, the stage ends before it:
// once its counters are read, its passes' segments hold nothing needed, and `p` may
// take their memory. Where even that does not fit (`p` then holds nothing), or a
// flush has no room for a pass's outputs, says which pass.
Failure Scheduler::State::step(PassState& p, std::vector<PassState*>& stage)
{
  if (skipped(*p.spec)) return {};
  const std::size_t index = std::size_t(&p - passes.data());
  if (needs_new_stage(p))
    if (auto f = end_stage(stage)) return f;
  busy.assign(stage.begin(), stage.end());
  busy.push_back(&p);
  try {
    execute(p, Redo::full);
  } catch (const DeviceMemoryExhausted&) {
    if (stage.empty()) return {std::current_exception(), index};
    if (auto f = end_stage(stage)) return f;
    busy.assign(1, &p);
    flush.clear_counters(p);
    try {
      execute(p, Redo::full);
    } catch (const DeviceMemoryExhausted&) {
      return {std::current_exception(), index};
    }
  }
  if (p.spec->stops()) stop_if_raised(*p.spec);
  stage.push_back(&p);
  return {};
}

void Scheduler::State::stop_if_raised(const PassSpec& pass)
{
  std::uint32_t flag = 0;
  context.read(state(pass.stop_flag).buffer, &flag, sizeof flag, 0, tl());
  ++stats.readbacks;
  if (flag) throw RunStopped(pass.name);
}

}  // namespace cstreams::runtime
