#include "front_control.hpp"

#include <cstreams/errors.hpp>

#include <algorithm>
#include <string>

namespace cstreams {

FrontControl::FrontControl(const DetectorOptions& options, const SceneLayout& layout, std::size_t work_items)
    : mode_(options.front), budget_mb_(options.front_budget_mb), target_(work_items)
{
  if (mode_ != FrontMode::deferred) return;
  if (!(budget_mb_ > 0)) throw InputError("the deferred front needs a positive memory budget");
  // Both front buffers share the budget.
  front_limit_ = std::size_t(budget_mb_ * 1024 * 1024) / (2 * sizeof(NodePair));
  target_ = std::min(target_, front_limit_ / 4);
  deepest_level_ = layout.depth > 0 ? 2 * std::uint32_t(layout.depth - 1) : 0;
  level_cap_ = deepest_level_;
}

void FrontControl::install(runtime::Scheduler& scheduler, const CcdStreams& streams,
                           const std::vector<NodePair>& seeds) const
{
  // Limits first: a limit below a stream's capacity reallocates it, losing what it held.
  if (mode_ == FrontMode::deferred) {
    scheduler.set_limit(streams.front, front_limit_);
    scheduler.set_limit(streams.next_front, front_limit_);
  }
  scheduler.upload(streams.front, seeds);
  scheduler.set(streams.level_cap, level_cap_);
}

unsigned FrontControl::run(runtime::Scheduler& scheduler, const CcdStreams& streams)
{
  unsigned retries = 0;
  for (;;) {
    try {
      scheduler.run();
      break;
    } catch (const runtime::StreamLimitExceeded& e) {
      if (mode_ != FrontMode::deferred || level_cap_ == 0)
        throw Error("the front does not fit its budget of " + std::to_string(budget_mb_) + " MiB even at the roots: " +
                    e.what());
      level_cap_ = level_cap_ > 2 ? level_cap_ - 2 : 0;
      scheduler.set(streams.level_cap, level_cap_);
      ++retries;
    }
  }
  if (mode_ == FrontMode::deferred && level_cap_ < deepest_level_ && scheduler.count(streams.next_front) < front_limit_ / 4)
    scheduler.set(streams.level_cap, ++level_cap_);
  return retries;
}

}  // namespace cstreams
