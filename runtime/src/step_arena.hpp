#pragma once
#include <cstreams/runtime/buffer.hpp>

#include <cstddef>
#include <map>
#include <vector>

namespace cstreams::runtime {

class Context;

// One buffer for the memory that lives within a run: registration segments, and the
// streams that passes emit anew each run. Held apart, each in a buffer of its own kept
// from run to run, they add up: cloth-ball's next-front and triangle-pair segments, its
// triangle pairs and its candidates held 134 MB through every step, where no more
// than 102 MB of them are ever live at once (the front update's segments beside the
// triangle pairs they are packed into).
//
// What is taken gets the lowest place that is free from then until it is given back
// (first fit); the places are kept whether the buffer holds them or not, so that a
// run's high water is known even where it outgrew the buffer, which then lends a buffer
// of its own. The next run, which takes the same in the same order when its step is
// alike, starts from a buffer of that high water.
class StepArena {
public:
  static constexpr std::size_t none = ~std::size_t(0);

  explicit StepArena(Context& context);

  // Bytes at the lowest free place (a slice of the buffer, or a buffer of its own where
  // that place lies beyond it); `at` receives the place, to give it back by. Throws
  // DeviceMemoryExhausted, holding nothing, where a buffer of its own does not fit.
  Buffer take(std::size_t bytes, const char* label, std::size_t& at);
  void give_back(std::size_t& at);  // sets `at` to none
  // Whether `bytes` taken once what is at `at` went back would lie within the buffer,
  // so that taking them allocates nothing and cannot run short of memory.
  bool fits_without(std::size_t at, std::size_t bytes) const;
  // Between runs, with nothing taken: a buffer of the last run's high water, where that
  // run did not outgrow the one before by more than an eighth and the device has room
  // for it twice over (what outgrows it then still has room of its own); else none, and
  // what is taken gets buffers of its own.
  void start_run();
  // Slices of free space, one of each size, or none where no free run holds them all:
  // scratch that is not recorded, overwritten by the next take.
  std::vector<Buffer> lend(const std::vector<std::size_t>& sizes) const;
  // Gives the buffer back where nothing is taken; returns whether memory went back.
  bool release();

  std::size_t bytes() const { return buffer_.bytes(); }

private:
  // The lowest place where `bytes` are free, what is at `ignored` counted as free.
  std::size_t first_fit(std::size_t bytes, std::size_t ignored = none) const;

  Context& context_;
  std::size_t align_;
  Buffer buffer_;
  std::map<std::size_t, std::size_t> taken_;  // place -> bytes
  std::size_t high_water_ = 0;                // of this run's places
  std::size_t last_high_water_ = 0;           // of the last run's
};

}  // namespace cstreams::runtime
