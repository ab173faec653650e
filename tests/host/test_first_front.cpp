// A detector's first front. The seeds a detector without a kept front searches every
// step: a cut of the BVTT whose pairs are dealt to the work-groups that search them so
// that no group takes one region of the trees alone. A kept front's first cut: finer
// where boxes overlap at the starting positions, in the trees' order.
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <set>
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

namespace {

// The BVTT parent of p, as cs_bvtt_parent (broad_phase.cl) climbs; (-1, -1) above a seed.
NodePair bvtt_parent(const SceneLayout& l, NodePair p)
{
  const auto &a = l.nodes[std::size_t(p[0])], &b = l.nodes[std::size_t(p[1])];
  const std::int32_t pa = a[2], pb = b[2];
  if (p[0] == p[1]) return pa < 0 ? NodePair{-1, -1} : NodePair{pa, pa};
  if (pa >= 0 && pa == pb) return {pa, pa};
  if (pa < 0 && pb < 0) return {-1, -1};
  return a[3] > b[3] ? NodePair{pa, p[1]} : NodePair{p[0], pb};
}

}  // namespace

TEST_CASE("a first front refined where boxes overlap is a cut in the coarse cut's order, deeper only there",
          "[detector][quick]")
{
  // A sphere that collides with itself, and a second one far from it: their pairs are
  // apart from the roots down.
  const auto sphere = scenes::icosphere(2, 1.0);
  std::vector<Vec3> far = sphere.positions;
  for (Vec3& v : far) v.x() += 10;
  SceneDescription scene;
  scene.add({"near", sphere.faces, sphere.positions});
  scene.add({"far", sphere.faces, far, ObjectKind::deformable, false});
  const SceneLayout layout = make_layout(scene, 0);
  const std::vector<NodePair> coarse = expand_front(layout, 16);
  const std::vector<NodePair> refined = expand_overlapping(layout, coarse, 8);
  REQUIRE(refined.size() > 4 * coarse.size());
  std::set<NodePair> in(refined.begin(), refined.end());
  REQUIRE(in.size() == refined.size());

  // Every pair of two leaves lies under exactly one refined pair, as under a cut (the
  // front update then finds each pair of faces once), in one of its two orders.
  std::vector<std::int32_t> leaves;
  for (std::size_t n = 0; n < layout.nodes.size(); ++n)
    if (layout.nodes[n][0] < 0) leaves.push_back(std::int32_t(n));
  const auto above = [&](NodePair p) {
    unsigned n = 0;
    for (; p[0] >= 0; p = bvtt_parent(layout, p)) n += unsigned(in.count(p));
    return n;
  };
  for (std::size_t x = 0; x < leaves.size(); ++x)
    for (std::size_t y = x + 1; y < leaves.size(); ++y) {
      const std::int32_t a = leaves[x], b = leaves[y];
      if (!scene.may_collide(layout.node_object[std::size_t(a)], layout.node_object[std::size_t(b)])) continue;
      if (above({a, b}) + above({b, a}) != 1) FAIL("leaves " << a << " and " << b);
    }

  // In the coarse cut's order, each coarse pair's own pairs together; the spheres' pairs
  // of each other, apart from the roots down, stay as the coarse cut holds them.
  std::map<NodePair, std::size_t> place;
  for (std::size_t k = 0; k < coarse.size(); ++k) place[coarse[k]] = k;
  // Where the boxes of a pair overlap, it lies the full eight levels below its coarse
  // pair, or holds two leaves.
  std::size_t last = 0, overlapping = 0;
  for (const NodePair& p : refined) {
    const bool across = layout.node_object[std::size_t(p[0])] != layout.node_object[std::size_t(p[1])];
    if (across) CHECK(place.count(p) == 1);
    unsigned levels = 0;
    NodePair q = p;
    for (; !place.count(q); ++levels) q = bvtt_parent(layout, q);
    CHECK(place[q] >= last);
    last = place[q];
    const bool leaves_only = layout.nodes[std::size_t(p[0])][0] < 0 && layout.nodes[std::size_t(p[1])][0] < 0;
    if (p[0] != p[1] && !leaves_only && layout.start_box(p[0]).overlaps(layout.start_box(p[1]))) {
      CHECK(levels == 8);
      ++overlapping;
    }
  }
  CHECK(overlapping > refined.size() / 8);
}
