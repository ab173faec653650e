#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include "scheduler/binding.hpp"
#include "scheduler/counters.hpp"
#include "scheduler/flush.hpp"
#include "scheduler/graph_layout.hpp"
#include "scheduler/late_packing.hpp"
#include "scheduler/pass_runner.hpp"
#include "scheduler/registrar.hpp"
#include "scheduler/run_reads.hpp"
#include "scheduler/scratch.hpp"
#include "scheduler/slices.hpp"
#include "scheduler/states.hpp"
#include "scheduler/statistics.hpp"
#include "scheduler/stream_buffers.hpp"
#include "scheduler/work_list.hpp"
#include "step_arena.hpp"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <functional>

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

Scheduler::Scheduler(Context& context, StreamGraph graph, SchedulerOptions options)
    : state_(std::make_unique<State>(context, std::move(graph), options))
{
}

Scheduler::~Scheduler() = default;

void Scheduler::run() { state_->run(); }
bool Scheduler::release_idle_scratch()
{
  state_->settle_stats();
  return state_->scratch.release_idle();
}
std::vector<Buffer> Scheduler::borrow_idle_scratch(const std::vector<std::size_t>& sizes) const
{
  return state_->scratch.borrow_idle(sizes);
}

void Scheduler::upload(StreamId stream, const void* items, std::size_t count)
{
  auto& s = *state_;
  s.settle_stats();
  auto& st = s.state(stream);
  // What the stream held is replaced, so it goes first; short of memory, idle scratch
  // goes too.
  if (count > st.capacity || !s.spec(stream).variable) s.scratch.with_memory([&] { s.buffers.grow(stream, count, false); });
  s.context.write(st.buffer, items, count * s.spec(stream).element_bytes);
  st.count = count;
  st.known = true;
  st.partial = false;
  st.handed_to.clear();
}

void Scheduler::on_counter_read(std::function<void()> work) { state_->flush.on_counter_read(std::move(work)); }

void Scheduler::read_after_run(StreamId stream, void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  if (spec.variable || count > s.state(stream).count)
    throw Error("cannot read " + std::to_string(count) + " items of stream " + spec.name + " after a run" +
                (spec.variable ? ": it is variable-length" : ", which holds " + std::to_string(s.state(stream).count)));
  s.run_reads.add(stream, items, count * spec.element_bytes);
}

void Scheduler::download(StreamId stream, void* items, std::size_t count) const
{
  auto& s = *state_;
  auto& st = s.state(stream);
  if (st.spent && count > 0)
    throw Error("cannot read stream " + s.spec(stream).name + ": it lives within a run, and went back once read");
  if (count > st.count)
    throw Error("cannot read " + std::to_string(count) + " items of stream " + s.spec(stream).name + ", which holds " +
                std::to_string(st.count));
  if (st.partial)
    throw Error("cannot read stream " + s.spec(stream).name + ": the last run went in " +
                std::to_string(s.stats.slices) + " slices to fit the device's memory, and the stream kept only the "
                "last one's items (StreamGraph::gather keeps them all)");
  s.context.read(st.buffer, items, count * s.spec(stream).element_bytes);
}

namespace {

void check_write(const StreamSpec& spec, std::size_t held, std::size_t first, std::size_t count)
{
  if (spec.variable || first + count > held)
    throw Error("cannot write items [" + std::to_string(first) + ", " + std::to_string(first + count) +
                ") of stream " + spec.name +
                (spec.variable ? ", which is variable-length" : ", which holds " + std::to_string(held)));
}

}  // namespace

void Scheduler::write(StreamId stream, std::size_t first, const void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  check_write(spec, s.state(stream).count, first, count);
  s.context.write(s.state(stream).buffer, items, count * spec.element_bytes, first * spec.element_bytes);
}

Handle<cl_event> Scheduler::write_queued(StreamId stream, std::size_t first, const void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  check_write(spec, s.state(stream).count, first, count);
  return s.context.write_queued(s.state(stream).buffer, items, count * spec.element_bytes, first * spec.element_bytes);
}

void Scheduler::copy(StreamId source, std::size_t source_first, StreamId destination, std::size_t destination_first,
                     std::size_t count)
{
  auto& s = *state_;
  const auto &from = s.spec(source), &to = s.spec(destination);
  if (from.element_bytes != to.element_bytes || source_first + count > s.state(source).count ||
      destination_first + count > s.state(destination).count || to.variable)
    throw Error("cannot copy " + std::to_string(count) + " items from stream " + from.name + " to " + to.name);
  s.context.copy(s.state(source).buffer, s.state(destination).buffer, count * from.element_bytes,
                 source_first * from.element_bytes, destination_first * to.element_bytes);
}

std::size_t Scheduler::count(StreamId stream) const { return state_->state(stream).count; }
std::size_t Scheduler::capacity(StreamId stream) const { return state_->state(stream).capacity; }

void Scheduler::set_capacity(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (!s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is fixed-length; resize it instead");
  s.settle_stats();
  auto& st = s.state(stream);
  const std::size_t kept = std::min(st.count, items);
  const Buffer old = st.buffer;  // held until its first items are copied over
  s.scratch.with_memory([&] { s.buffers.allocate(stream, items); });
  if (kept > 0) s.context.copy(old, st.buffer, kept * s.spec(stream).element_bytes);
  st.count = kept;
  st.handed_to.clear();
}

void Scheduler::set_limit(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (!s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is fixed-length and never grows");
  s.state(stream).limit = items;
  if (s.state(stream).capacity > items) set_capacity(stream, items);
}

void Scheduler::resize(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is variable-length; its passes size it");
  s.settle_stats();
  if (items != s.state(stream).capacity) s.buffers.allocate(stream, items);
  s.state(stream).count = items;
}

void Scheduler::swap(StreamId a, StreamId b)
{
  auto& s = *state_;
  const auto &sa = s.spec(a), &sb = s.spec(b);
  if (sa.element_bytes != sb.element_bytes || sa.variable != sb.variable)
    throw Error("streams " + sa.name + " and " + sb.name + " differ in element size or kind and cannot swap");
  s.settle_stats();
  auto &x = s.state(a), &y = s.state(b);
  std::swap(x.buffer, y.buffer);
  std::swap(x.count, y.count);
  std::swap(x.capacity, y.capacity);
  std::swap(x.known, y.known);
  std::swap(x.partial, y.partial);
  std::swap(x.handed_to, y.handed_to);
  std::swap(x.arena_at, y.arena_at);
}

const Buffer& Scheduler::buffer(StreamId stream) const { return state_->state(stream).buffer; }

void Scheduler::set(ParamId param, const void* bytes, std::size_t size)
{
  auto& s = *state_;
  const auto& spec = s.graph.params().at(param.index);
  if (size != spec.bytes)
    throw Error("parameter " + spec.name + " takes " + std::to_string(spec.bytes) + " bytes, not " + std::to_string(size));
  auto& v = s.params[param.index];
  v.assign(static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + size);
}

const StreamGraph& Scheduler::graph() const { return state_->graph; }

std::vector<std::string> Scheduler::execution_order() const
{
  std::vector<std::string> names;
  for (const auto& p : state_->passes) names.push_back(p.spec->name);
  return names;
}

const RunStats& Scheduler::stats() const
{
  state_->settle_stats();
  return state_->stats;
}
Registration Scheduler::registration() const { return state_->options.registration; }

}  // namespace cstreams::runtime
