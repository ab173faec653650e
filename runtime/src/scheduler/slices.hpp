#pragma once
// A run that goes on in slices where a pass finds no room even in a stage of its own:
// from a pass over one stream (Scheduler's class comment), the rest of the graph runs
// over slices of that stream, doubling them until a slice fits, and a later run starts
// from the number that fitted. Owns where slices start, how many, and what each slice
// reads and keeps; not how a pass executes (the run loop, through PassRunner). Private
// to the runtime.
#include "counters.hpp"
#include "pass_runner.hpp"
#include "registrar.hpp"
#include "scratch.hpp"
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class Context;

// The parts a sliced run works with.
struct SliceParts {
  Context& context;
  PassRunner& runner;
  Counters& counters;
  Registrar& registrar;
  Scratch& scratch;
  StreamBuffers& streams;
  std::vector<PassState>& passes;
  std::vector<const PassState*>& busy;
  RunStats& stats;
};

class Slices {
public:
  explicit Slices(const SliceParts& parts) : p_(parts) {}

  // The pass from which the run goes in slices (SIZE_MAX: none): a run after one that
  // went in slices starts them there at once.
  const std::size_t& sliced_pass() const { return sliced_pass_; }
  // Where the run stopped at `failure`: the rest of it in slices, from the pass it
  // names, or from the nearest pass before it that can be sliced where it had no room.
  // Rethrows its error where none can.
  void go_on(const Failure& failure);

private:
  bool sliceable(std::size_t first) const;
  std::size_t slice_start(std::size_t failed) const;
  std::size_t slice_items(StreamId over, std::size_t total) const;
  void run_in_slices(std::size_t first);
  void prepare_slices(std::size_t first, const std::vector<bool>& every_slice, const std::vector<StreamId>& outputs,
                      std::size_t count);
  void run_slices(std::size_t first, const std::vector<bool>& every_slice, const std::vector<StreamId>& outputs,
                  const std::vector<StreamId>& once, std::size_t size);
  void restart_slice(std::size_t first, const std::vector<bool>& every_slice, std::size_t k);

  SliceParts p_;
  std::size_t sliced_pass_ = SIZE_MAX;
  unsigned slices_ = 1;
  // Whether the slices are for want of memory, rather than for a work list's budget
  // (WorkListOverBudget): only then does idle scratch go back before them.
  bool short_of_memory_ = true;
  // The slices that pass `found_pass_` was last found to need, by doubling them, and its
  // input then (0: none yet). What a slice needs follows what it emits more than what
  // it reads (a front's first pairs expand into many, later ones into few), so a run
  // with more input starts from that number, and one with less takes as much fewer,
  // down to one.
  unsigned found_slices_ = 0;
  std::size_t found_input_ = 0, found_pass_ = SIZE_MAX;
};

}  // namespace cstreams::runtime
