#include "flush.hpp"

#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/primitives.hpp>

#include <algorithm>

namespace cstreams::runtime {

void Flush::run(const std::vector<PassState*>& stage)
{
  failed_pass_ = SIZE_MAX;
  p_.busy.assign(stage.begin(), stage.end());
  // Only variable-length outputs have counters to read.
  if (std::none_of(stage.begin(), stage.end(), [](const PassState* p) {
        return !p->emitters.empty() || p->spec->culls() || (p->list && p->list->awaiting);
      }))
    return;
  std::vector<PassState*> packed, overflowing;
  for (;;) {
    read_counters();
    settle_lists(stage);
    pack_done(stage, packed, overflowing);
    p_.busy.assign(overflowing.begin(), overflowing.end());
    if (overflowing.empty()) break;
    rerun_overflowing(stage, overflowing);
  }
  finish(stage);
}

// The stage's counters, and the reads after the run whose writers have all run.
void Flush::read_counters()
{
  queue_run_reads();
  p_.counters.clear_next();
  if (before_counter_read_) before_counter_read_();
  p_.counters.read();
  ++p_.stats.readbacks;
}

// Work lists whose last batch's counts came with the read: done, or their rounds go on
// (refine), and the pass emits again.
void Flush::settle_lists(const std::vector<PassState*>& stage)
{
  for (PassState* p : stage)
    if (p->list && p->list->awaiting) {
      if (p->list->batch_finished(p_.counters.list_counts(*p->list))) {
        ListHost host = p_.runner.list_host(*p);
        settle_list(*p->spec, *p->list, p->stats, host);
      } else {
        p->list->settled = false;
      }
    }
}

void Flush::queue_run_reads()
{
  p_.run_reads.queue(
      [&](StreamId stream) {
        return std::all_of(p_.passes.begin(), p_.passes.end(), [&](const PassState& p) {
          const auto out = pass_outputs(*p.spec);
          return std::find(out.begin(), out.end(), stream) == out.end() || p.ran || p_.runner.skipped(*p.spec);
        });
      },
      [this](StreamId stream) -> const Buffer& { return p_.streams.state(stream).buffer; });
}

// Short of memory for a pass's output, where the stage's other passes are done or
// can run again, the run may go on in slices from that pass (Slices).
// Not where a pass before it still overflows (it would not run again), nor where a
// pass after it has handed its input's buffer over (it could not).
void Flush::out_of_memory(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing,
                          PassState* q)
{
  const auto at = std::find(stage.begin(), stage.end(), q);
  const bool before = std::any_of(stage.begin(), at, [&](PassState* p) {
    return std::find(overflowing.begin(), overflowing.end(), p) != overflowing.end();
  });
  const bool gone = std::any_of(at + 1, stage.end(), [](const PassState* p) { return p->handed_over; });
  if (before || gone) return;
  // The passes before it are done, and the run goes on after them.
  finish(std::vector<PassState*>(stage.begin(), at));
  failed_pass_ = std::size_t(q - p_.passes.data());
}

// A pass whose outputs all fit is done: it packs its outputs that pack late now (its
// segments stay busy until then), and its segments hold nothing needed any more,
// so they may go back if growing another pass's output runs short of memory. The
// others are `overflowing`.
void Flush::pack_done(const std::vector<PassState*>& stage, std::vector<PassState*>& packed,
                      std::vector<PassState*>& overflowing)
{
  overflowing.clear();
  for (PassState* p : stage)
    if (p_.registrar.overflowed(*p)) {
      overflowing.push_back(p);
    } else if (std::find(packed.begin(), packed.end(), p) == packed.end()) {
      try {
        p_.packer.pack(*p);
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
void Flush::rerun_overflowing(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing)
{
  std::vector<PassState*> unpacked;
  for (std::size_t k = 0; k < overflowing.size(); ++k) {
    PassState* p = overflowing[k];
    const std::function<bool()> later_segments_back = [&] {
      bool freed = false;
      for (std::size_t j = k + 1; j < overflowing.size(); ++j) {
        PassState& q = *overflowing[j];
        if (q.mode == Registration::global_atomic) continue;
        p_.registrar.fall_back_to_global_counter(q);
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
Redo Flush::grow_overflowed(PassState& p, const std::function<bool()>& later_segments_back)
{
  const bool atomic = p.mode == Registration::global_atomic;
  Redo r = Redo::none;
  for (auto& e : p.emitters) {
    if (p_.registrar.segments_overflowed(p, e)) {
      // The rerun plans from this execution's counts, so every group fits.
      p_.registrar.replan(p, e);
      r = Redo::full;
    }
    if (p_.registrar.outgrew(p, e)) {
      const bool now_atomic =
          grow_output(p, e.stream, p_.counters[p_.streams.state(e.stream).slot], later_segments_back);
      r = std::max(r, atomic || now_atomic ? Redo::full : Redo::pack);
    }
  }
  if (p.spec->culls()) {
    const StreamId target = p.spec->cull_target;
    const std::size_t items = p_.counters[p_.streams.state(target).slot];
    if (items > p_.streams.state(target).capacity) {
      allocate_making_room([&] { p_.scratch.with_memory([&] { p_.streams.grow(target, items); }); },
                           later_segments_back);
      r = std::max(r, Redo::pack);
    }
  }
  return r;
}

// Grows a stream that pass `p` emits into, giving back registration segments when
// the device has no memory left for it: first those of idle passes (with_memory),
// then those that `make_room` gives back, then the pass's own, which then emits this
// run through the global counter. Returns whether the pass must run again in full. A
// stream that does not fit even then is an error.
bool Flush::grow_output(PassState& p, StreamId s, std::size_t needed, const std::function<bool()>& make_room)
{
  try {
    allocate_making_room([&] { p_.scratch.with_memory([&] { p_.streams.grow(s, needed); }); }, make_room);
    return false;
  } catch (const DeviceMemoryExhausted&) {
  }
  bool rerun = false;
  if (p.mode != Registration::global_atomic) {
    p_.registrar.fall_back_to_global_counter(p);
    rerun = true;
  }
  try {
    p_.streams.grow(s, needed);
  } catch (const DeviceMemoryExhausted&) {
    p_.streams.grow(s, needed, false);
  }
  return rerun;
}

void Flush::rerun(PassState& p, Redo r)
{
  if (r == Redo::full) clear_counters(p);
  p_.runner.execute(p, r);
  if (r == Redo::pack && std::none_of(p.emitters.begin(), p.emitters.end(),
                                      [&](const EmitterState& e) { return p_.registrar.packs_late(p, e); }))
    p_.busy.erase(std::find(p_.busy.begin(), p_.busy.end(), &p));
}

// Passes whose outputs are all in their streams, as the counters read last say.
void Flush::finish(const std::vector<PassState*>& done)
{
  for (PassState* p : done)
    if (p->mode == Registration::segmented_lock)
      for (auto& e : p->emitters) p_.registrar.adopt_plan(e);
  p_.scratch.stage_done(done);
  for (PassState* p : done)
    for (StreamId s : pass_outputs(*p->spec))
      if (p_.streams.spec(s).variable) {
        auto& st = p_.streams.state(s);
        st.count = p_.counters[st.slot];
        st.known = true;
        st.handed_to.clear();  // swapped with a spent input, it held that one's mark
      }
}

void Flush::clear_counters(const PassState& p)
{
  for (const auto& e : p.emitters) {
    p_.counters.set(p_.streams.state(e.stream).slot, std::uint32_t(p_.streams.state(e.stream).base));
    p_.counters.set(e.overflow_slot, 0);
  }
}

}  // namespace cstreams::runtime
