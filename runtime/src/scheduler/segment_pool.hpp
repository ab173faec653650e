#pragma once
// Registration segments between stages, where a run does not use the step arena:
// segments hold a pass's items only until its stage's counters are read, then wait here
// for the passes of later stages (the front update's and decompose's, say, never hold
// items at once). Owns the idle buffers and which of them a run keeps; allocates
// nothing (the scheduler takes new segments where none here fits). Private to the runtime.
#include <cstreams/runtime/buffer.hpp>

#include <cstddef>
#include <optional>
#include <vector>

namespace cstreams::runtime {

class SegmentPool {
public:
  // The smallest idle buffer that holds `bytes`, where what it holds beyond them is
  // little, or fits `room` twice over: what a buffer holds beyond the need, the rest of
  // the stage cannot have. Where none is taken, the idle buffers too small go back:
  // held through the new allocation, they set the run's peak (cloth-ball's second step,
  // whose front update outgrew the buffers the first step's stages kept, held 336 MiB
  // where later steps hold 260), and the stages after this one can share the new one.
  std::optional<Buffer> take(std::size_t bytes, std::size_t room);
  void give_back(Buffer buffer) { idle_.push_back(std::move(buffer)); }
  // What a stage's emitters needed, once its counters are read.
  void stage_done(std::vector<std::size_t> needs);
  // A run starts: its stages' needs are counted afresh.
  void start_run() { stage_needs_.clear(); }
  // At the end of a run: buffers go back, smallest first, while the others would serve
  // this run's stages as well, so that the pool settles at what the stages need, each
  // buffer shared by as many as it can serve. Then those more than an eighth larger
  // than the most they served go back too (a burst that has passed, or segments sized
  // before a run had planned them), and the passes they served take buffers of their
  // size next run: a pool held for many steps holds what the steps plan.
  void keep_needed();
  // Gives every idle buffer back; returns whether there was any.
  bool release();
  const std::vector<Buffer>& idle() const { return idle_; }

private:
  std::size_t unserved(const std::vector<std::size_t>& sizes, std::vector<std::size_t>* served = nullptr) const;

  std::vector<Buffer> idle_;
  std::vector<std::vector<std::size_t>> stage_needs_;  // of this run, each stage's emitters'
};

// The smallest of `items` that holds `need` bytes (`bytes_of` an item), or end(): the
// one rule by which passes take idle segments and by which the pool works out which of
// them to keep.
template <class Items, class Bytes> auto smallest_holding(Items& items, std::size_t need, Bytes bytes_of)
{
  auto best = items.end();
  for (auto it = items.begin(); it != items.end(); ++it)
    if (bytes_of(*it) >= need && (best == items.end() || bytes_of(*it) < bytes_of(*best))) best = it;
  return best;
}

}  // namespace cstreams::runtime
