// The CCD graph a scene gets: the refit's levels, and only the passes and streams the
// scene needs.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"
#include "../support/test_scenes.hpp"
#include "detector_steps.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>

using namespace cstreams;
using namespace cstreams::test;

namespace {

std::vector<std::string> names(const std::vector<runtime::PassSpec>& passes)
{
  std::vector<std::string> out;
  for (const auto& p : passes) out.push_back(p.name);
  return out;
}

std::vector<std::string> names(const std::vector<runtime::StreamSpec>& streams)
{
  std::vector<std::string> out;
  for (const auto& s : streams) out.push_back(s.name);
  return out;
}

std::vector<std::string> names_of(const runtime::StreamGraph& g, const std::vector<runtime::StreamId>& streams)
{
  std::vector<std::string> out;
  for (const auto s : streams) out.push_back(g.stream(s).name);
  return out;
}

bool contains(const std::vector<std::string>& list, const std::string& item)
{
  return std::find(list.begin(), list.end(), item) != list.end();
}

ObjectDescription ball(const std::string& name, const Vec3& centre, ObjectKind kind, bool self)
{
  Mesh m = scenes::icosphere(1, 0.5);
  for (auto& p : m.positions) p += centre;
  return {name, m.faces, m.positions, kind, self};
}

}  // namespace

// The levels the refit passes go over, in their order: "refit level k" is level k,
// "refit levels t-b" levels b down to t.
std::vector<std::size_t> refitted_levels(const runtime::StreamGraph& g)
{
  std::vector<std::size_t> levels;
  for (const auto& p : g.passes()) {
    if (p.name.rfind("refit levels ", 0) == 0) {
      const std::size_t dash = p.name.find('-');
      const std::size_t top = std::stoul(p.name.substr(13, dash - 13));
      for (std::size_t k = std::stoul(p.name.substr(dash + 1)) + 1; k-- > top;) levels.push_back(k);
    } else if (p.name.rfind("refit level ", 0) == 0) {
      levels.push_back(std::stoul(p.name.substr(12)));
    }
  }
  return levels;
}

std::vector<std::size_t> levels_up_from(std::size_t depth)
{
  std::vector<std::size_t> levels(depth);
  for (std::size_t k = 0; k < depth; ++k) levels[k] = depth - 1 - k;
  return levels;
}

TEST_CASE("the refit goes over every level once, deepest first, as many a launch as a group can take",
          "[detector][quick]")
{
  // Trees of different depths in one forest: where one tree ends, a group's ranges below
  // are empty.
  SceneDescription scene;
  scene.add(ball("cloth", {0, 0, 0}, ObjectKind::deformable, true));
  scene.add({"small", {{0, 1, 2}, {0, 2, 3}}, {{2, 0, 0}, {3, 0, 0}, {3, 1, 0}, {2, 1, 0}}, ObjectKind::rigid, false});
  const SceneLayout layout = make_layout(scene, 0);
  for (std::size_t group : {1, 4, 64, 256}) {
    GraphDevice device;
    device.work_group_size = group;
    const auto g = build_ccd_graph(layout, DetectorOptions{}, expand_front(layout, 64).size(), device);
    INFO("work-group size " << group);
    CHECK(refitted_levels(g.graph) == levels_up_from(layout.depth));
    // A group of 2^k work-items takes k + 1 levels a launch, and the launch from the
    // roots k + 3.
    std::size_t per_launch = 1;
    while ((std::size_t(1) << per_launch) <= group) ++per_launch;
    std::size_t launches = 1;
    for (std::size_t rest = layout.depth; rest > per_launch + 2; rest -= per_launch) ++launches;
    const std::size_t passes = std::count_if(g.graph.passes().begin(), g.graph.passes().end(),
                                             [](const auto& p) { return p.name.rfind("refit", 0) == 0; });
    CHECK(passes == launches);
    // The groups of a band, one a node of its top level, cover each of its levels with
    // their ranges in order, each node once.
    const RefitPlan plan = plan_refit(layout, group);
    CHECK(g.refit_ranges == plan.ranges);
    for (const RefitBand& band : plan.bands)
      for (std::size_t d = 0; d < band.levels; ++d) {
        std::uint32_t next = layout.levels[band.top + d];
        for (std::size_t node = layout.levels[band.top]; node < layout.levels[band.top + 1]; ++node) {
          const auto range = plan.ranges[band.first_range + (node - layout.levels[band.top]) * band.levels + d];
          if (range[0] == range[1]) continue;
          CHECK(range[0] == next);
          next = range[1];
        }
        CHECK(next == layout.levels[band.top + d + 1]);
      }
  }
}

TEST_CASE("the graph models only what the scene needs", "[detector][quick]")
{
  DetectorOptions options;
  auto graph_of = [&](const SceneDescription& scene) {
    const SceneLayout layout = make_layout(scene, 0);
    return build_ccd_graph(layout, options, expand_front(layout, 64).size()).graph;
  };

  SECTION("one self-colliding deformable object")
  {
    SceneDescription scene;
    scene.add(ball("cloth", {0, 0, 0}, ObjectKind::deformable, true));
    const auto g = graph_of(scene);
    const auto passes = names(g.passes()), streams = names(g.streams());
    CHECK(contains(passes, "swept bounds"));
    CHECK(refitted_levels(g) == levels_up_from(make_layout(scene, 0).depth));
    CHECK(contains(passes, "front update"));
    CHECK(contains(passes, "cull orphan vf"));
    CHECK(contains(passes, "cull orphan ee"));
    const auto screen = std::find_if(g.passes().begin(), g.passes().end(),
                                     [](const auto& p) { return p.name == "test candidates"; });
    REQUIRE(screen != g.passes().end());
    CHECK(contains(names_of(g, runtime::pass_inputs(*screen)), "orphan ee candidates"));
    CHECK(contains(streams, "front"));
    CHECK(contains(streams, "next front"));
    CHECK(!contains(streams, "x0 double"));
  }
  SECTION("no self-collision: no orphans, and a lone object has no front at all")
  {
    SceneDescription scene;
    scene.add(ball("a", {0, 0, 0}, ObjectKind::deformable, false));
    auto g = graph_of(scene);
    CHECK(!contains(names(g.passes()), "front update"));
    CHECK(!contains(names(g.streams()), "orphan vf"));
    CHECK(contains(names(g.passes()), "swept bounds"));  // still refit: it moves

    scene.add(ball("b", {2, 0, 0}, ObjectKind::rigid, true));  // rigid: never self
    g = graph_of(scene);
    const auto passes = names(g.passes()), streams = names(g.streams());
    CHECK(contains(passes, "front update"));
    CHECK(!contains(passes, "cull orphan vf"));
    CHECK(!contains(streams, "orphan vf candidates"));
  }
  SECTION("static objects get no refit; static-static and masked pairs never enter the front")
  {
    SceneDescription scene;
    scene.add(ball("floor", {0, 0, 0}, ObjectKind::static_, true));
    scene.add(ball("wall", {1, 0, 0}, ObjectKind::static_, true));
    auto g = graph_of(scene);
    CHECK(names(g.passes()).empty());  // nothing moves and nothing may collide

    const auto mover = scene.add(ball("mover", {0, 1, 0}, ObjectKind::rigid, false));
    SceneLayout layout = make_layout(scene, 0);
    CHECK(layout.seeds.size() == 2);  // mover against each static object
    CHECK(layout.moving_faces == scene.objects[mover].faces.size());
    CHECK(layout.slots.front().object == mover);  // moving objects first
    g = graph_of(scene);
    // Bounds passes cover the mover only; static bounds are uploaded once. Vertices'
    // boxes are made where they are read.
    CHECK(contains(names(g.passes()), "swept bounds"));
    CHECK(refitted_levels(g) == levels_up_from(layout.trees[mover].depth()));
    CHECK(g.passes().front().items == layout.moving_faces + layout.moving_edges);

    scene.ignore(0, mover);
    scene.ignore(1, mover);
    CHECK(make_layout(scene, 0).seeds.empty());
    CHECK(!contains(names(graph_of(scene).passes()), "front update"));
  }
  SECTION("front mode none keeps no front; double precision adds exact positions and screens in float")
  {
    SceneDescription scene;
    scene.add(ball("cloth", {0, 0, 0}, ObjectKind::deformable, true));
    options.front = FrontMode::none;
    options.solver.precision = Precision::double_;
    const auto g = graph_of(scene);
    CHECK(contains(names(g.passes()), "search from seeds"));
    CHECK(!contains(names(g.streams()), "next front"));
    CHECK(contains(names(g.streams()), "x0 double"));
    // The refinement takes what the float screen leaves open, with no screen in double
    // between them.
    CHECK(!contains(names(g.passes()), "test candidates"));
    const auto screen = std::find_if(g.passes().begin(), g.passes().end(),
                                     [](const auto& p) { return p.name == "test candidates in float"; });
    REQUIRE(screen != g.passes().end());
    CHECK(contains(names_of(g, runtime::pass_inputs(*screen)), "ee candidates"));
    const auto refine = std::find_if(g.passes().begin(), g.passes().end(),
                                     [](const auto& p) { return p.name == "refine open queries"; });
    REQUIRE(refine != g.passes().end());
    CHECK(contains(names_of(g, runtime::pass_inputs(*refine)), "open queries"));
  }
}
