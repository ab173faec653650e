#include "segment_pool.hpp"

#include <algorithm>
#include <functional>

namespace cstreams::runtime {

std::optional<Buffer> SegmentPool::take(std::size_t bytes, std::size_t room)
{
  const auto fits = smallest_holding(idle_, bytes, [](const Buffer& b) { return b.bytes(); });
  if (fits != idle_.end()) {
    const std::size_t excess = fits->bytes() - bytes;
    if (excess <= bytes / 8 || 2 * excess <= room) {
      Buffer taken = std::move(*fits);
      idle_.erase(fits);
      return taken;
    }
  }
  idle_.erase(std::remove_if(idle_.begin(), idle_.end(), [&](const Buffer& b) { return b.bytes() < bytes; }),
              idle_.end());
  return std::nullopt;
}

void SegmentPool::stage_done(std::vector<std::size_t> needs)
{
  if (!needs.empty()) stage_needs_.push_back(std::move(needs));
}

// Needs of this run's stages that buffers of these sizes would leave unserved, each
// stage's largest need first taking the smallest buffer that holds it; `served`, if
// given, gets the largest need each buffer served.
std::size_t SegmentPool::unserved(const std::vector<std::size_t>& sizes, std::vector<std::size_t>* served) const
{
  std::size_t count = 0;
  if (served) served->assign(sizes.size(), 0);
  for (const auto& needs : stage_needs_) {
    std::vector<std::size_t> free(sizes.size());  // indices into sizes
    for (std::size_t k = 0; k < free.size(); ++k) free[k] = k;
    for (const std::size_t need : needs) {
      const auto best = smallest_holding(free, need, [&](std::size_t k) { return sizes[k]; });
      if (best == free.end()) {
        ++count;
        continue;
      }
      if (served) (*served)[*best] = std::max((*served)[*best], need);
      free.erase(best);
    }
  }
  return count;
}

void SegmentPool::keep_needed()
{
  for (auto& needs : stage_needs_) std::sort(needs.begin(), needs.end(), std::greater<>());
  std::sort(idle_.begin(), idle_.end(), [](const Buffer& a, const Buffer& b) { return a.bytes() < b.bytes(); });
  const auto sizes_of = [](const std::vector<Buffer>& buffers) {
    std::vector<std::size_t> sizes;
    for (const auto& b : buffers) sizes.push_back(b.bytes());
    return sizes;
  };
  const std::size_t with_all = unserved(sizes_of(idle_));
  std::vector<Buffer> kept;
  for (std::size_t k = 0; k < idle_.size(); ++k) {
    std::vector<std::size_t> without = sizes_of(kept);
    for (std::size_t j = k + 1; j < idle_.size(); ++j) without.push_back(idle_[j].bytes());
    if (unserved(without) > with_all) kept.push_back(std::move(idle_[k]));
  }
  std::vector<std::size_t> served;
  unserved(sizes_of(kept), &served);
  idle_.clear();
  for (std::size_t k = 0; k < kept.size(); ++k)
    if (kept[k].bytes() <= served[k] + served[k] / 8 + (1u << 20)) idle_.push_back(std::move(kept[k]));
}

bool SegmentPool::release()
{
  const bool any = std::any_of(idle_.begin(), idle_.end(), [](const Buffer& b) { return bool(b); });
  idle_.clear();
  return any;
}

}  // namespace cstreams::runtime
