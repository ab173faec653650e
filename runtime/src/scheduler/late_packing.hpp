#pragma once
// Outputs packed once their stage's counters are read (Registrar::packs_late): each
// takes a buffer of exactly its items, a handed-over one its input's (PassSpec::
// hand_over), where the segments packed before it lay; and the inputs that packing
// leaves spent. Owns which buffer such an output takes and what goes back before it;
// not the merge itself (Registrar), nor when a pass is done (Flush). Private to the
// runtime.
#include "counters.hpp"
#include "registrar.hpp"
#include "scratch.hpp"
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class StepArena;

class LatePacker {
public:
  // `sliced_pass`: the pass from which the run goes in slices (SIZE_MAX: none).
  LatePacker(StreamBuffers& streams, Scratch& scratch, Registrar& registrar, Counters& counters, StepArena& arena,
             std::vector<PassState>& passes, const std::size_t& sliced_pass)
      : streams_(streams), scratch_(scratch), registrar_(registrar), counters_(counters), arena_(arena),
        passes_(passes), sliced_pass_(sliced_pass)
  {
  }

  // After the stage's counters are read and no pass of it runs again: p's outputs that
  // pack late, in order, each taking a buffer of its items, then in the arena giving
  // its segments' place to the next.
  void pack(PassState& p);

private:
  void leave_spent_where_pressed(PassState& p, const EmitterState& e);
  void give_back_spent_inputs(PassState& p, std::size_t bytes);
  void hand_over(PassState& p, const EmitterState& e);
  void leave_spent(PassState& p, const EmitterState& e);
  std::size_t items(const EmitterState& e) const { return counters_[streams_.state(e.stream).slot]; }

  StreamBuffers& streams_;
  Scratch& scratch_;
  Registrar& registrar_;
  Counters& counters_;
  StepArena& arena_;
  std::vector<PassState>& passes_;
  const std::size_t& sliced_pass_;
};

}  // namespace cstreams::runtime
