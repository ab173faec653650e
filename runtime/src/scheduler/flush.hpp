#pragma once
// The end of a stage: its counters read in one transfer (with the reads after the run
// whose writers are done), the passes whose outputs fit packed and done, and those that
// overflowed grown and run again, until none does. Owns what a counter read decides:
// which passes are done, what grows, how much runs again; not how a pass executes (the
// run loop, through PassRunner) nor where memory comes from (Scratch). Private to the
// runtime.
#include "counters.hpp"
#include "late_packing.hpp"
#include "pass_runner.hpp"
#include "registrar.hpp"
#include "run_reads.hpp"
#include "scratch.hpp"
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <functional>
#include <vector>

namespace cstreams::runtime {

// The parts a flush works with.
struct FlushParts {
  PassRunner& runner;
  Counters& counters;
  Registrar& registrar;
  LatePacker& packer;
  Scratch& scratch;
  StreamBuffers& streams;
  RunReads& run_reads;
  std::vector<PassState>& passes;
  std::vector<const PassState*>& busy;  // the passes whose scratch holds what is still needed
  RunStats& stats;
};

class Flush {
public:
  explicit Flush(const FlushParts& parts) : p_(parts) {}

  // Scheduler::on_counter_read.
  void on_counter_read(std::function<void()> work) { before_counter_read_ = std::move(work); }

  // Reads every counter of the stage in one transfer; grows what overflowed and
  // reruns its producer until nothing did. Short of memory for a pass's output where
  // the run may go on in slices from that pass, throws with failed_pass() set.
  void run(const std::vector<PassState*>& stage);
  std::size_t failed_pass() const { return failed_pass_; }

  // Before a pass executes again in full: the counters its kernel adds to start from
  // zero (from the items of earlier slices, for a gathered stream), whichever
  // registration it runs with now.
  void clear_counters(const PassState& p);
  // Before a counter read: the reads after the run whose streams' writers have all run
  // (or are skipped this run) are queued ahead of it, and come back with it. A writer
  // that runs again afterwards (a rerun, a later slice) queues the read anew.
  void queue_run_reads();

private:
  void read_counters();
  void settle_lists(const std::vector<PassState*>& stage);
  void out_of_memory(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing, PassState* q);
  void pack_done(const std::vector<PassState*>& stage, std::vector<PassState*>& packed,
                 std::vector<PassState*>& overflowing);
  void rerun_overflowing(const std::vector<PassState*>& stage, const std::vector<PassState*>& overflowing);
  Redo grow_overflowed(PassState& p, const std::function<bool()>& later_segments_back);
  bool grow_output(PassState& p, StreamId s, std::size_t needed, const std::function<bool()>& make_room);
  void rerun(PassState& p, Redo r);
  void finish(const std::vector<PassState*>& done);

  FlushParts p_;
  std::function<void()> before_counter_read_;
  std::size_t failed_pass_ = SIZE_MAX;
};

}  // namespace cstreams::runtime
