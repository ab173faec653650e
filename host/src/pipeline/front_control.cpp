#include "front_control.hpp"

#include <cstreams/errors.hpp>

#include <algorithm>
#include <limits>
#include <string>

namespace cstreams {

FrontControl::FrontControl(const DetectorOptions& options, const SceneLayout& layout, std::size_t work_items,
                           std::size_t work_group, bool bounded_loops)
    : mode_(options.front), budget_mb_(options.front_budget_mb), target_(work_items), work_group_(work_group),
      layout_(&layout), bounded_loops_(bounded_loops)
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
  // Seeds searched every step are spread over the work-groups. A kept front is not: the
  // next front follows the order of the one it came from, and a front spread over the
  // trees made every later step's front update slower (H200, cloth-ball: 1.61 -> 1.83
  // ms a warm step), more than it saved on the first (12.8 -> 10.2 ms).
  scheduler.upload(streams.front, mode_ == FrontMode::none ? spread_over_groups(seeds, work_group_) : seeds);
  scheduler.set(streams.level_cap, level_cap_);
}

void FrontControl::refine_front(runtime::Scheduler& scheduler, const CcdStreams& streams)
{
  const auto front = scheduler.download<NodePair>(streams.front);
  const std::size_t most = mode_ == FrontMode::deferred ? front_limit_ : std::numeric_limits<std::size_t>::max();
  const std::vector<NodePair> seeds = expand_front(*layout_, front, std::min(4 * front.size(), most), most);
  if (seeds.size() <= front.size())
    throw Error("a search of the front still runs out of the device's loop trips from a front of " +
                std::to_string(front.size()) + " pairs, the finest there is" +
                (mode_ == FrontMode::deferred ? " within the front's budget" : ""));
  std::uint32_t deepest = 0;
  for (const auto& [a, b] : seeds)
    deepest = std::max(deepest, std::uint32_t(layout_->nodes[std::size_t(a)][3] + layout_->nodes[std::size_t(b)][3]));
  if (mode_ == FrontMode::deferred) level_cap_ = std::max(level_cap_, deepest);
  install(scheduler, streams, seeds);
}

unsigned FrontControl::run(runtime::Scheduler& scheduler, const CcdStreams& streams)
{
  unsigned retries = 0;
  for (;; ++retries) {
    if (bounded_loops_) scheduler.upload(streams.searches_cut, std::vector<std::uint32_t>{0, 1});
    try {
      scheduler.run();
      break;
    } catch (const runtime::RunStopped&) {
      refine_front(scheduler, streams);
    } catch (const runtime::StreamLimitExceeded& e) {
      if (mode_ != FrontMode::deferred || level_cap_ == 0)
        throw Error("the front does not fit its budget of " + std::to_string(budget_mb_) + " MiB even at the roots: " +
                    e.what());
      level_cap_ = level_cap_ > 2 ? level_cap_ - 2 : 0;
      scheduler.set(streams.level_cap, level_cap_);
    }
  }
  if (mode_ == FrontMode::deferred && level_cap_ < deepest_level_ && scheduler.count(streams.next_front) < front_limit_ / 4)
    scheduler.set(streams.level_cap, ++level_cap_);
  return retries;
}

}  // namespace cstreams
