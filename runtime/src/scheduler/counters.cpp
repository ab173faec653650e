#include "counters.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/primitives.hpp>

#include <algorithm>
#include <utility>

namespace cstreams::runtime {

Counters::Counters(Context& context, std::vector<PassState>& passes, std::size_t slots, Timeline* timeline)
    : context_(context), passes_(passes), timeline_(timeline)
{
  const std::size_t align_words = (context.device().base_address_align + 3) / 4;
  std::size_t words = slots;
  for (auto& p : passes_)
    if (p.list) {
      p.list->counts_at = round_up(words, align_words);
      words = p.list->counts_at + list_words;
    }
  host_.assign(std::max<std::size_t>(words, 1), 0);
  counters_ = Buffer(context, host_.size() * sizeof(std::uint32_t), "stream counters");
  next_ = Buffer(context, host_.size() * sizeof(std::uint32_t), "stream counters");
  for (auto& p : passes_)
    if (p.list) {
      p.list->counts = counters_.slice(p.list->counts_at * sizeof(std::uint32_t), list_count_bytes);
      p.list->next_counts = next_.slice(p.list->counts_at * sizeof(std::uint32_t), list_count_bytes);
    }
}

void Counters::start_run()
{
  if (!next_clear_) return clear_all();
  std::swap(counters_, next_);
  for (auto& p : passes_)
    if (p.list) std::swap(p.list->counts, p.list->next_counts);
  lists_cleared();
  next_clear_ = false;
}

void Counters::clear_all()
{
  context_.fill_u32(counters_, 0, 0, host_.size(), timeline_);
  lists_cleared();
}

void Counters::lists_cleared()
{
  for (auto& p : passes_)
    if (p.list) p.list->counts_clear = true;
}

void Counters::set(std::uint32_t slot, std::uint32_t value) { context_.fill_u32(counters_, value, slot, 1, timeline_); }

void Counters::clear_next()
{
  if (next_clear_) return;
  context_.fill_u32(next_, 0, 0, host_.size(), timeline_);
  next_clear_ = true;
}

void Counters::read() { context_.read(counters_, host_.data(), host_.size() * sizeof(std::uint32_t), 0, timeline_); }

}  // namespace cstreams::runtime
