#pragma once
// A pass's work list (Worklist in stream_graph.hpp): its lists and state on the device,
// its seed and the batches of rounds that run until a round leaves nothing, growing the
// lists where a round overflows them. It owns those buffers and the batching; it may not
// touch other passes, streams or the scheduler's counters beyond its own words: it
// takes memory, binds the pass's own arguments and counts its reads through ListHost,
// which the run loop lends it (scheduler/run_loop.cpp). Private to the runtime.
#include "../step_arena.hpp"

#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>

namespace cstreams::runtime {

class Context;
class Timeline;

// A work list's device side (Worklist in stream_graph.hpp).
constexpr std::size_t list_words = 13;
constexpr std::size_t list_count_bytes = list_words * sizeof(std::uint32_t);

// Work lists and list states this small stay, however little a run needs: giving them
// back would save nothing worth an allocation when the next run needs them again.
constexpr std::size_t kept_list_bytes = std::size_t(1) << 16;

struct ListState {
  Kernel seed, round;
  Buffer state;
  Buffer lists[2];  // ping-pong: round r reads lists[r % 2] and appends to the other
  // Their places in the step arena, where the run takes them from it: the stage gives
  // them back once its counters are read, so that the next stages' memory, and the
  // stages' before, share theirs (ListHost::take).
  std::size_t state_at = StepArena::none;
  std::size_t lists_at[2] = {StepArena::none, StepArena::none};
  std::size_t held_bytes = 0;  // the most the state and lists held at once this run
  // cl_kernels/runtime/worklist.h's counts[list_words]: words of the scheduler's
  // counters from `counts_at`, so that they start a run cleared with them, with nothing
  // written before the seed, and come back with the stage's counter read rather than in
  // a read of their own (the two cost an H200 ~20 us a conservative step). `counts`
  // views them in `counters`, `next_counts` in `next_counters`, and they swap with them.
  std::size_t counts_at = 0;
  Buffer counts, next_counts;
  bool counts_clear = false;  // the counts hold zeros: a seed may start
  std::size_t capacity = 0;
  // What the next run's lists take at least: the capacity memory pressure took, or where
  // the lists went back with their stage to the arena, what the next run needs.
  std::size_t released = 0;
  // What the next run's lists should hold: the last settled run's widest round with
  // slack, and twice what it outgrew the run before by (widest, that run's).
  std::size_t needed = 0, widest = 0;
  // The rounds the last runs needed, the next run's first batch the most of them: a run
  // that needs more than its first batch has its pass emit twice (refine()), and the
  // rounds of steps in a row go up and down by one or two (300 bodies: 13-17), where an
  // empty round costs a few microseconds. Past them, the batches start at two rounds.
  std::array<unsigned, 8> recent_rounds{};
  unsigned runs_settled = 0;
  bool settled = false;  // this run's rounds are done, or their last batch is (awaiting)
  // Where this run's rounds stand: the next batch, and whether they start from the seed.
  bool reseed = true;
  unsigned at_round = 0, batch = 0, next_batch = 0;
  // Where `awaiting`, the stage's counter read brings the counts after the last batch
  // (refine()).
  bool awaiting = false;
  void restart()
  {
    settled = awaiting = false;
    reseed = true;
  }
  // After a batch, as its counts say: its last round left nothing and none overflowed.
  bool batch_finished(const std::uint32_t* counts) const
  {
    return counts[3] <= capacity && counts[at_round % 3] == 0;
  }
};

// What a work list borrows from the scheduler while its rounds run.
struct ListHost {
  Context& context;
  Timeline* timeline;                  // profiling, or none
  const Buffer& counters;              // the run's counters, the list's words among them
  std::uint32_t* counts;               // its words as the last counter read brought them
  // A buffer of at least `bytes` for the list's state or a list: from the step arena
  // while the run uses it (`at` its place), else a buffer of its own, kept from run to
  // run; making room if need be. And one given back.
  std::function<void(Buffer&, std::size_t&, std::size_t, const char*)> take;
  std::function<void(Buffer&, std::size_t&)> give_back;
  std::function<unsigned(const Kernel&)> bind_own_args;  // the pass's arguments; the next index
  bool extra_state;                    // the optional mode's state is held this run
  unsigned& readbacks;                 // the run's blocking reads
};

// Seeds the work list and runs its rounds until one leaves nothing, in batches
// between which the host reads the counts once. A round that overflows the lists runs
// again, as a replay (cl_kernels/runtime/worklist.h), once they have grown to what it
// asked for with its input kept; a seed that overflows starts again.
// The pass emits from the state as it stands after a batch, and the stage's counter
// read brings the counts with it (Flush, settle_list), which saves a round trip where
// the batch was the last; where it was not, the rounds go on from there and the pass
// emits again. On a device that ends loops early, each round goes over exactly its
// items, one a work-item, so that no work-item strides over many: the host waits for
// the counts after every round (such devices are CPUs, where a read costs little).
void refine(const PassSpec& spec, ListState& l, PassStats& stats, std::size_t n, ListHost& host);

// Once the counts after a batch of rounds are read: whether the rounds are done, their
// statistics taken. Otherwise the next batch is planned, from a list grown where a
// round overflowed it (replayed) or from the seed where the seed did.
bool settle_list(const PassSpec& spec, ListState& l, PassStats& stats, ListHost& host);

}  // namespace cstreams::runtime
