// The seeds a detector without a kept front searches every step: a cut of the BVTT whose
// pairs are dealt to the work-groups that search them so that no group takes one region
// of the trees alone.
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <vector>

using namespace cstreams;

TEST_CASE("seeds spread over work-groups are the same cut, each group's pairs from across it",
          "[detector][quick]")
{
  SceneDescription scene;
  scene.add({"cloth", scenes::icosphere(4, 1.0).faces, scenes::icosphere(4, 1.0).positions});
  const SceneLayout layout = make_layout(scene, 0);
  const std::vector<NodePair> front = expand_front(layout, 4000);
  REQUIRE(front.size() >= 4000);
  std::map<NodePair, std::size_t> place;
  for (std::size_t k = 0; k < front.size(); ++k) place[front[k]] = k;
  REQUIRE(place.size() == front.size());
  for (std::size_t group : {1, 32, 256, 10000}) {
    INFO("groups of " << group);
    const std::vector<NodePair> spread = spread_over_groups(front, group);
    std::vector<NodePair> a = front, b = spread;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    CHECK(a == b);
    // A group's pairs lie across the front, wherever the front holds several groups:
    // its first and last pairs are more than half the front apart.
    const std::size_t groups = (front.size() + group - 1) / group;
    for (std::size_t first = 0; first + group <= spread.size() && groups > 2; first += group) {
      std::size_t lo = front.size(), hi = 0;
      for (std::size_t k = first; k < first + group; ++k) {
        lo = std::min(lo, place[spread[k]]);
        hi = std::max(hi, place[spread[k]]);
      }
      if (group > 1) CHECK(hi - lo > front.size() / 2);
    }
  }
}
