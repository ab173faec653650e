#include "step_arena.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>

namespace cstreams::runtime {

StepArena::StepArena(Context& context)
    : context_(context), align_(std::max<std::size_t>(context.device().base_address_align, 1))
{
}

std::size_t StepArena::first_fit(std::size_t bytes, std::size_t ignored) const
{
  std::size_t place = 0;
  for (const auto& [at, size] : taken_) {
    if (at == ignored) continue;
    if (place + bytes <= at) break;
    place = std::max(place, round_up(at + size, align_));
  }
  return place;
}

Buffer StepArena::take(std::size_t bytes, const char* label, std::size_t& at)
{
  bytes = std::max<std::size_t>(bytes, 1);
  const std::size_t place = first_fit(bytes);
  Buffer taken = place + bytes <= buffer_.bytes() ? buffer_.slice(place, bytes) : Buffer(context_, bytes, label);
  taken_.emplace(place, bytes);
  high_water_ = std::max(high_water_, place + bytes);
  at = place;
  return taken;
}

bool StepArena::fits_without(std::size_t at, std::size_t bytes) const
{
  return first_fit(std::max<std::size_t>(bytes, 1), at) + std::max<std::size_t>(bytes, 1) <= buffer_.bytes();
}

void StepArena::give_back(std::size_t& at)
{
  if (at == none) return;
  taken_.erase(at);
  at = none;
}

void StepArena::start_run()
{
  const std::size_t want = high_water_, before = last_high_water_;
  last_high_water_ = high_water_;
  high_water_ = 0;
  if (!taken_.empty()) return;
  // A run that outgrew the one before by more than an eighth (the first step, searched
  // from the roots) says little about the next: a buffer of its size held the step after
  // it, and what that step outgrew came on top.
  if (want > before + before / 8) {
    buffer_ = Buffer();
    return;
  }
  // Within a sixteenth (and a MiB) of the plan the buffer stays: a step a little smaller
  // than the last allocates nothing. (Within an eighth, n-body kept the 7% more that
  // its first step, searched from the roots, had needed.)
  if (want > 0 && buffer_.bytes() >= want && buffer_.bytes() <= want + want / 16 + (std::size_t(1) << 20)) return;
  buffer_ = Buffer();
  const std::size_t limit = context_.memory_limit(), room = limit - std::min(limit, context_.memory_in_use());
  if (want == 0 || room / 2 < want) return;
  try {
    buffer_ = Buffer(context_, want, "step arena");
  } catch (const DeviceMemoryExhausted&) {
    return;
  }
  // NVIDIA's driver keeps a buffer no kernel has written where the host is, and moved
  // all of it to the device at the first use of each new slice: cloth-ball's step took
  // 150 ms instead of 2. Written once here, it stays on the device.
  context_.fill_u32(buffer_, 0, 0, want / 4);
}

std::vector<Buffer> StepArena::lend(const std::vector<std::size_t>& sizes) const
{
  std::vector<std::size_t> offsets;
  std::size_t end = 0;
  for (const std::size_t bytes : sizes) {
    offsets.push_back(end);
    end = round_up(end + std::max<std::size_t>(bytes, 1), align_);
  }
  std::vector<Buffer> slices;
  const std::size_t place = first_fit(end);
  if (sizes.empty() || place + end > buffer_.bytes()) return slices;
  for (std::size_t k = 0; k < sizes.size(); ++k)
    slices.push_back(buffer_.slice(place + offsets[k], std::max<std::size_t>(sizes[k], 1)));
  return slices;
}

bool StepArena::release()
{
  if (!taken_.empty() || !buffer_) return false;
  buffer_ = Buffer();
  return true;
}

}  // namespace cstreams::runtime
