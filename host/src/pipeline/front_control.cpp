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

std::vector<NodePair> FrontControl::first_cut() const { return expand_front(*layout_, target_); }

std::vector<NodePair> FrontControl::first_front(const std::vector<NodePair>& cut) const
{
  if (mode_ != FrontMode::exact) return cut;
  // A kept front's first cut is searched once, in the first step, down to the exact
  // front: each work-group searches the subtrees of its pairs, as long as its pairs'
  // together, and the groups near a fold of cloth take far longer than the rest. Eight
  // levels finer where boxes overlap, there are enough groups for the device to run
  // them in many waves, each over a smaller region of the trees, so that the long ones
  // overlap the others, and the front stays in the trees' order, which warm steps read
  // fastest. H200, the cold step's wall time, two calls: cloth-ball 9.2-9.7 -> 6.0-6.2
  // ms, n-body 11.4-13.5 -> 8.4-10.6, armadillo-rollers 6.5-7.6 -> 5.6-5.8, rod-twist
  // 4.9-5.0 -> 4.2-4.4 (four levels: 7.2, 9.0, 6.8, 4.5); warm steps within their
  // spread. The coarse cut's
  // pairs dealt to the groups in runs of eight gained about as much, but the front came
  // out of the trees' order and every warm step read it 3-8% slower. A deferred front
  // keeps the cut its budget allows.
  return expand_overlapping(*layout_, cut, 8);
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
