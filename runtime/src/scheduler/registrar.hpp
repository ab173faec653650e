#pragma once
// How a pass's execution registers what it emits: in planned segments (segmented lock),
// in small ones (lock-free) or through one global counter where segments would not fit;
// the scans and merges appended to its launch; and, once the stage's counters are read,
// whether its segments overflowed and the plan its counts make. Owns the registration
// mode of each execution, the segments' sizes (through SegmentPlanner) and the
// scan and merge kernels; not the memory they come from (Scratch), not the streams'
// sizes (StreamBuffers), not when a pass runs again (Flush). Private to the runtime.
#include "counters.hpp"
#include "scratch.hpp"
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstreams/runtime/details/segment_plan.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <string>

namespace cstreams::runtime {

class Context;
class Timeline;

// The registration a pass's kernels are built for: the global counter where its items
// may come in any order, or where it emits none (its kernels are then the same in
// every mode, and one build serves as its fallback too), else the scheduler's.
inline Registration registration_of(const PassSpec& spec, Registration preferred)
{
  return spec.any_order || spec.emits.empty() ? Registration::global_atomic : preferred;
}
// The pass's kernel `name` built for registration `mode`.
Kernel build_pass_kernel(Context& context, const PassSpec& spec, Registration mode, const std::string& name);
// The pass's kernels for the global counter, its fallback, unless it has them.
void build_fallback(Context& context, PassState& p);

class Registrar {
public:
  Registrar(Context& context, Registration registration, StreamBuffers& streams, Scratch& scratch, Counters& counters,
            Timeline* timeline);

  const details::SegmentPlanner& planner() const { return planner_; }
  const Buffer& no_plan() const { return no_plan_; }
  // Scratch shared by every pass: the scan's and the lock-free offsets.
  std::size_t shared_scratch_bytes() const { return scan_.scratch_bytes() + offsets_.bytes(); }

  Registration registration_of(const PassSpec& spec) const { return runtime::registration_of(spec, registration_); }

  // Before p's kernel runs over `global` work-items in p.mode: segments planned for
  // each emitter, or, where they would not fit the device (after idle scratch went
  // back), the global counter for this run.
  void set_up(PassState& p, std::size_t global);
  // This run of the pass registers through one global counter, and its segments'
  // memory goes back.
  void fall_back_to_global_counter(PassState& p);
  // What the scheduler appends to a launch: the scans and merges of the emitted
  // streams' segments, and a culling pass's compaction.
  void register_outputs(PassState& p, std::size_t n, std::size_t global, std::size_t wg);
  // Segmented lock: the segments' items, in the order of their groups, into the stream.
  // The merge also completes the offsets with their total, which makes them a plan;
  // with `copy` false it does only that.
  void merge_segments(const PassState& p, const EmitterState& e, bool copy = true);

  // Whether this execution packs the emitter's items into the buffer of an input
  // (PassSpec::hand_over): only once the stage's counters are read, since until then
  // the pass may run again and read its input.
  static bool hands_over(const PassState& p, const EmitterState& e)
  {
    return p.mode == Registration::segmented_lock && e.handed_from != StreamId{};
  }
  // Whether the emitter's segments are packed only once the stage's counters are read:
  // handed-over outputs, and in the arena every transient one, whose stream then takes
  // exactly its items, where the segments packed before it in the stage lay (the front
  // update's triangle pairs where its next front's segments were: cloth-ball's arena
  // 118 -> 97 MB).
  bool packs_late(const PassState& p, const EmitterState& e) const;

  // After the stage's counters are read: whether a group's or work-item's items did not
  // all fit its segment; whether the emitter's items outgrew its stream (one packed late
  // gets its buffer only once they are known); whether any output of the pass did
  // either.
  bool segments_overflowed(const PassState& p, const EmitterState& e) const;
  bool outgrew(const PassState& p, const EmitterState& e) const;
  bool overflowed(const PassState& p) const;
  // Segmented lock: this execution's counts plan the next one's segments.
  void adopt_plan(EmitterState& e);
  // After e's segments overflowed: the rerun's segments sized so that every group fits.
  void replan(const PassState& p, EmitterState& e);

private:
  bool segments_fit(const EmitterState& e, std::size_t global) const;
  void prepare_segments(EmitterState& e, std::size_t global);
  void scan_and_merge(PassState& p);
  bool scans_at_once(const PassState& p, const EmitterState& e) const;
  std::size_t merged_per_group(const EmitterState& e) const;
  std::uint32_t count(std::uint32_t slot) const { return counters_[slot]; }

  Context& context_;
  StreamBuffers& streams_;
  Scratch& scratch_;
  Timeline* timeline_;
  Counters& counters_;
  Registration registration_;
  details::SegmentPlanner planner_;
  Scan scan_;
  Kernel merge_interleaved_, merge_planned_;
  Buffer offsets_;  // lock-free segments' offsets
  Buffer no_plan_;  // one zero: the plan of segments that have none
};

}  // namespace cstreams::runtime
