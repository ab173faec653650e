#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/details/segment_plan.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include "scheduler/binding.hpp"
#include "scheduler/growth.hpp"
#include "scheduler/run_reads.hpp"
#include "scheduler/segment_pool.hpp"
#include "scheduler/states.hpp"
#include "scheduler/statistics.hpp"
#include "scheduler/stream_buffers.hpp"
#include "scheduler/work_list.hpp"
#include "step_arena.hpp"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <functional>
#include <numeric>

namespace cstreams::runtime {

namespace {

using details::SegmentPlanner;

enum class Redo { none, pack, full };

// Segments of an output packed late up to which its merge adds up the counts before each
// group's segments itself (a few loads a work-item) rather than after a scan's launch.
constexpr std::size_t own_offsets_most_segments = 8192;

// Segmented lock: the most segments one group of the merge copies (CS_MERGE_SEGMENTS
// in cl_kernels/runtime/compact.cl).
constexpr std::size_t most_merged_per_group = 64;

std::string registration_define(Registration r)
{
  return "-DCS_REGISTRATION=" + std::to_string(int(r));
}

}  // namespace

struct Scheduler::State {
  State(Context& c, StreamGraph g, SchedulerOptions o)
      : context(c), graph(std::move(g)), options(o), planner(o.registration, c.work_group_size()), scan(c),
        merge_interleaved(c.programs().kernel("runtime/compact.cl", "cs_merge_interleaved")),
        merge_planned(c.programs().kernel("runtime/compact.cl", "cs_merge_planned")),
        no_plan(c, sizeof(cl_uint), "registration plan"), arena(c)
  {
  }

  Context& context;
  StreamGraph graph;
  SchedulerOptions options;
  SegmentPlanner planner;
  Scan scan;
  Kernel merge_interleaved, merge_planned;
  Buffer offsets;  // lock-free segments' offsets
  Buffer no_plan;  // one zero: the plan of segments that have none
  Buffer counters;
  // The next run's counters, cleared during this run at its first counter read, where
  // the device is busy: a run that starts with them clear starts with its first kernel
  // (a clear first held an H200's first launch back by 10-20 us).
  Buffer next_counters;
  bool next_counters_clear = false;
  std::vector<std::uint32_t> host_counters;
  // A work list's counts as the last counter read (or list read) brought them.
  std::uint32_t* counts_read(const ListState& l) { return host_counters.data() + l.counts_at; }
  RunReads run_reads{context};  // Scheduler::read_after_run
  std::function<void()> before_counter_read;  // Scheduler::on_counter_read
  std::vector<StreamState> streams;
  std::vector<PassState> passes;  // execution order
  std::vector<std::vector<unsigned char>> params;
  Timeline timeline;
  RunStats stats;
  // Whether `stats` still waits for the last run's figures, collected on the first
  // call for them (Scheduler::stats) rather than as the run ends: a caller's next
  // launch then goes first.
  bool stats_pending = false;
  StepArena arena;
  StreamBuffers buffers{context, graph, arena, streams};
  // Until memory runs short: from then on, what lives within a run is held pass by
  // pass (segments in the idle pool, streams in buffers of their own), so that any of
  // it that is idle can go back.
  bool use_arena = options.step_arena;
  bool pressed = false;
  // This run packs transient outputs late (packs_late): without a memory budget, or
  // into an arena whose start found room for it twice over. A stream packed late is
  // allocated while its segments hold its items, when the pass can no longer fall back
  // to the global counter: under a budget it would run in slices instead.
  bool late = false;

  Timeline* tl() { return options.profile ? &timeline : nullptr; }
  const StreamSpec& spec(StreamId s) const { return graph.stream(s); }
  StreamState& state(StreamId s) { return streams.at(s.index); }
  const StreamState& state(StreamId s) const { return streams.at(s.index); }
  std::size_t words(StreamId s) const { return spec(s).element_bytes / 4; }

  // A stream's buffer at a size or grown (scheduler/stream_buffers.hpp): within a run, a
  // transient stream's from the arena.
  void allocate(StreamId s, std::size_t items) { buffers.allocate(s, items, running && use_arena); }
  void drop(StreamState& st) { buffers.drop(st); }
  void grow(StreamId s, std::size_t needed, bool slack = true)
  {
    buffers.grow(s, needed, slack, running && use_arena, slices_left, tl());
  }

  void restore(StreamId s)
  {
    auto& st = state(s);
    if (st.released > st.capacity) with_memory([&] { grow(s, st.released, false); });
    st.released = 0;
  }
  Registration registration_of(const PassSpec& spec) const
  {
    return spec.any_order ? Registration::global_atomic : options.registration;
  }

  // Passes whose scratch may hold what is still needed: while a stage runs, its passes
  // and the pass being executed; once its counters are read, those that overflowed.
  std::vector<const PassState*> busy;

  SegmentPool segment_pool;  // segments between stages, without the arena

  // Segments of at least `bytes` for e: from the arena, else from the pool, else new.
  void take_segments(EmitterState& e, std::size_t bytes)
  {
    if (use_arena) {
      e.items = arena.take(bytes, "registration segments", e.arena_at);
      return;
    }
    const std::size_t limit = context.memory_limit(), room = limit - std::min(limit, context.memory_in_use());
    if (auto idle = segment_pool.take(bytes, room)) {
      e.items = std::move(*idle);
      return;
    }
    with_memory([&] { e.items = Buffer(context, std::max<std::size_t>(bytes, 1), "registration segments"); });
  }

  std::vector<Buffer> borrow_idle_scratch(const std::vector<std::size_t>& sizes) const
  {
    return use_arena ? arena.lend(sizes) : std::vector<Buffer>{};
  }

  void give_back_segments(EmitterState& e)
  {
    if (e.arena_at != StepArena::none) drop_segments(e);
    else if (e.items) segment_pool.give_back(std::move(e.items));
  }

  // Segments, with their counts where those came from the arena too.
  void drop_segments(EmitterState& e)
  {
    arena.give_back(e.arena_at);
    e.items = Buffer();
    drop_stage_scratch(e.counts, e.counts_at);
  }

  // Scratch of at least `bytes` that the stage alone reads: from the arena, given back
  // with the stage's segments; without it, held from run to run.
  void take_stage_scratch(Buffer& buffer, std::size_t& at, std::size_t bytes, const char* label)
  {
    if (!use_arena) {
      drop_stage_scratch(buffer, at);
      with_memory([&] { ensure_capacity(context, buffer, bytes, label); });
      return;
    }
    if (at != StepArena::none && buffer.bytes() >= bytes) return;
    arena.give_back(at);
    buffer = Buffer();
    with_memory([&] { buffer = arena.take(bytes, label, at); });
  }

  void drop_stage_scratch(Buffer& buffer, std::size_t& at)
  {
    if (at == StepArena::none) return;
    arena.give_back(at);
    buffer = Buffer();
  }

  // After a stage's counters are read and nothing of it overflowed.
  void give_back_segments(const std::vector<PassState*>& stage)
  {
    std::vector<std::size_t> needs;
    for (PassState* p : stage) {
      for (auto& e : p->emitters)
        if (e.items) {
          needs.push_back(e.needed);
          give_back_segments(e);
        }
      drop_stage_scratch(p->keep, p->keep_at);
    }
    segment_pool.stage_done(std::move(needs));
  }

  // Runs `allocate`; when the device has no memory left, gives back the scratch of
  // every pass that holds nothing in it now (done already, or not run yet this run; it
  // is allocated again when the pass next runs) and tries once more.
  template <class Allocate> void with_memory(Allocate allocate)
  {
    allocate_making_room(allocate, [this] { return release_idle_scratch(); });
  }

  // Registration segments (with their counts), cull flags and work lists of the passes
  // outside the stage being run, and within a run the streams of the passes yet to run.
  // Their plans stay (a word a group), so that segments allocated again are planned
  // ones, and so do their offsets, which a pass done in the stage being flushed is yet
  // to adopt as its plan. Returns whether any memory was given back.
  bool release_idle_scratch()
  {
    bool freed = false;
    const auto release = [&](Buffer& b) {
      if (b) {
        b = Buffer();
        freed = true;
      }
    };
    pressed = true;
    if (segment_pool.release()) freed = true;
    for (auto& other : passes) {
      if (std::find(busy.begin(), busy.end(), &other) != busy.end()) continue;
      for (auto& e : other.emitters) {
        if (e.items || e.counts) freed = true;
        drop_segments(e);
        release(e.counts);
      }
      if (other.keep) freed = true;
      drop_stage_scratch(other.keep, other.keep_at);
      release(other.keep);
      // What a pass yet to run this run will emit holds the last run's items, which
      // nothing reads before it; it comes back at its size when the pass runs.
      if (running && !other.ran)
        for (StreamId s : other.spec->emits) {
          auto& st = state(s);
          if (!st.buffer) continue;
          st.released = std::max(st.released, st.capacity);
          drop(st);
          freed = true;
        }
      if (auto& l = other.list) {
        release(l->state);
        for (auto& list : l->lists) release(list);
        l->released = std::max(l->released, l->capacity);
        l->capacity = 0;
      }
    }
    if (arena.release()) freed = true;
    return freed;
  }

  // Grows a stream that pass `p` emits into, giving back registration segments when
  // the device has no memory left for it: first those of idle passes (with_memory),
  // then those that `make_room` gives back, then the pass's own, which then emits this
  // run through the global counter. Returns whether the pass must run again in full. A
  // stream that does not fit even then is an error.
  template <class MakeRoom> bool grow_output(PassState& p, StreamId s, std::size_t needed, MakeRoom make_room)
  {
    try {
      allocate_making_room([&] { with_memory([&] { grow(s, needed); }); }, make_room);
      return false;
    } catch (const DeviceMemoryExhausted&) {
    }
    bool rerun = false;
    if (p.mode != Registration::global_atomic) {
      fall_back_to_global_counter(p);
      rerun = true;
    }
    try {
      grow(s, needed);
    } catch (const DeviceMemoryExhausted&) {
      grow(s, needed, false);
    }
    return rerun;
  }

  // Whether a 4-byte parameter is set and not 0.
  bool nonzero(ParamId param) const
  {
    const auto& bytes = params.at(param.index);
    return bytes.size() == 4 && (bytes[0] | bytes[1] | bytes[2] | bytes[3]) != 0;
  }

  // Where a launch's arguments come from (scheduler/binding.hpp).
  Bindings bindings() const { return {graph, streams, params, counters, no_plan, planner}; }
  unsigned bind_own_args(const PassSpec& spec, const Kernel& k) const { return runtime::bind_own_args(bindings(), spec, k); }

  // The kernel an execution of p launches: its variant while the variant's parameter is set.
  const Kernel& active(const PassState& p) const
  {
    return p.active(!p.spec->variant_kernel.empty() && nonzero(p.spec->variant_while));
  }

  void bind_args(const PassState& p) const { runtime::bind_args(bindings(), p, active(p)); }


  // Segments follow the last run, so one burst (a first step searched from the roots,
  // say) can ask for more memory than the device has, or than is left of it. Then the
  // pass registers this run through one global counter instead: slower under
  // contention, but its memory is the stream itself.
  bool segments_fit(const EmitterState& e, std::size_t global) const
  {
    const std::uint64_t items = planner.segment_items(e, planner.segment_count(e, global));
    if (items > 0xffffffffu) return false;  // the kernels index segments with 32 bits
    const std::size_t bytes = std::size_t(items) * spec(e.stream).element_bytes;
    const std::size_t in_use = context.memory_in_use(), limit = context.memory_limit();
    return bytes <= context.device().max_allocation && in_use <= limit && bytes <= limit - in_use;
  }

  std::size_t group_of(const PassSpec& spec) const
  {
    const std::size_t wg = context.work_group_size();
    return spec.group ? std::min(spec.group, wg) : wg;
  }

  // This run of the pass registers through one global counter, and its segments'
  // memory goes back.
  void fall_back_to_global_counter(PassState& p)
  {
    for (auto& e : p.emitters) {
      drop_segments(e);
      e.segment_bytes = 0;
    }
    if (!p.atomic_kernel.get()) {
      p.atomic_kernel = build_kernel(*p.spec, Registration::global_atomic);
      if (!p.spec->variant_kernel.empty())
        p.atomic_variant = build_kernel(*p.spec, Registration::global_atomic, p.spec->variant_kernel);
    }
    p.mode = Registration::global_atomic;
    p.atomic_this_run = true;
  }

  void prepare_segments(EmitterState& e, std::size_t global)
  {
    planner.prepare(e, global);
    const std::size_t bytes = std::size_t(planner.segment_items(e, e.segments)) * spec(e.stream).element_bytes;
    // Segments still held from this run's overflowing execution are written anew: kept
    // while they fit.
    if (e.items.bytes() < bytes) give_back_segments(e);
    if (!e.items) take_segments(e, bytes);
    e.needed = bytes;
    e.segment_bytes = e.items.bytes();
    // Segmented lock: each spilled item's group and rank follow the counts.
    take_stage_scratch(e.counts, e.counts_at, (e.segments + 2 * e.pool) * sizeof(cl_uint), "registration counts");
  }

  // What a pass's work list borrows from the scheduler while its rounds run.
  ListHost list_host(const PassState& p)
  {
    return ListHost{context,
                    tl(),
                    counters,
                    counts_read(*p.list),
                    [this](const std::function<void()>& allocate) { with_memory(allocate); },
                    [this, &p](const Kernel& k) { return bind_own_args(*p.spec, k); },
                    p.spec->worklist->extra_state_bytes > 0 && nonzero(p.spec->worklist->extra_state_while),
                    stats.readbacks};
  }

  void execute(PassState& p, Redo redo)
  {
    p.ran = true;
    if (!run_reads.empty())
      for (StreamId s : pass_outputs(*p.spec)) run_reads.requeue(s);
    std::size_t n = p.spec->launches_over_stream() ? state(p.spec->over).count : p.spec->items;
    for (StreamId s : p.spec->also_over) n += state(s).count;
    const std::size_t wg = group_of(*p.spec);
    const std::size_t global = round_up(n, wg);
    if (p.list && !p.list->settled) {
      ListHost host = list_host(p);
      refine(*p.spec, *p.list, p.stats, n, host);
      p.list->settled = true;
    }
    if (redo == Redo::full) launch(p, n, global, wg);
    register_outputs(p, n, global, wg);
  }

  // Sets the pass up to emit (its registration, its outputs' buffers, its segments or
  // the global counter) and launches its kernel over `global` work-items.
  void launch(PassState& p, std::size_t n, std::size_t global, std::size_t wg)
  {
    // Once a run has fallen back it stays there: its reruns must not try segments again.
    p.mode = p.atomic_this_run ? Registration::global_atomic : registration_of(*p.spec);
    // Outputs that memory pressure or a new run took come back at their size before
    // any segments are taken: the segments then fit beside them, or the pass registers
    // through the global counter (a handed-over output gets its buffer once packed).
    for (auto& e : p.emitters)
      if (e.handed_from == StreamId{} && !(late && state(e.stream).transient)) restore(e.stream);
    if (p.spec->culls()) restore(p.spec->cull_target);
    for (auto& e : p.emitters) {
      if (e.segment_capacity == 0) e.segment_capacity = planner.first_segment_capacity(e);
      SegmentPlanner::forget_stale_plan(e, planner.segment_count(e, global));
      if (p.mode != Registration::global_atomic && !segments_fit(e, global) &&
          !(release_idle_scratch() && segments_fit(e, global)))
        fall_back_to_global_counter(p);
    }
    // Each emitter's segments fit alone; all of them together may not.
    if (p.mode != Registration::global_atomic) {
      try {
        for (auto& e : p.emitters) prepare_segments(e, global);
      } catch (const DeviceMemoryExhausted&) {
        fall_back_to_global_counter(p);
      }
    }
    // Lock-free: the next run tries small segments again.
    if (p.mode == Registration::global_atomic)
      for (auto& e : p.emitters) e.segment_capacity = planner.first_segment_capacity(e);
    // Outputs the segments left to the global counter come back now; those that pack
    // late get their buffer once packed.
    for (auto& e : p.emitters) {
      if (!packs_late(p, e)) restore(e.stream);
      state(e.stream).released = 0;
    }
    if (p.spec->culls()) take_stage_scratch(p.keep, p.keep_at, n * sizeof(cl_uint), "cull flags");
    // Without segments to hand over, the output needs its own buffer: as large as the
    // input, a first guess that saves a rerun where the output is about its size.
    for (auto& e : p.emitters) {
      if (e.handed_from == StreamId{} || hands_over(p, e)) continue;
      const std::size_t guess = state(e.stream).base + state(e.handed_from).count;
      if (state(e.stream).capacity < guess) with_memory([&] { grow(e.stream, guess); });
    }
    bind_args(p);
    context.launch(active(p), global, wg, tl(), p.spec->name);
    ++p.stats.launches;
  }

  // What the scheduler appends to a launch: the scans and merges of the emitted
  // streams' segments, and a culling pass's compaction.
  void register_outputs(PassState& p, std::size_t n, std::size_t global, std::size_t wg)
  {
    const std::string& label = p.spec->name;
    if (p.mode == Registration::lock_free) {
      for (auto& e : p.emitters) {
        auto& dst = state(e.stream);
        with_memory([&] {
          ensure_capacity(context, offsets, e.segments * sizeof(cl_uint), "registration offsets");
          scan.exclusive(e.counts, offsets, e.segments, counters, dst.slot, tl(), label.c_str());
        });
        merge_interleaved.set_args(e.items, cl_uint(words(e.stream)), e.counts, offsets, cl_uint(e.segments),
                                   cl_uint(e.segment_capacity), dst.buffer, cl_uint(dst.capacity));
        context.launch(merge_interleaved, e.segments * e.segment_capacity, wg, tl(), label);
      }
    } else if (p.mode == Registration::segmented_lock && global > 0) {
      // The scans first, two outputs' at once, then the merges.
      std::vector<Scan::Job> scans;
      for (auto& e : p.emitters) {
        with_memory(
            [&] { ensure_capacity(context, e.offsets, (e.segments + 1) * sizeof(cl_uint), "registration offsets"); });
        if (scans_at_once(p, e)) scans.push_back({&e.counts, &e.offsets, e.segments, state(e.stream).slot});
      }
      with_memory([&] {
        for (std::size_t k = 0; k < scans.size(); k += 2)
          if (k + 1 < scans.size()) scan.exclusive_both(scans[k], scans[k + 1], counters, tl(), label.c_str());
          else scan.exclusive(*scans[k].in, *scans[k].out, scans[k].n, counters, scans[k].slot, tl(), label.c_str());
      });
      for (auto& e : p.emitters)
        if (!packs_late(p, e)) merge_segments(p, e);
    }
    if (p.spec->culls()) {
      auto& dst = state(p.spec->cull_target);
      with_memory([&] {
        scan.compact(state(p.spec->cull_source).buffer, words(p.spec->cull_source), p.keep, n, dst.buffer,
                     dst.capacity, counters, dst.slot, tl(), label.c_str());
      });
    }
  }

  // Segmented lock: the segments' items, in the order of their groups, into the stream.
  // The merge also completes the offsets with their total, which makes them a plan;
  // with `copy` false it does only that.
  void merge_segments(const PassState& p, const EmitterState& e, bool copy = true)
  {
    const auto& dst = state(e.stream);
    const std::size_t wg = context.work_group_size(), per_group = merged_per_group(e);
    // A spilled item finds its place through the scanned offset of its group's segment.
    const bool scanned = scans_at_once(p, e), own_offsets = !scanned && copy && host_counters[e.overflow_slot] == 0;
    if (!scanned && !own_offsets)
      scan.exclusive(e.counts, e.offsets, e.segments, counters, no_slot, tl(), p.spec->name.c_str());
    merge_planned.set_args(e.items, cl_uint(words(e.stream)), e.counts, e.offsets, cl_uint(e.segments), plan_of(e, no_plan),
                           cl_uint(e.planned), cl_uint(planner.first_segment_capacity(e)), counters,
                           cl_uint(e.overflow_slot), cl_uint(e.pool), dst.buffer, cl_uint(copy ? dst.capacity : 0),
                           cl_uint(per_group), cl_uint(own_offsets));
    const std::size_t groups = (e.segments + per_group - 1) / per_group;
    const std::size_t spill_groups = own_offsets ? 0 : (e.pool + wg - 1) / wg;
    context.launch(merge_planned, copy ? (groups + spill_groups) * wg : 1, wg, tl(), p.spec->name);
  }

  // Segments a merging group copies: about eight groups' worth of items, judged by the
  // plan's average segment (else the room of an unplanned one), and at most
  // most_merged_per_group and a work-item each, which reads its bounds.
  std::size_t merged_per_group(const EmitterState& e) const
  {
    const std::size_t wg = context.work_group_size(), most = std::min(most_merged_per_group, wg);
    const std::size_t average = e.planned ? e.planned_total / e.planned : planner.first_segment_capacity(e);
    return std::clamp<std::size_t>(8 * wg / std::max<std::size_t>(average, 1), 1, most);
  }

  // Whether this execution packs the emitter's items into the buffer of an input
  // (PassSpec::hand_over): only once the stage's counters are read, since until then
  // the pass may run again and read its input.
  static bool hands_over(const PassState& p, const EmitterState& e)
  {
    return p.mode == Registration::segmented_lock && e.handed_from != StreamId{};
  }

  // Whether the emitter's counts are scanned into its offsets right after its kernel. An
  // output packed once the counters are read needs no scan before: its kernel added up
  // its count (registration.h), and where few segments hold it and none spilled, its
  // merge finds their offsets itself (merge_segments).
  bool scans_at_once(const PassState& p, const EmitterState& e) const
  {
    return !packs_late(p, e) || e.segments > own_offsets_most_segments;
  }

  // Whether the emitter's segments are packed only once the stage's counters are read:
  // handed-over outputs, and in the arena every transient one, whose stream then takes
  // exactly its items, where the segments packed before it in the stage lay (the front
  // update's triangle pairs where its next front's segments were: cloth-ball's arena
  // 118 -> 97 MB).
  bool packs_late(const PassState& p, const EmitterState& e) const
  {
    return hands_over(p, e) || (p.mode == Registration::segmented_lock && late && state(e.stream).transient);
  }

  // After the stage's counters are read and no pass of it runs again: the outputs that
  // pack late, in order, each taking a buffer of its items, then in the arena giving its
  // segments' place to the next. Once memory has run short, an output to be handed over
  // that the pass wrote into a buffer of its own (through the global counter) leaves its
  // input spent as a hand-over would: held beside it for the rest of the run, the front
  // left the refinement no room under budgets above those that ran (NVIDIA, a generated
  // n-body scene whose step peaks at 10.4 MiB: 8.0 and 8.2 MiB failed, 7.5 ran). Not
  // before memory runs short: a run that registers through the global counter by choice
  // keeps both buffers, which then swap from step to step without an allocation. Not
  // where the pass runs in slices, whose later slices read the input.
  void pack_late(PassState& p)
  {
    bool first = true;
    for (auto& e : p.emitters) {
      if (!packs_late(p, e)) {
        if (pressed && e.handed_from != StreamId{} && std::size_t(&p - passes.data()) < sliced_pass) leave_spent(p, e);
        continue;
      }
      if (!first && use_arena) give_back_spent_inputs(p, host_counters[state(e.stream).slot] * spec(e.stream).element_bytes);
      first = false;
      if (hands_over(p, e)) {
        hand_over(p, e);
      } else {
        const std::size_t items = host_counters[state(e.stream).slot];
        if (state(e.stream).capacity < items) with_memory([&] { grow(e.stream, items, false); });
      }
      if (e.segments > 0) merge_segments(p, e);
      if (use_arena) drop_segments(e);
    }
  }

  // Before pass p packs an output of `bytes` late: its inputs that live within the run
  // (StreamGraph::within_run) and that no pass after it reads go back, where the output
  // then still fits in the arena's buffer (so that taking it allocates nothing and
  // cannot fail, which would leave a pass to run again without its input). After its
  // first output only: packed first, that one takes a place of its own, and the input's
  // place joins the first output's segments for the rest. n-body's triangle pairs
  // (35.1 MiB) so let its edge-edge candidates (59.0 MiB) pack where they and the
  // vertex-face candidates' segments lay: the step held 387.6 MiB, now 328.6.
  void give_back_spent_inputs(PassState& p, std::size_t bytes)
  {
    const std::size_t at = std::size_t(&p - passes.data());
    for (StreamId s : p.inputs) {
      auto& st = state(s);
      if (!spec(s).within_run || st.arena_at == StepArena::none || !arena.fits_without(st.arena_at, bytes)) continue;
      const bool read_later = std::any_of(passes.begin() + std::ptrdiff_t(at) + 1, passes.end(), [&](const PassState& q) {
        return std::find(q.inputs.begin(), q.inputs.end(), s) != q.inputs.end();
      });
      if (read_later) continue;
      st.released = std::max(st.released, st.capacity);
      drop(st);
      st.spent = true;
    }
  }

  // A handed-over output takes a buffer that holds its items (its own, else the
  // input's, else a new one), and the other goes back. The input is left empty, which
  // run() checks for before it reads the input again. Taking the input's buffer gives
  // the input the output's, in steady state the empty one the input was left with last
  // run, so that a step allocates nothing here. Where the output needs a new buffer, the
  // input is kept until it has one: the pass may then still run again, in slices, if
  // there is no room for it.
  void hand_over(PassState& p, const EmitterState& e)
  {
    auto &in = state(e.handed_from), &out = state(e.stream);
    const std::size_t items = host_counters[out.slot];
    if (items > out.limit) throw StreamLimitExceeded(spec(e.stream).name, items, out.limit);
    if (out.capacity < items && in.capacity >= items) {
      std::swap(out.buffer, in.buffer);
      std::swap(out.capacity, in.capacity);
      out.peak_bytes = std::max(out.peak_bytes, out.buffer.bytes());
    }
    if (out.capacity < items) with_memory([&] { grow(e.stream, items); });
    leave_spent(p, e);
  }

  // The input of a hand-over once its output holds the items: empty, and marked as
  // given, which run() checks for before it reads the input again.
  void leave_spent(PassState& p, const EmitterState& e)
  {
    auto& in = state(e.handed_from);
    if (in.capacity > 0) allocate(e.handed_from, 0);
    in.count = 0;
    in.known = true;
    in.handed_to = spec(e.stream).name;
    p.handed_over = true;
  }

  // After the stage's counters are read: whether a group's or work-item's items did not
  // all fit its segment.
  bool segments_overflowed(const PassState& p, const EmitterState& e) const
  {
    return planner.overflowed(p.mode, e, host_counters[e.overflow_slot]);
  }

  // Segmented lock: this execution's counts plan the next one's segments.
  void adopt_plan(EmitterState& e)
  {
    SegmentPlanner::adopt(e, host_counters[state(e.stream).slot], host_counters[e.overflow_slot]);
    std::swap(e.plan, e.offsets);
  }

  // After the stage's counters are read: whether the emitter's items outgrew its stream
  // (one packed late gets its buffer only once they are known).
  bool outgrew(const PassState& p, const EmitterState& e) const
  {
    return !packs_late(p, e) && host_counters[state(e.stream).slot] > state(e.stream).capacity;
  }

  // After the stage's counters are read: whether an output of the pass overflowed its
  // segments or its stream.
  bool overflowed(const PassState& p)
  {
    if (p.list && !p.list->settled) return true;
    for (const auto& e : p.emitters)
      if (segments_overflowed(p, e) || outgrew(p, e)) return true;
    if (!p.spec->culls()) return false;
    const auto& target = state(p.spec->cull_target);
    return host_counters[target.slot] > target.capacity;
  }

  // Every counter of the run zero, the work lists' counts among them.
  void clear_all_counters()
  {
    context.fill_u32(counters, 0, 0, host_counters.size(), tl());
    lists_cleared();
  }
  void lists_cleared()
  {
    for (auto& p : passes)
      if (p.list) p.list->counts_clear = true;
  }

  // Reads every counter of the stage in one transfer; grows what overflowed and
  // reruns its producer until nothing did.
  void flush(const std::vector<PassState*>& stage)
  {
    busy.assign(stage.begin(), stage.end());
    // Only variable-length outputs have counters to read.
    if (std::none_of(stage.begin(), stage.end(), [](const PassState* p) {
          return !p->emitters.empty() || p->spec->culls() || (p->list && p->list->awaiting);
        }))
      return;
    std::vector<PassState*> packed, overflowing;
    for (;;) {
      read_counters();
      // Work lists whose last batch's counts came with the read: done, or their rounds go
      // on (refine), and the pass emits again.
      for (PassState* p : stage)
        if (p->list && p->list->awaiting) {
          if (p->list->batch_finished(counts_read(*p->list))) {
            ListHost host = list_host(*p);
            settle_list(*p->spec, *p->list, p->stats, host);
          } else {
            p->list->settled = false;
          }
        }
      pack_done(stage, packed, overflowing);
      busy.assign(overflowing.begin(), overflowing.end());
      if (overflowing.empty()) break;
      rerun_overflowing(stage, overflowing);
    }
    finish(stage);
  }

  // The stage's counters, and the reads after the run whose writers have all run.
  void read_counters()
  {
    queue_run_reads();
    if (!next_counters_clear) {
      context.fill_u32(next_counters, 0, 0, host_counters.size(), tl());
      next_counters_clear = true;
    }
    if (before_counter_read) before_counter_read();
    context.read(counters, host_counters.data(), host_counters.size() * sizeof(std::uint32_t), 0, tl());
    ++stats.readbacks;
  }

  // Short of memory for a pass's output, where the stage's other passes are done or
  // can run again, the run may go on in slices from that pass (run_in_slices).
  // Not where a pass before it still overflows (it would not run again), nor where a
  // pass after it has handed its input's buffer over (it could not).
  void out_of_memory(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing, PassState* q)
  {
    const auto at = std::find(stage.begin(), stage.end(), q);
    const bool before = std::any_of(stage.begin(), at, [&](PassState* p) {
      return std::find(overflowing.begin(), overflowing.end(), p) != overflowing.end();
    });
    const bool gone = std::any_of(at + 1, stage.end(), [](const PassState* p) { return p->handed_over; });
    if (before || gone) return;
    // The passes before it are done, and the run goes on after them.
    finish(std::vector<PassState*>(stage.begin(), at));
    flush_failure = std::size_t(q - passes.data());
  }

  // A pass whose outputs all fit is done: it packs its outputs that pack late now (its
  // segments stay busy until then), and its segments hold nothing needed any more,
  // so they may go back if growing another pass's output runs short of memory. The
  // others are `overflowing`.
  void pack_done(const std::vector<PassState*>& stage, std::vector<PassState*>& packed,
                 std::vector<PassState*>& overflowing)
  {
    overflowing.clear();
    for (PassState* p : stage)
      if (overflowed(*p)) {
        overflowing.push_back(p);
      } else if (std::find(packed.begin(), packed.end(), p) == packed.end()) {
        try {
          pack_late(*p);
        } catch (const DeviceMemoryExhausted&) {
          out_of_memory(stage, overflowing, p);
          throw;
        }
        packed.push_back(p);
      }
  }

  // Pass by pass, so that one packed again gives its segments back before the next
  // one's outputs grow. Where even the idle scratch leaves no room for a pass's
  // outputs, the overflowing passes after it give back their segments, which hold
  // their items until they pack, and run again in full through the global counter:
  // so a run that fits with every pass on the global counter fits (a cull's output
  // had failed to grow beside the busy segments of the pass after it).
  void rerun_overflowing(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing)
  {
    std::vector<PassState*> unpacked;
    for (std::size_t k = 0; k < overflowing.size(); ++k) {
      PassState* p = overflowing[k];
      const std::function<bool()> later_segments_back = [&] {
        bool freed = false;
        for (std::size_t j = k + 1; j < overflowing.size(); ++j) {
          PassState& q = *overflowing[j];
          if (q.mode == Registration::global_atomic) continue;
          fall_back_to_global_counter(q);
          unpacked.push_back(&q);
          freed = true;
        }
        return freed;
      };
      try {
        // What a pass emitted from a work list's state before its rounds were done
        // counts for nothing, its overflows included: it emits again once they are.
        const bool resumes = p->list && !p->list->settled;
        const bool fell_back = std::find(unpacked.begin(), unpacked.end(), p) != unpacked.end();
        const Redo r = resumes || fell_back ? Redo::full : Redo::none;
        rerun(*p, resumes ? r : std::max(r, grow_overflowed(*p, later_segments_back)));
        if (!resumes) ++p->stats.reruns;
      } catch (const DeviceMemoryExhausted&) {
        out_of_memory(stage, overflowing, p);
        throw;
      }
    }
  }

  // After a pass's counters show it overflowed: its segments planned anew from them, its
  // outputs grown; returns how much of the pass must run again.
  Redo grow_overflowed(PassState& p, const std::function<bool()>& later_segments_back)
  {
    const bool atomic = p.mode == Registration::global_atomic;
    Redo r = Redo::none;
    for (auto& e : p.emitters) {
      auto& dst = state(e.stream);
      if (segments_overflowed(p, e)) {
        // The rerun plans from this execution's counts, so every group fits.
        if (packs_late(p, e)) merge_segments(p, e, false);
        if (p.mode == Registration::segmented_lock) {
          adopt_plan(e);
          e.exact_plan = true;
        } else e.segment_capacity = grown(host_counters[e.overflow_slot]);
        r = Redo::full;
      }
      if (outgrew(p, e)) {
        const bool now_atomic = grow_output(p, e.stream, host_counters[dst.slot], later_segments_back);
        r = std::max(r, atomic || now_atomic ? Redo::full : Redo::pack);
      }
    }
    if (p.spec->culls()) {
      auto& dst = state(p.spec->cull_target);
      if (host_counters[dst.slot] > dst.capacity) {
        allocate_making_room([&] { with_memory([&] { grow(p.spec->cull_target, host_counters[dst.slot]); }); },
                             later_segments_back);
        r = std::max(r, Redo::pack);
      }
    }
    return r;
  }

  void rerun(PassState& p, Redo r)
  {
    if (r == Redo::full) clear_counters(p);
    execute(p, r);
    if (r == Redo::pack &&
        std::none_of(p.emitters.begin(), p.emitters.end(), [&](const EmitterState& e) { return packs_late(p, e); }))
      busy.erase(std::find(busy.begin(), busy.end(), &p));
  }

  // Before a counter read: the reads after the run whose streams' writers have all run
  // (or are skipped this run) are queued ahead of it, and come back with it. A writer
  // that runs again afterwards (a rerun, a later slice) queues the read anew.
  void queue_run_reads()
  {
    run_reads.queue(
        [&](StreamId stream) {
          return std::all_of(passes.begin(), passes.end(), [&](const PassState& p) {
            const auto out = pass_outputs(*p.spec);
            return std::find(out.begin(), out.end(), stream) == out.end() || p.ran ||
                   (p.spec->conditional() && !nonzero(p.spec->runs_while));
          });
        },
        buffer_of());
  }

  // A stream's buffer, for the reads after the run.
  RunReads::BufferOf buffer_of()
  {
    return [this](StreamId stream) -> const Buffer& { return state(stream).buffer; };
  }

  // Passes whose outputs are all in their streams, as the counters read last say.
  void finish(const std::vector<PassState*>& done)
  {
    for (PassState* p : done)
      if (p->mode == Registration::segmented_lock)
        for (auto& e : p->emitters) adopt_plan(e);
    give_back_segments(done);
    for (PassState* p : done)
      for (StreamId s : pass_outputs(*p->spec))
        if (spec(s).variable) {
          state(s).count = host_counters[state(s).slot];
          state(s).known = true;
          state(s).handed_to.clear();  // swapped with a spent input, it held that one's mark
        }
  }

  // Before a pass executes again in full: the counters its kernel adds to start from
  // zero (from the items of earlier slices, for a gathered stream), whichever
  // registration it runs with now.
  void clear_counters(const PassState& p)
  {
    for (const auto& e : p.emitters) {
      context.fill_u32(counters, std::uint32_t(state(e.stream).base), state(e.stream).slot, 1, tl());
      context.fill_u32(counters, 0, e.overflow_slot, 1, tl());
    }
  }

  Kernel build_kernel(const PassSpec& spec, Registration mode, const std::string& name)
  {
    const std::string define = registration_define(mode);
    const std::string opts = spec.kernel.options.empty() ? define : spec.kernel.options + " " + define;
    return context.programs().kernel(spec.kernel.program, name, opts);
  }
  Kernel build_kernel(const PassSpec& spec, Registration mode) { return build_kernel(spec, mode, spec.kernel.kernel); }

  bool needs_new_stage(const PassState& p)
  {
    return std::any_of(p.inputs.begin(), p.inputs.end(),
                       [&](StreamId s) { return spec(s).variable && !state(s).known; });
  }

  void run()
  {
    timeline.clear();
    stats = RunStats{};
    stats_pending = false;
    for (auto& p : passes) {
      p.stats = PassStats{p.spec->name};
      p.atomic_this_run = false;
      p.handed_over = false;
      p.ran = false;
      if (p.list) p.list->restart();
      for (auto& e : p.emitters) {
        e.segment_bytes = 0;
        e.exact_plan = false;
      }
    }
    segment_pool.start_run();
    start_arena();
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
    if (next_counters_clear) {
      std::swap(counters, next_counters);
      for (auto& p : passes)
        if (p.list) std::swap(p.list->counts, p.list->next_counts);
      lists_cleared();
    } else {
      clear_all_counters();
    }
    next_counters_clear = false;

    // However the run ends (a stop, an error), no pass's scratch is busy afterwards:
    // allocations between runs may take it.
    struct Idle {
      std::vector<const PassState*>& busy;
      bool& running;
      ~Idle()
      {
        busy.clear();
        running = false;
      }
    } idle{busy, running};
    run_reads.requeue_all();
    running = true;
    for (auto& st : streams) {
      st.earlier = 0;
      st.partial = false;
    }
    std::vector<PassState*> stage;
    Failure failure;
    for (std::size_t i = 0; i < passes.size() && !failure; ++i) {
      if (i == sliced_pass) {
        if (!(failure = end_stage(stage))) failure.pass = i;
        break;
      }
      failure = step(passes[i], stage);
    }
    if (!failure) failure = end_stage(stage);
    if (failure.pass != SIZE_MAX) {
      if (failure.error) {
        sliced_pass = slice_start(failure.pass);
        if (sliced_pass == SIZE_MAX) std::rethrow_exception(failure.error);
        slices = 1;
      }
      run_in_slices(sliced_pass);
    }
    run_reads.finish(buffer_of(), tl());
    segment_pool.keep_needed();
    stats_pending = true;
  }

  // What lived within the last run goes back: its segments (still held where a run
  // ended early) and its transient streams, which come back at their size when their
  // producers run. Then the arena takes the size the last run needed.
  void start_arena()
  {
    if (pressed) use_arena = false;
    for (auto& p : passes) {
      for (auto& e : p.emitters)
        if (e.arena_at != StepArena::none || e.counts_at != StepArena::none) drop_segments(e);
      drop_stage_scratch(p.keep, p.keep_at);
    }
    for (auto& st : streams)
      if (st.arena_at != StepArena::none || (use_arena && st.transient && st.buffer)) {
        st.released = std::max(st.released, st.capacity);
        drop(st);
      }
    if (use_arena) arena.start_run();
    else arena.release();
    late = use_arena && (context.memory_limit() >= context.device().global_memory || arena.bytes() > 0);
  }

  // Where a pass had no room even in a stage of its own (error set), or where the run
  // goes on in slices (pass set).
  struct Failure {
    std::exception_ptr error;
    std::size_t pass = SIZE_MAX;
    explicit operator bool() const { return pass != SIZE_MAX; }
  };

  // Flushes the stage and empties it; short of memory for a pass's outputs where the
  // run may go on in slices from that pass, says so.
  Failure end_stage(std::vector<PassState*>& stage)
  {
    flush_failure = SIZE_MAX;
    try {
      flush(stage);
    } catch (const DeviceMemoryExhausted&) {
      if (flush_failure == SIZE_MAX) throw;
      stage.clear();
      return {std::current_exception(), flush_failure};
    }
    stage.clear();
    return {};
  }

  // Executes pass `p` in the current stage; short of memory, the stage ends before it:
  // once its counters are read, its passes' segments hold nothing needed, and `p` may
  // take their memory. Where even that does not fit (`p` then holds nothing), or a
  // flush has no room for a pass's outputs, says which pass.
  Failure step(PassState& p, std::vector<PassState*>& stage)
  {
    if (p.spec->conditional() && !nonzero(p.spec->runs_while)) return {};
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
      clear_counters(p);
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

  bool running = false;  // within run()
  // The pass that runs in slices (SIZE_MAX: none) and into how many.
  std::size_t sliced_pass = SIZE_MAX;
  unsigned slices = 1;
  // The slices that pass `found_pass` was last found to need, by doubling them, and its
  // input then (0: none yet). What a slice needs follows what it emits more than what
  // it reads (a front's first pairs expand into many, later ones into few), so a run
  // with more input starts from that number, and one with less takes as much fewer,
  // down to one.
  unsigned found_slices = 0;
  std::size_t found_input = 0, found_pass = SIZE_MAX;
  std::size_t slices_left = 0;  // after the one running
  std::size_t flush_failure = SIZE_MAX;  // the pass whose output a flush had no memory for, if slices may start there

  // Only a pass over one stream can be sliced, and only where it reads that stream alone
  // from there on (another pass would see a slice where it expects the stream); a
  // culled stream would be compacted slice by slice over what it gathered before.
  bool sliceable(std::size_t first) const
  {
    const PassSpec& head = *passes[first].spec;
    if (!head.launches_over_stream() || !head.also_over.empty() || head.culls()) return false;
    for (std::size_t j = first + 1; j < passes.size(); ++j) {
      const auto& ins = passes[j].inputs;
      if (std::find(ins.begin(), ins.end(), head.over) != ins.end()) return false;
      if (passes[j].spec->culls() && spec(passes[j].spec->cull_target).gathered) return false;
    }
    return true;
  }

  // Where slices start when pass `failed` finds no room: there, or where it cannot be
  // sliced (a culling pass), at the nearest pass before it that can and that may run
  // again (no pass from there on has packed an output into its input's buffer), so
  // that smaller slices of that pass's work leave it room. SIZE_MAX: nowhere.
  std::size_t slice_start(std::size_t failed) const
  {
    for (std::size_t p = failed + 1; p-- > 0;) {
      if (passes[p].handed_over) return SIZE_MAX;
      if (sliceable(p)) return p;
    }
    return SIZE_MAX;
  }

  // Items a slice of `total` holds when the run goes in `slices` slices: a multiple of
  // what starts a sub-buffer on the device's alignment.
  std::size_t slice_items(StreamId over, std::size_t total) const
  {
    const std::size_t bytes = spec(over).element_bytes, align = context.device().base_address_align;
    const std::size_t step = align / std::gcd(align, bytes);
    return std::max(step, round_up((total + slices - 1) / slices, step));
  }

  // Runs pass `first` and the rest of the graph in slices of its launch stream,
  // doubling them until a slice fits (Scheduler's class comment).
  void run_in_slices(std::size_t first)
  {
    const StreamId over = passes[first].spec->over;
    // The passes that depend on what the sliced pass emits run every slice; the rest once.
    std::vector<bool> every_slice(passes.size(), false), sliced(streams.size(), false);
    for (std::size_t j = first; j < passes.size(); ++j) {
      const auto& ins = passes[j].inputs;
      if (j == first || std::any_of(ins.begin(), ins.end(), [&](StreamId s) { return sliced[s.index]; })) {
        every_slice[j] = true;
        for (StreamId s : pass_outputs(*passes[j].spec)) sliced[s.index] = true;
      }
    }
    // Launch streams of those passes that come from passes run once count in the first
    // slice only, so that no item is tested twice.
    std::vector<StreamId> once;
    for (std::size_t j = first + 1; j < passes.size(); ++j) {
      if (!every_slice[j] || !passes[j].spec->launches_over_stream()) continue;
      std::vector<StreamId> launched{passes[j].spec->over};
      launched.insert(launched.end(), passes[j].spec->also_over.begin(), passes[j].spec->also_over.end());
      for (StreamId s : launched)
        if (!sliced[s.index] && s != over && std::find(once.begin(), once.end(), s) == once.end()) once.push_back(s);
    }
    // The variable streams the sliced passes emit, whose counts go slice by slice.
    std::vector<StreamId> outputs;
    for (std::uint32_t i = 0; i < streams.size(); ++i)
      if (sliced[i] && spec(StreamId{i}).variable) outputs.push_back(StreamId{i});
    const std::size_t total = state(over).count;
    bool found = first == found_pass && found_input > 0;
    slices = found ? unsigned(std::max<std::size_t>(
                         1, (found_slices * std::min(total, found_input) + found_input - 1) / found_input))
                   : std::max(slices, 2u);
    for (;;) {
      const std::size_t size = slice_items(over, total);
      try {
        run_slices(first, every_slice, outputs, once, size);
        if (!found) {
          found_slices = slices;
          found_input = total;
          found_pass = first;
        }
        return;
      } catch (const DeviceMemoryExhausted&) {
        if (size <= slice_items(over, 0) || slices >= (1u << 30)) throw;
        slices *= 2;
        found = false;
      }
    }
  }

  // Before a run's slices: what an earlier attempt held goes back, and the outputs take
  // what `count` slices of the last run's items need.
  void prepare_slices(std::size_t first, const std::vector<bool>& every_slice, const std::vector<StreamId>& outputs,
                      std::size_t count)
  {
    // What an earlier attempt held goes back: idle scratch, and sliced streams beyond
    // what a slice of the last run's items needs; the sliced passes register through
    // the global counter, whose memory is the streams themselves.
    busy.clear();
    release_idle_scratch();
    for (std::size_t j = first; j < passes.size(); ++j)
      if (every_slice[j]) {
        fall_back_to_global_counter(passes[j]);
        // A slice's work list is sized by the slice, not by what the whole input needed;
        // its statistics add up these slices alone, not an attempt that ran short.
        if (passes[j].list) {
          passes[j].list->released = 0;
          PassStats& stats = passes[j].stats;
          stats.rounds = 0;
          stats.list_items = 0;
          stats.widest_list = 0;
        }
      }
    // A gathered stream takes what the last run gathered at once, instead of growing
    // slice by slice with its items held twice.
    for (const bool gathered : {false, true})
      for (StreamId s : outputs) {
        auto& st = state(s);
        if (spec(s).gathered != gathered) continue;
        st.base = st.earlier = st.released = 0;
        const std::size_t share = grown(gathered ? st.run_items : st.run_items / std::max<std::size_t>(count, 1));
        if (gathered ? st.capacity < st.run_items : st.capacity > share) grow(s, share, false);
      }
  }

  void run_slices(std::size_t first, const std::vector<bool>& every_slice, const std::vector<StreamId>& outputs,
                  const std::vector<StreamId>& once, std::size_t size)
  {
    const StreamId over = passes[first].spec->over;
    const std::size_t total = state(over).count, count = std::max<std::size_t>(1, (total + size - 1) / size);
    prepare_slices(first, every_slice, outputs, count);
    // However the slices end, the input and the streams counted once are whole again.
    auto& in = state(over);
    struct Whole {
      StreamState& in;
      const Buffer buffer;
      const std::size_t count;
      std::vector<std::pair<StreamState*, std::size_t>> once;
      std::vector<StreamState>& streams;
      ~Whole()
      {
        in.buffer = buffer;
        in.count = count;
        for (auto& [st, n] : once) st->count = n;
        for (auto& st : streams) st.base = 0;
      }
    } whole{in, in.buffer, in.count, {}, streams};
    const std::size_t bytes = spec(over).element_bytes;
    for (std::size_t k = 0, begin = 0; k == 0 || begin < total; ++k, begin += size) {
      const std::size_t n = std::min(size, total - begin);
      slices_left = count - std::min(count, k + 1);
      in.buffer = n > 0 ? whole.buffer.slice(begin * bytes, n * bytes) : whole.buffer;
      in.count = n;
      if (k == 1)
        for (StreamId s : once) {
          whole.once.emplace_back(&state(s), state(s).count);
          state(s).count = 0;
        }
      clear_all_counters();
      for (std::size_t j = first; j < passes.size(); ++j) {
        if (k > 0 && !every_slice[j]) continue;
        if (passes[j].list) passes[j].list->restart();
        for (StreamId s : pass_outputs(*passes[j].spec))
          if (spec(s).variable) {
            state(s).known = false;
            if (state(s).base > 0) context.fill_u32(counters, std::uint32_t(state(s).base), state(s).slot, 1, tl());
          }
      }
      std::vector<PassState*> stage;
      Failure failure;
      for (std::size_t j = first; j < passes.size() && !failure; ++j)
        if (k == 0 || every_slice[j]) failure = step(passes[j], stage);
      if (!failure) failure = end_stage(stage);
      if (failure) std::rethrow_exception(failure.error);
      for (StreamId s : outputs) {
        auto& st = state(s);
        if (spec(s).gathered) st.base = st.count;
        else if (begin + n < total) st.earlier += st.count;
      }
    }
    stats.slices = unsigned(count);
    for (StreamId s : outputs) state(s).partial = stats.slices > 1 && !spec(s).gathered;
    stats.sliced_pass = passes[first].spec->name;
  }

  void stop_if_raised(const PassSpec& pass)
  {
    std::uint32_t flag = 0;
    context.read(state(pass.stop_flag).buffer, &flag, sizeof flag, 0, tl());
    ++stats.readbacks;
    if (flag) throw RunStopped(pass.name);
  }

  // Before a change to what the last run's figures describe (a stream's size or buffer,
  // the idle scratch).
  void settle_stats()
  {
    if (stats_pending) collect_stats();
  }

  void collect_stats()
  {
    stats_pending = false;
    runtime::collect_stats(stats, {graph, timeline, scan.scratch_bytes() + offsets.bytes(), segment_pool.idle(), arena, streams,
                                   passes});
  }

};

Scheduler::Scheduler(Context& context, StreamGraph graph, SchedulerOptions options)
    : state_(std::make_unique<State>(context, std::move(graph), options))
{
  auto& s = *state_;
  const auto order = s.graph.schedule();
  std::uint32_t slots = 0;
  s.streams.resize(s.graph.streams().size());
  std::vector<bool> handed_over(s.streams.size(), false);  // takes an input's buffer from its first run
  for (const auto& pass : s.graph.passes())
    for (const auto& handover : pass.handovers) handed_over[handover.second.index] = true;
  for (std::size_t i = 0; i < s.streams.size(); ++i) {
    const auto& spec = s.graph.streams()[i];
    s.allocate(StreamId{std::uint32_t(i)}, handed_over[i] ? 0 : spec.size);
    if (spec.variable) {
      s.streams[i].slot = slots++;
    } else {
      s.streams[i].count = spec.size;
    }
  }
  for (const auto& pass : s.graph.passes()) {
    for (StreamId e : pass.emits) s.streams[e.index].transient = true;
    if (pass.culls()) s.streams[pass.cull_target.index].transient = true;
  }
  for (const auto& pass : s.graph.passes())
    for (const auto& [input, output] : pass.handovers) s.streams[input.index].transient = s.streams[output.index].transient = false;
  for (std::size_t i = 0; i < s.streams.size(); ++i)
    if (s.graph.streams()[i].gathered) s.streams[i].transient = false;
  s.params.resize(s.graph.params().size());
  for (std::size_t index : order) {
    const PassSpec& spec = s.graph.passes()[index];
    PassState p;
    p.spec = &spec;
    const Registration registration = s.registration_of(spec);
    p.kernel = s.build_kernel(spec, registration);
    if (!spec.variant_kernel.empty()) p.variant = s.build_kernel(spec, registration, spec.variant_kernel);
    if (const auto& w = spec.worklist) {
      auto& l = p.list.emplace();
      l.seed = s.build_kernel(spec, registration, w->seed);
      l.round = s.build_kernel(spec, registration, w->round);
    }
    for (StreamId e : spec.emits) {
      EmitterState es;
      es.stream = e;
      es.expected = spec.expected_items(e);
      es.group = s.group_of(spec);
      for (const auto& [input, output] : spec.handovers)
        if (output == e) es.handed_from = input;
      es.overflow_slot = slots++;
      p.emitters.push_back(std::move(es));
    }
    p.inputs = pass_inputs(spec);
    p.stats.name = spec.name;
    s.passes.push_back(std::move(p));
  }
  s.context.fill_u32(s.no_plan, 0, 0, 1);
  // The work lists' counts after the streams', each where a sub-buffer may start.
  const std::size_t align_words = (context.device().base_address_align + 3) / 4;
  std::size_t words = slots;
  for (auto& p : s.passes)
    if (p.list) {
      p.list->counts_at = round_up(words, align_words);
      words = p.list->counts_at + list_words;
    }
  s.host_counters.assign(std::max<std::size_t>(words, 1), 0);
  s.counters = Buffer(context, s.host_counters.size() * sizeof(std::uint32_t), "stream counters");
  s.next_counters = Buffer(context, s.host_counters.size() * sizeof(std::uint32_t), "stream counters");
  for (auto& p : s.passes)
    if (p.list) {
      p.list->counts = s.counters.slice(p.list->counts_at * sizeof(std::uint32_t), list_count_bytes);
      p.list->next_counts = s.next_counters.slice(p.list->counts_at * sizeof(std::uint32_t), list_count_bytes);
    }
}

Scheduler::~Scheduler() = default;

void Scheduler::run() { state_->run(); }
bool Scheduler::release_idle_scratch()
{
  state_->settle_stats();
  return state_->release_idle_scratch();
}
std::vector<Buffer> Scheduler::borrow_idle_scratch(const std::vector<std::size_t>& sizes) const
{
  return state_->borrow_idle_scratch(sizes);
}

void Scheduler::upload(StreamId stream, const void* items, std::size_t count)
{
  auto& s = *state_;
  s.settle_stats();
  auto& st = s.state(stream);
  // What the stream held is replaced, so it goes first; short of memory, idle scratch
  // goes too.
  if (count > st.capacity || !s.spec(stream).variable) s.with_memory([&] { s.grow(stream, count, false); });
  s.context.write(st.buffer, items, count * s.spec(stream).element_bytes);
  st.count = count;
  st.known = true;
  st.partial = false;
  st.handed_to.clear();
}

void Scheduler::on_counter_read(std::function<void()> work) { state_->before_counter_read = std::move(work); }

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
  s.with_memory([&] { s.allocate(stream, items); });
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
  if (items != s.state(stream).capacity) s.allocate(stream, items);
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
