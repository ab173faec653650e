#pragma once
// How deep the kept front may reach. Exact and no-front modes never change it; the
// deferred mode keeps the front within its memory budget by lowering the level cap
// and running the step again when the front would outgrow it, and raises the cap
// again once the front has shrunk well below the budget.
//
// On a device that ends loops early, a search from one front pair may run out of loop
// trips (cs_front_update); the step then runs again from a finer front, four times the
// pairs of the one it searched from, until no search does.
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cstreams {

class FrontControl {
public:
  FrontControl(const DetectorOptions& options, const SceneLayout& layout, std::size_t work_items,
               std::size_t work_group, bool bounded_loops);

  // The first cut of the BVTT: enough work for the device, within budget. The first
  // front from it: an exact front's finer where boxes overlap at the starting
  // positions, the others' the cut itself. The graph's first sizes follow the cut.
  std::vector<NodePair> first_cut() const;
  std::vector<NodePair> first_front(const std::vector<NodePair>& cut) const;
  // Gives a new scheduler the first front (seeds searched every step spread over the
  // work-groups that search them: spread_over_groups), its limits and the level cap.
  void install(runtime::Scheduler& scheduler, const CcdStreams& streams, const std::vector<NodePair>& seeds) const;
  // Runs the graph; returns how many runs were repeated at a coarser or finer front.
  unsigned run(runtime::Scheduler& scheduler, const CcdStreams& streams);
  std::uint32_t level_cap() const { return level_cap_; }

private:
  static constexpr std::uint32_t unbounded = 0xffffffffu;
  // Installs a front four times finer than the one the last run searched from, under
  // a level cap that does not fold it back; throws where it cannot get finer.
  void refine_front(runtime::Scheduler& scheduler, const CcdStreams& streams);

  FrontMode mode_;
  double budget_mb_;
  std::uint32_t level_cap_ = unbounded;
  std::uint32_t deepest_level_ = 0;
  std::size_t front_limit_ = 0;
  std::size_t target_;
  std::size_t work_group_;
  const SceneLayout* layout_;
  bool bounded_loops_;
};

}  // namespace cstreams
