#pragma once
// What the parts that execute passes again (Flush, which reruns what overflowed; Slices,
// which runs the rest of a graph slice by slice) ask of the run loop, which owns
// executing a pass and the stages (run_loop.cpp). Private to the runtime.
#include "states.hpp"
#include "work_list.hpp"

#include <cstreams/runtime/stream_graph.hpp>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <vector>

namespace cstreams::runtime {

// How much of a pass executes again: nothing, the packing of what its kernel registered
// (its outputs grew), or its kernel too.
enum class Redo { none, pack, full };

// Where a pass had no room even in a stage of its own (error set), or where the run
// goes on in slices (pass set).
struct Failure {
  std::exception_ptr error;
  std::size_t pass = SIZE_MAX;
  explicit operator bool() const { return pass != SIZE_MAX; }
};

class PassRunner {
public:
  // Executes p: its work list's rounds where they are not settled, its kernel where
  // `redo` is full, and the registration of what it emitted.
  virtual void execute(PassState& p, Redo redo) = 0;
  // What p's work list borrows from the run while its rounds run.
  virtual ListHost list_host(const PassState& p) = 0;
  // Whether a conditional pass does not run this run (its parameter is 0).
  virtual bool skipped(const PassSpec& spec) const = 0;
  // Executes p in the current stage, or says where the run cannot go on (Failure).
  virtual Failure step(PassState& p, std::vector<PassState*>& stage) = 0;
  // Flushes the stage and empties it.
  virtual Failure end_stage(std::vector<PassState*>& stage) = 0;

protected:
  ~PassRunner() = default;
};

}  // namespace cstreams::runtime
