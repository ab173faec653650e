#pragma once
// Memory that lives within a run apart from the streams: registration segments with
// their counts, a stage's scratch (cull flags, work lists), the step arena they come from while
// memory lasts, and the idle segments kept between stages without it; and what goes
// back when the device runs short. Owns taking and giving back that memory and the
// switch from the arena to buffers held pass by pass; not how streams change size
// (StreamBuffers), nor when a pass falls back to the global counter (Registrar).
// Private to the runtime.
#include "../step_arena.hpp"
#include "segment_pool.hpp"
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstreams/runtime/primitives.hpp>

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class Context;

class Scratch {
public:
  // `busy`: the passes whose scratch may hold what is still needed (the run loop's and
  // the flush's to say); `running`: within a run.
  Scratch(Context& context, StepArena& arena, StreamBuffers& streams, std::vector<PassState>& passes,
          const std::vector<const PassState*>& busy, const bool& running, bool use_arena)
      : context_(context), arena_(arena), streams_(streams), passes_(passes), busy_(busy), running_(running),
        use_arena_(use_arena)
  {
  }

  // Until memory runs short: from then on, what lives within a run is held pass by pass
  // (segments in the idle pool, streams in buffers of their own), so that any of it
  // that is idle can go back.
  bool use_arena() const { return use_arena_; }
  // Memory ran short once (release_idle).
  bool pressed() const { return pressed_; }
  // Whether `bytes` fit the memory limit once `gone` bytes go back, memory never having
  // run short.
  bool fits_once_gone(std::size_t gone, std::size_t bytes) const;
  // This run packs transient outputs late (Registrar::packs_late): without a memory
  // budget, or into an arena whose start found room for it twice over. A stream packed
  // late is allocated while its segments hold its items, when the pass can no longer
  // fall back to the global counter: under a budget it would run in slices instead.
  bool late() const { return late_; }

  // Segments of at least `bytes` for e: from the arena, else from the pool, else new.
  void take_segments(EmitterState& e, std::size_t bytes);
  void give_back_segments(EmitterState& e);
  // Segments, with their counts where those came from the arena too.
  void drop_segments(EmitterState& e);
  // Scratch of at least `bytes` that the stage alone reads: from the arena, given back
  // with the stage's segments; without it, held from run to run.
  void take_stage_scratch(Buffer& buffer, std::size_t& at, std::size_t bytes, const char* label);
  void drop_stage_scratch(Buffer& buffer, std::size_t& at);
  // A work list's state and lists that came from the arena go back; the next run takes
  // lists for what this one's widest round needed (ListState::released): taken anew
  // from the arena each run, they need not keep what doubling on a replay gave them.
  void drop_list(ListState& l);
  // After a stage's counters are read and nothing of it overflowed.
  void stage_done(const std::vector<PassState*>& stage);

  // Runs `allocate`; when the device has no memory left, gives back the scratch of
  // every pass that holds nothing in it now (done already, or not run yet this run; it
  // is allocated again when the pass next runs) and tries once more.
  template <class Allocate> void with_memory(Allocate allocate)
  {
    allocate_making_room(allocate, [this] { return release_idle(); });
  }
  // Registration segments (with their counts), cull flags and work lists of the passes
  // that are not busy, and within a run the streams of the passes yet to run. Their
  // plans stay (a word a group), so that segments allocated again are planned ones, and
  // so do their offsets, which a pass done in the stage being flushed is yet to adopt as
  // its plan. Returns whether any memory was given back.
  bool release_idle();
  // Slices of the arena's free space between runs (Scheduler::borrow_idle_scratch).
  std::vector<Buffer> borrow_idle(const std::vector<std::size_t>& sizes) const
  {
    return use_arena_ ? arena_.lend(sizes) : std::vector<Buffer>{};
  }

  // What lived within the last run goes back: its segments (still held where a run
  // ended early) and its transient streams, which come back at their size when their
  // producers run. Then the arena takes the size the last run needed.
  void start_run();
  // The pool keeps the idle segments the run's stages needed.
  void end_run() { pool_.keep_needed(); }
  const std::vector<Buffer>& idle_segments() const { return pool_.idle(); }

private:
  void release_pass(PassState& p, bool& freed);

  Context& context_;
  StepArena& arena_;
  StreamBuffers& streams_;
  std::vector<PassState>& passes_;
  const std::vector<const PassState*>& busy_;
  const bool& running_;
  SegmentPool pool_;  // segments between stages, without the arena
  bool use_arena_;
  bool pressed_ = false;
  bool late_ = false;
};

}  // namespace cstreams::runtime
