// The device pipeline through the public API, against the host reference.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"
#include "../support/test_scenes.hpp"

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

namespace {

// Runs one step of `scene` from `frame` through a detector built at that frame.
void run_step(Detector& detector, const Step& step)
{
  for (std::uint32_t o = 0; o < step.x0.size(); ++o)
    if (step.scene->objects[o].kind != ObjectKind::static_) detector.set_step(o, step.x0[o], step.x1[o]);
  detector.detect();
}

// The same contacts, feature by feature and time by time.
void check_same_contacts(const ContactSpan& a, const ContactSpan& b)
{
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].same_features(b[i]));
    CHECK(a[i].toi == b[i].toi);
  }
}

void check_candidates(const Scene& scene, std::size_t frame, const DetectorOptions& options)
{
  INFO("scene " << scene.name << ", frame " << frame << ", front " << to_string(options.front) << ", "
                << runtime::to_string(options.registration) << ", separation " << options.solver.min_separation);
  const Step step = load_step(scene, frame);
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  host.solver.min_separation = options.solver.min_separation;
  const Candidates expected = reference_broad_phase(step, host);
  Detector detector(cstreams::test::device(), describe(scene, frame), options);
  run_step(detector, step);
  const Candidates got = detector.candidates();
  CHECK(got.vf_count() == expected.vf_count());
  CHECK(got.ee_count() == expected.ee_count());
  CHECK(got == expected);
  CHECK(got.vf_count() > 0);
  // The same step again, the front now tracked from the last: the same pairs; and in
  // the steady state (a third time) nothing grows.
  run_step(detector, step);
  CHECK(detector.candidates() == expected);
  run_step(detector, step);
  for (const auto& p : detector.stats().run.passes) CHECK(p.reruns == 0);
}

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

TEST_CASE("device candidates equal the host's in float boxes, in every front mode", "[detector][quick]")
{
  const Scene f = cstreams::test::cloth_funnel();
  DetectorOptions options;
  for (auto front : {FrontMode::none, FrontMode::exact, FrontMode::deferred}) {
    options.front = front;
    options.solver.min_separation = 0;
    check_candidates(f, 0, options);
  }
  // With a minimum separation the broad phase widens every box; the candidates do not
  // depend on the solver, and the conservative one would spend its time (seconds on two
  // CPU cores) on thousands of pairs that hover at that distance.
  options.front = FrontMode::exact;
  options.solver.min_separation = 1e-3;
  options.solver.solver = Solver::cubic;
  check_candidates(f, 0, options);
  options.solver.solver = Solver::conservative;

  // Multi-object scenes: cloth against a static sphere, and tumbling rigid bodies.
  options.solver.min_separation = 0;
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 40);
  check_candidates(cloth, 33, options);
  Scene bart = cstreams::test::generated_scene("bart", 12, 0);
  bart.ignored_pairs.emplace_back(0, 1);
  bart.ignored_pairs.emplace_back(2, 5);
  options.registration = runtime::Registration::lock_free;
  check_candidates(bart, 8, options);
}

// Two triangles in one plane move along x. Passing the same place a step apart, their
// swept boxes overlap while their features never come near: the decomposition leaves
// every feature pair out. Moving into each other, it keeps what meets.
TEST_CASE("the decomposition leaves out features that pass the same place at different times", "[detector][quick]")
{
  const std::vector<Vec3> a0{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, b0{{3, 0, 0}, {4, 0, 0}, {3, 1, 0}};
  const auto moved = [](std::vector<Vec3> x, double dx) {
    for (auto& p : x) p.x() += dx;
    return x;
  };
  SceneDescription scene;
  const std::uint32_t a = scene.add({"a", {{0, 1, 2}}, a0}), b = scene.add({"b", {{0, 1, 2}}, b0});
  Detector detector(cstreams::test::device(), scene);
  // a's tip reaches x = 3.5 at the end; b starts at x = 3 and moves on by 2.
  detector.set_step(a, a0, moved(a0, 2.5));
  detector.set_step(b, b0, moved(b0, 2));
  detector.detect();
  CHECK(detector.stats().triangle_pairs == 1);
  CHECK(detector.stats().vf_candidates == 0);
  CHECK(detector.stats().ee_candidates == 0);
  CHECK(detector.contacts().empty());

  detector.set_step(a, a0, moved(a0, 2.5));
  detector.set_step(b, b0, moved(b0, -2.5));
  detector.detect();
  CHECK(detector.stats().vf_candidates > 0);
  CHECK(detector.stats().ee_candidates > 0);
  CHECK(!detector.contacts().empty());
}

namespace {

// Contacts of every step of `scene` through one detector fed frame by frame; `retries`
// adds up the steps' repeated runs.
std::vector<std::vector<Contact>> run_frames(const Scene& scene, const DetectorOptions& options, std::size_t first,
                                             std::size_t last, DetectorStats* deepest = nullptr,
                                             runtime::Context& context = cstreams::test::device(),
                                             unsigned* retries = nullptr)
{
  Detector detector(context, describe(scene, first), options);
  std::vector<std::vector<Contact>> out;
  for (std::size_t frame = first; frame < last; ++frame) {
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].kind != ObjectKind::static_) detector.set_positions(o, scene.positions(o, frame + 1));
    detector.detect();
    out.push_back(detector.contacts());
    if (deepest && detector.stats().front_pairs >= deepest->front_pairs) *deepest = detector.stats();
    if (retries) *retries += detector.stats().front_retries;
  }
  return out;
}

bool same(const std::vector<std::vector<Contact>>& a, const std::vector<std::vector<Contact>>& b)
{
  if (a.size() != b.size()) return false;
  for (std::size_t f = 0; f < a.size(); ++f) {
    if (a[f].size() != b[f].size()) return false;
    for (std::size_t i = 0; i < a[f].size(); ++i)
      if (!a[f][i].same_features(b[f][i]) || a[f][i].toi != b[f][i].toi) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("front modes, registrations and tiny capacities report identical contacts over many frames",
          "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  DetectorOptions options;
  options.front = FrontMode::none;
  const auto expected = run_frames(cloth, options, 10, 29);
  std::size_t total = 0;
  for (const auto& c : expected) total += c.size();
  CHECK(total > 100);

  DetectorStats exact_stats, deferred_stats;
  options.front = FrontMode::exact;
  CHECK(same(run_frames(cloth, options, 10, 29, &exact_stats), expected));
  options.front = FrontMode::deferred;
  // A budget far below the exact front's: it must be kept at coarser levels.
  options.front_budget_mb = double(exact_stats.front_pairs * 8 * 2) / 4 / (1024 * 1024);
  CHECK(same(run_frames(cloth, options, 10, 29, &deferred_stats), expected));
  CHECK(deferred_stats.front_pairs < exact_stats.front_pairs);
  CHECK(deferred_stats.front_level_cap < 2 * 20);

  options.front = FrontMode::exact;
  options.registration = runtime::Registration::lock_free;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
  options.registration = runtime::Registration::global_atomic;
  options.initial_capacity = 1;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
  options.registration = runtime::Registration::segmented_lock;
  options.front = FrontMode::deferred;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
}

// An exact front tracked over many steps climbs wherever boxes have moved apart, so that
// it is the very cut a search from the roots finds for the same step in the same trees
// (both detectors build their BVHs from the same first frame); a front that failed to
// climb would still find every contact, but grow step after step.
TEST_CASE("an exact front tracked over many steps is the one a search from the roots finds", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  DetectorOptions options;
  options.front = FrontMode::exact;
  constexpr std::size_t first = 10, last = 29;
  Detector tracked(cstreams::test::device(), describe(cloth, first), options);
  for (std::size_t frame = first; frame < last; ++frame) run_step(tracked, load_step(cloth, frame));
  Detector searched(cstreams::test::device(), describe(cloth, first), options);
  run_step(searched, load_step(cloth, last - 1));
  CHECK(tracked.stats().front_pairs > 0);
  CHECK(searched.stats().front_pairs == tracked.stats().front_pairs);
  CHECK(searched.stats().triangle_pairs == tracked.stats().triangle_pairs);
  CHECK(same({searched.contacts()}, {tracked.contacts()}));
}

TEST_CASE("a device that ends loops early reports the same contacts, searching from finer fronts",
          "[detector][quick]")
{
  // Mesa's llvmpipe ends a work-item's loops after 65535 trips in all. A context asked
  // for a far lower limit makes any device work as if it did: a search that runs out of
  // trips stops the step, which runs again from a front four times finer, and the
  // refinement's rounds go over exactly their items.
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  runtime::Context limited(filter_from_environment(), 0, 2048);
  REQUIRE(limited.loop_trip_limit() == 2048);
  DetectorOptions options;
  // Searches of 64 trips need a front finer than the default budget holds; a deferred
  // front that cannot get fine enough within its budget is an error (below).
  options.front_budget_mb = 64;
  for (auto front : {FrontMode::none, FrontMode::exact, FrontMode::deferred}) {
    INFO(to_string(front));
    options.front = front;
    unsigned retries = 0;
    CHECK(same(run_frames(cloth, options, 10, 16, nullptr, limited, &retries), run_frames(cloth, options, 10, 16)));
    CHECK(retries > 0);
  }
  options.front_budget_mb = 0.125;
  CHECK_THROWS_WITH(run_frames(cloth, options, 10, 11, nullptr, limited),
                    Catch::Contains("runs out of the device's loop trips") && Catch::Contains("within the front's budget"));
}

namespace {

// The conservative refinement's pass of a step (no name where the step had none).
runtime::PassStats refinement(const DetectorStats& stats)
{
  for (const auto& p : stats.run.passes)
    if (p.name == "refine open queries") return p;
  return {};
}

// `scene`'s positions in `frame`, moved by `shift`.
std::vector<Vec3> shifted(const Scene& scene, std::uint32_t object, std::size_t frame, const Vec3& shift)
{
  std::vector<Vec3> x = scene.positions(object, frame);
  for (Vec3& p : x) p += shift;
  return x;
}

// Steps `scene` from frame 0 through two detectors, one reporting contacts and one
// (on `earliest_device`) only the earliest times, and checks that they give the same
// times, object by object. `start` is where the first step starts from (frame 0's
// positions where empty).
struct EarliestRun {
  std::uint64_t all_boxes = 0, earliest_boxes = 0;  // refined, over the steps
  std::size_t at_zero = 0, later = 0;               // objects' earliest times: 0, and in (0, 1)
  std::size_t all_contacts = 0, earliest_contacts = 0;  // settled, over the steps
  std::size_t earliest_peak = 0;                    // the most the earliest times' device held
  unsigned sliced = 0;                              // their steps that ran in slices
};

EarliestRun compare_earliest(const Scene& scene, std::size_t steps, const DetectorOptions& options,
                             runtime::Context& earliest_device = cstreams::test::device(),
                             const SceneDescription& start = {})
{
  const SceneDescription first = start.objects.empty() ? describe(scene, 0) : start;
  Detector all(cstreams::test::device(), first, options);
  Detector earliest(earliest_device, first, options);
  EarliestRun run;
  for (std::size_t frame = 0; frame < steps; ++frame) {
    INFO("frame " << frame);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].kind != ObjectKind::static_) {
        all.set_positions(o, scene.positions(o, frame + 1));
        earliest.set_positions(o, scene.positions(o, frame + 1));
      }
    all.detect();
    earliest.detect(Report::earliest_toi);
    const std::vector<double> expected = all.earliest_toi();
    CHECK(earliest.earliest_toi() == expected);
    run.at_zero += std::count(expected.begin(), expected.end(), 0.0);
    run.later += std::count_if(expected.begin(), expected.end(), [](double t) { return t > 0 && t < 1; });
    run.all_boxes += refinement(all.stats()).list_items;
    run.earliest_boxes += refinement(earliest.stats()).list_items;
    run.all_contacts += all.stats().contacts;
    run.earliest_contacts += earliest.stats().contacts;
    run.earliest_peak = std::max(run.earliest_peak, earliest.stats().peak_bytes);
    run.sliced += earliest.stats().run.slices > 1;
  }
  UNSCOPED_INFO("boxes " << run.all_boxes << " against " << run.earliest_boxes << "; earliest times at 0: "
                         << run.at_zero << ", later: " << run.later);
  return run;
}

}  // namespace

// Report::earliest_toi lets the conservative refinement give up the queries that can no
// longer hold an object's earliest time (refine.cl): where a contact found for each of
// its objects is earlier than the query's answer can be (bodies colliding at different
// times), or where its objects already touch at time 0 (a cloth with a vertex on one
// of its faces at the start). The cubic test skips the pairs whose features stay apart
// until then (narrow_phase_pairs.cl). The times must stay the full list's, object by
// object.
TEST_CASE("earliest times alone equal the full list's, object by object, with less refinement", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 24, 40);
  const Scene funnel = cstreams::test::cloth_funnel();
  // The funnel starting with one vertex on a vertex of its last face: a contact at 0.
  SceneDescription touching_start = describe(funnel, 0);
  {
    std::vector<Vec3>& x = touching_start.objects[0].positions;
    const auto& face = touching_start.objects[0].faces.back();
    std::uint32_t moved = 0;
    while (moved == face[0] || moved == face[1] || moved == face[2]) ++moved;
    x[moved] = x[face[0]];
  }
  for (auto solver : {Solver::conservative, Solver::cubic})
    for (auto precision : {Precision::single, Precision::double_}) {
      INFO(to_string(solver) << ", " << to_string(precision));
      if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
      DetectorOptions options;
      options.solver.solver = solver;
      options.solver.precision = precision;
      const EarliestRun apart = compare_earliest(bodies, bodies.frame_count() - 1, options);
      CHECK(apart.later > 0);
      if (solver == Solver::cubic) {
        // Which pairs skip depends on which contacts the device found first (pocl: the
        // bodies' 42,612 contacts over their steps settle 26,495), so only the times are
        // checked; the skip itself is tested in test_narrow_phase.
        const EarliestRun touching = compare_earliest(funnel, 1, options, cstreams::test::device(), touching_start);
        CHECK(touching.at_zero == 1);
        CHECK(apart.earliest_contacts <= apart.all_contacts);
        continue;
      }
      // In double the bodies' queries start from the times they can be coplanar at, and
      // settle in a few rounds, before contacts found elsewhere give any of them up.
      if (precision == Precision::single) CHECK(apart.earliest_boxes < apart.all_boxes);
      else CHECK(apart.earliest_boxes <= apart.all_boxes);
      if (precision == Precision::single) {
        const EarliestRun touching = compare_earliest(funnel, 1, options, cstreams::test::device(), touching_start);
        CHECK(touching.at_zero == 1);
        CHECK(touching.earliest_boxes < touching.all_boxes / 4);
      }
    }
}

namespace {

// One step of `scene` from frame 0, every position moved by `shift`.
std::vector<Contact> step_contacts(const Scene& scene, const Vec3& shift, Precision precision)
{
  DetectorOptions options;
  options.solver.precision = precision;
  SceneDescription start = describe(scene, 0);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) start.objects[o].positions = shifted(scene, o, 0, shift);
  Detector detector(cstreams::test::device(), start, options);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) detector.set_positions(o, shifted(scene, o, 1, shift));
  detector.detect();
  return detector.contacts();
}

double earliest(const std::vector<Contact>& contacts)
{
  double t = 1;
  for (const Contact& c : contacts) t = std::min(t, c.toi);
  return t;
}

}  // namespace

// Positions that are floats are the input itself: single precision bounds them exactly
// (round_to_float, CcdStreams::exact_floats) rather than within half an ulp. The
// funnel's frames are floats: in single precision it must then report every pair that
// double precision does, no later, and few more. The same floats taken as rounded (the
// positions moved by 2^-40, under half an ulp) report more than twice as many.
TEST_CASE("single precision takes positions that are floats as the input itself", "[detector][quick]")
{
  const Scene funnel = cstreams::test::cloth_funnel();
  const std::vector<Contact> floats = step_contacts(funnel, Vec3::Zero(), Precision::single);
  const std::vector<Contact> rounded = step_contacts(funnel, {0x1p-40, 0, 0}, Precision::single);
  INFO(floats.size() << " contacts from floats, " << rounded.size() << " from the same floats rounded");
  CHECK(earliest(floats) > 0);
  CHECK(2 * floats.size() < rounded.size());
  if (!cstreams::test::device().device().fp64) return;
  const std::vector<Contact> exact = step_contacts(funnel, Vec3::Zero(), Precision::double_);
  INFO(exact.size() << " in double");
  REQUIRE(!exact.empty());
  for (const Contact& e : exact) {
    const auto found = std::find_if(floats.begin(), floats.end(), [&](const Contact& c) { return c.same_features(e); });
    REQUIRE(found != floats.end());
    // No later than the first contact, which is no later than double's time moved
    // forward by the tolerance (by which it may have been moved back, rounded down).
    CHECK(found->toi <= e.toi + 1.001 * SolverOptions().tolerance);
  }
  CHECK(10 * floats.size() <= 11 * exact.size());
}

// A first step sizes the refinement's work lists from its queries, and the funnel's
// late rounds outgrow them: the round that overflows runs again once they have grown
// (a replay), and the step must refine exactly as one whose lists were large enough
// from the start, the same step run again: the same boxes, rounds and contacts. A
// quiet step after them needs far smaller lists, and holds no more.
TEST_CASE("a refinement whose work list overflows goes on as one that never did", "[detector][quick]")
{
  const Scene funnel = cstreams::test::cloth_funnel();
  // Double precision settles the funnel in rounds that fit its first lists; in single
  // precision, positions that are not floats (moved by 2^-40) refine many more boxes.
  const Vec3 shift(0x1p-40, 0, 0);
  DetectorOptions options;
  options.solver.precision = Precision::single;
  Detector detector(cstreams::test::device(), describe(funnel, 0), options);
  std::vector<std::vector<Contact>> contacts;
  std::vector<runtime::PassStats> refined;
  for (int run = 0; run < 2; ++run) {
    for (std::uint32_t o = 0; o < funnel.objects.size(); ++o)
      if (funnel.objects[o].kind != ObjectKind::static_)
        detector.set_step(o, shifted(funnel, o, 0, shift), shifted(funnel, o, 1, shift));
    detector.detect();
    contacts.push_back(detector.contacts());
    refined.push_back(refinement(detector.stats()));
    REQUIRE(refined.back().name == "refine open queries");
  }
  CHECK(refined[0].reruns > 0);
  CHECK(refined[1].reruns == 0);
  CHECK(refined[0].list_items == refined[1].list_items);
  CHECK(refined[0].rounds == refined[1].rounds);
  CHECK(!contacts[0].empty());
  CHECK(same({contacts[0]}, {contacts[1]}));
  // A step at rest refines little: the lists grown for the funnel go back.
  for (std::uint32_t o = 0; o < funnel.objects.size(); ++o)
    if (funnel.objects[o].kind != ObjectKind::static_)
      detector.set_step(o, funnel.positions(o, 0), funnel.positions(o, 0));
  detector.detect();
  const runtime::PassStats at_rest = refinement(detector.stats());
  REQUIRE(at_rest.name == "refine open queries");
  INFO(refined[1].scratch_bytes << " bytes of work lists and state after the funnel's step, " << at_rest.scratch_bytes
                                << " after one at rest");
  CHECK(4 * at_rest.scratch_bytes < refined[1].scratch_bytes);
}

// Short of memory, a step runs the passes from the one that does not fit onwards in
// slices of its input, each refining its own queries: a slice's contacts give up only
// queries of the same slice, and the times must still be the full list's.
TEST_CASE("earliest times alone stay the full list's when a memory budget runs steps in slices", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 24, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const DetectorOptions options;
  runtime::Context unlimited(filter_from_environment());
  const std::size_t peak = compare_earliest(bodies, steps, options, unlimited).earliest_peak;
  unsigned sliced = 0;
  for (const double share : {0.8, 0.75, 0.7, 0.6, 0.5}) {
    runtime::Context limited(filter_from_environment());
    limited.set_memory_limit(std::size_t(share * double(peak)));
    INFO("budget " << share << " of the unbudgeted peak, " << peak << " bytes");
    try {
      sliced += compare_earliest(bodies, steps, options, limited).sliced;
    } catch (const runtime::DeviceMemoryExhausted&) {
      CHECK(share < 0.8);
    }
  }
  CHECK(sliced > 0);
}

// Split into their connected components (n-body's balls, the armadillo and its
// rollers), the real steps have many objects and contacts at many times.
TEST_CASE("earliest times alone equal the full list's on real steps split into their bodies", "[detector][slow]")
{
  for (const auto& s : {cstreams::test::real_steps[3], cstreams::test::real_steps[2]}) {
    const std::string dir = cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/frames/");
    const Scene scene = scene_from_frames({dir + s.frame0, dir + s.frame1}, true);
    INFO("scene " << s.scene << ", " << scene.objects.size() << " objects");
    REQUIRE(scene.objects.size() > 1);
    for (auto precision : {Precision::single, Precision::double_}) {
      if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
      INFO(to_string(precision));
      DetectorOptions options;
      options.solver.precision = precision;
      const EarliestRun run = compare_earliest(scene, 1, options);
      CHECK(run.at_zero + run.later > 1);
      // In double, armadillo-rollers' queries start from the times they can be coplanar
      // at and settle in two rounds, before contacts found elsewhere give any of them up.
      if (precision == Precision::single) CHECK(run.earliest_contacts < run.all_contacts);
      else CHECK(run.earliest_contacts <= run.all_contacts);
    }
  }
}

TEST_CASE("device contacts equal the solver's on the host's candidates, in both precisions", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 40);
  const Step step = load_step(cloth, 33);
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  const Candidates candidates = reference_broad_phase(step, host);
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    DetectorOptions options;
    options.solver.precision = precision;
    const auto& device = cstreams::test::device().device();
    if (precision == Precision::double_ && !device.fp64) {
      CHECK_THROWS_WITH(Detector(cstreams::test::device(), describe(cloth, 33), options),
                        Catch::Contains("neither cl_khr_fp64 nor cl_amd_fp64"));
      continue;
    }
    Detector detector(cstreams::test::device(), describe(cloth, 33), options);
    run_step(detector, step);
    std::vector<Contact> expected;
    DeviceSolver elementary(cstreams::test::device(), options.solver);
    for (const auto& block : candidates.blocks) {
      std::vector<Query> vf, ee;
      for (const auto& p : block.vf) vf.push_back(vertex_face_query(step, block.object_a, block.object_b, p));
      for (const auto& p : block.ee) ee.push_back(edge_edge_query(step, block.object_a, block.object_b, p));
      const auto rv = elementary.solve(ContactKind::vertex_face, vf), re = elementary.solve(ContactKind::edge_edge, ee);
      for (std::size_t i = 0; i < vf.size(); ++i)
        if (rv[i].collides()) expected.push_back(make_contact(step, block.object_a, block.object_b, block.vf[i], rv[i].toi));
      for (std::size_t i = 0; i < ee.size(); ++i)
        if (re[i].collides()) expected.push_back(make_contact(step, block.object_a, block.object_b, block.ee[i], re[i].toi));
    }
    sort_canonical(expected);
    const auto& got = detector.contacts();
    REQUIRE(got.size() == expected.size());
    bool inter_object = false;
    for (std::size_t i = 0; i < got.size(); ++i) {
      CHECK(got[i].same_features(expected[i]));
      CHECK(got[i].toi == expected[i].toi);
      inter_object |= got[i].object_a != got[i].object_b;
    }
    CHECK(inter_object);

    // Earliest times per object, without the list: the list's minimum, rounded down.
    const auto earliest = detector.earliest_toi();
    for (std::uint32_t o = 0; o < cloth.objects.size(); ++o) {
      double first = 1;
      for (const auto& c : got)
        if (c.object_a == o || c.object_b == o) first = std::min(first, c.toi);
      CHECK(earliest[o] <= first);
      CHECK(earliest[o] >= double(std::nextafter(float(first), 0.0f)));
    }
    detector.detect(Report::earliest_toi);
    CHECK_THROWS_WITH(detector.contacts(), Catch::Contains("earliest"));
  }
}

// The sort's last pass on records made by hand, merged as one run (so in the order
// given): the host reads its output as Contacts, so every field must land where
// Contact keeps it, whatever bits the scene gives ids (fields that straddle words too),
// and a float time must widen to the very double the float is (subnormals too, which
// the kernel widens bit by bit).
TEST_CASE("contacts come back laid out as the host's Contact, times widened exactly", "[detector][quick]")
{
  runtime::Context& context = cstreams::test::device();
  context.programs().add_sources(ccd_kernel_sources());
  constexpr cl_uint block = 8;
  const float floats[] = {0.0f,
                          std::numeric_limits<float>::denorm_min(),
                          3e-40f,
                          std::nextafter(std::numeric_limits<float>::min(), 0.0f),
                          std::numeric_limits<float>::min(),
                          1e-7f,
                          0.7f,
                          1.0f};
  const double doubles[] = {0.0, std::numeric_limits<double>::denorm_min(), 1e-310, 0.3, 1.0 - 1e-16, 1.0};
  // (object bits, vertex bits): the widest ids, and fields that end mid-word.
  for (const auto& [object_bits, vertex_bits] : {std::pair<cl_uint, cl_uint>{31, 32}, {3, 13}, {0, 7}})
    for (const bool double_time : {false, true}) {
      INFO((double_time ? "double" : "single") << " times, " << object_bits << " object bits, " << vertex_bits
                                                << " vertex bits");
      const cl_uint time_bits = double_time ? 64 : 32;
      const cl_uint words = (1 + 2 * object_bits + 4 * vertex_bits + time_bits + 31) / 32;
      const auto below = [](cl_uint bits, std::uint64_t x) {
        return bits == 0 ? 0 : x & ((std::uint64_t(1) << bits) - 1);
      };
      std::vector<std::uint32_t> records;
      std::vector<Contact> expected;
      const std::size_t n = double_time ? std::size(doubles) : std::size(floats);
      REQUIRE(n <= block);  // one block: one run, merged with nothing
      for (std::size_t i = 0; i < n; ++i) {
        Contact c;
        c.kind = i % 2 ? ContactKind::edge_edge : ContactKind::vertex_face;
        c.object_a = std::uint32_t(below(object_bits, 0x7fffffffu - i));
        c.object_b = std::uint32_t(below(object_bits, 7 * i));
        c.v = {std::uint32_t(below(vertex_bits, 11 + i)), std::uint32_t(below(vertex_bits, 4000000000u - i)),
               std::uint32_t(below(vertex_bits, 13)), std::uint32_t(below(vertex_bits, 3000000000u + 5 * i))};
        std::uint64_t time_field;
        if (double_time) {
          std::memcpy(&time_field, &doubles[i], sizeof time_field);
          c.toi = doubles[i];
        } else {
          std::uint32_t bits;
          std::memcpy(&bits, &floats[i], sizeof bits);
          time_field = bits;
          c.toi = double(floats[i]);
        }
        expected.push_back(c);
        // Fields most significant first, bit by bit.
        std::vector<std::uint32_t> record(words, 0);
        std::size_t at = 0;
        const auto put = [&](std::uint64_t value, cl_uint bits) {
          for (cl_uint b = bits; b-- > 0; ++at)
            if (value >> b & 1) record[at / 32] |= 0x80000000u >> (at % 32);
        };
        put(i % 2, 1);
        put(c.object_a, object_bits);
        put(c.object_b, object_bits);
        for (const std::uint32_t v : c.v) put(v, vertex_bits);
        put(time_field, time_bits);
        records.insert(records.end(), record.begin(), record.end());
      }
      const runtime::Kernel merge_last = context.programs().kernel("ccd/contacts.cl", "cs_contacts_merged",
                                                                   "-DCS_SORT_WORDS=" + std::to_string(words));
      runtime::Buffer in(context, records.size() * sizeof(std::uint32_t), "records");
      runtime::Buffer out(context, n * sizeof(Contact), "contacts");
      context.write(in, records.data(), records.size() * sizeof(std::uint32_t));
      merge_last.set_args(in, cl_uint(n), block, block, cl_uint(double_time), object_bits, vertex_bits, out);
      merge_last.set_local(8, block * words * sizeof(cl_uint));
      context.launch(merge_last, context.work_group_size(), context.work_group_size());
      std::vector<Contact> got(n);
      context.read(out, got.data(), n * sizeof(Contact));
      for (std::size_t i = 0; i < n; ++i) {
        INFO("contact " << i);
        CHECK(got[i].kind == expected[i].kind);
        CHECK(got[i].object_a == expected[i].object_a);
        CHECK(got[i].object_b == expected[i].object_b);
        CHECK(got[i].v == expected[i].v);
        CHECK(got[i].toi == expected[i].toi);
      }
    }
}

TEST_CASE("bad input at the API is a clear error and the detector stays usable", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 30);
  Detector detector(cstreams::test::device(), describe(cloth, 30));
  const Step step = load_step(cloth, 30);
  run_step(detector, step);
  const std::vector<Contact> before = detector.contacts();
  REQUIRE(!before.empty());

  const std::uint32_t sheet = detector.object("cloth"), sphere = detector.object("sphere");
  CHECK_THROWS_WITH(detector.object("table"), Catch::Contains("no object named 'table'"));
  CHECK_THROWS_WITH(detector.set_positions(7, step.x1[0]), Catch::Contains("no object 7"));
  CHECK_THROWS_WITH(detector.set_positions(sphere, step.x1[sphere]), Catch::Contains("'sphere' is static"));
  auto fewer = step.x1[sheet];
  fewer.pop_back();
  CHECK_THROWS_WITH(detector.set_positions(sheet, fewer), Catch::Contains("vertices, not " + std::to_string(fewer.size())));
  // The step's start, where the cloth is not now, but for one coordinate.
  auto nan = step.x0[sheet];
  nan[17].y() = std::nan("");
  CHECK_THROWS_AS(detector.set_step(sheet, step.x0[sheet], nan), InputError);
  CHECK_THROWS_WITH(detector.set_step(sheet, step.x0[sheet], nan), Catch::Contains("'cloth': vertex 17"));
  CHECK_THROWS_WITH(detector.set_step(sheet, nan, step.x0[sheet]), Catch::Contains("'cloth': vertex 17"));
  CHECK_THROWS_WITH(detector.set_positions(sheet, nan), Catch::Contains("'cloth': vertex 17"));
  // Refused whole: the next step is the one a detector given none of them runs (the
  // cloth stays where the last step left it, touching the sphere).
  Detector clean(cstreams::test::device(), describe(cloth, 30));
  run_step(clean, step);
  clean.detect();
  detector.detect();
  REQUIRE(!clean.contacts().empty());
  check_same_contacts(detector.contacts(), clean.contacts());

  run_step(detector, step);
  REQUIRE(detector.contacts().size() == before.size());
  for (std::size_t i = 0; i < before.size(); ++i) CHECK(detector.contacts()[i].same_features(before[i]));

  SceneDescription broken;
  broken.add({"tri", {{0, 1, 1}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}});
  CHECK_THROWS_WITH(Detector(cstreams::test::device(), broken), Catch::Contains("object 'tri': face 0 repeats a vertex"));
  broken.objects[0].faces = {{0, 1, 3}};
  CHECK_THROWS_WITH(Detector(cstreams::test::device(), broken), Catch::Contains("face 0 uses vertex 3 of 3"));
}

TEST_CASE("contacts do not depend on the work-group size a device runs", "[detector][quick]")
{
  // Devices differ in how many work-items a group may hold (rusticl on llvmpipe: 32);
  // the conservative refinement keeps 256 box positions a group whatever that number.
  const Scene scene = cstreams::test::cloth_funnel();
  const Step step = load_step(scene, 0);
  runtime::Context small(filter_from_environment(), 32);
  REQUIRE(small.work_group_size() == 32);
  for (Precision precision : {Precision::single, Precision::double_}) {
    if (precision == Precision::double_ && !small.device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector a(cstreams::test::device(), describe(scene, 0), options), b(small, describe(scene, 0), options);
    run_step(a, step);
    run_step(b, step);
    check_same_contacts(a.contacts(), b.contacts());
  }
}

TEST_CASE("no step of cloth-ball peaks above 200 MiB, nor far above what a settled one holds", "[detector][slow]")
{
  // Issue 12 asks for 200 MiB on cloth-ball, which settled cubic steps hold (161 MiB on
  // pocl and the H100). The first step, searched from the roots, sized its candidates'
  // segments for two of each a triangle pair (201 MiB); the third, the first with a
  // step arena, ran beside the contact readback's scratch of the step before (203 MiB).
  // The first steps, whose segments no run has planned yet, peak at up to 172 MiB, 7%
  // above a settled step.
  const Scene scene = cstreams::test::cloth_ball();
  const Step step = load_step(scene, 0);
  runtime::Context context(filter_from_environment());
  DetectorOptions options;
  options.solver.solver = Solver::cubic;
  Detector detector(context, describe(scene, 0), options);
  std::vector<std::size_t> peaks;
  for (int repeat = 0; repeat < 5; ++repeat) {
    run_step(detector, step);
    peaks.push_back(detector.stats().peak_bytes);
  }
  const std::size_t held = context.memory_in_use();
  for (std::size_t k = 0; k < peaks.size(); ++k) {
    INFO("step " << k << " peaks at " << peaks[k] << " bytes; settled, the detector holds " << held);
    CHECK(peaks[k] <= std::size_t(200) << 20);
    CHECK(double(peaks[k]) <= 1.1 * double(held));
  }
}

TEST_CASE("a detector's memory settles at what its steps plan, and no step peaks far above it", "[detector][quick]")
{
  // The first step searches from seeds; the second is the first from a whole front,
  // before any run has planned its registration segments; later steps plan from the
  // last. A step repeated, as a benchmark runs it, on a context of its own so that the
  // high-water mark and what is in use are the detector's.
  const Scene scene = cstreams::test::cloth_funnel();
  const Step step = load_step(scene, 0);
  for (Solver solver : {Solver::cubic, Solver::conservative}) {
    runtime::Context context(filter_from_environment());
    DetectorOptions options;
    options.solver.solver = solver;
    Detector detector(context, describe(scene, 0), options);
    std::vector<std::size_t> peaks, held;
    for (int repeat = 0; repeat < 5; ++repeat) {
      run_step(detector, step);
      peaks.push_back(detector.stats().peak_bytes);
      held.push_back(context.memory_in_use());
    }
    INFO(to_string(solver) << ": held " << held.back() << " bytes; peaks " << peaks[0] << " " << peaks[1] << " "
                           << peaks[2]);
    CHECK(held[4] == held[3]);
    CHECK(peaks[4] == held[4]);  // a settled step allocates nothing
    // Segments sized for four items a front pair, as they were, took 2.7 times what a
    // settled step then held, which has since held less (segments an eighth over their
    // plan, not a quarter) where a first step, unplanned, does not: on rusticl, whose
    // loops end early and whose first step searches again from a finer front, that
    // step peaks at 2.4 times.
    for (std::size_t peak : peaks) CHECK(double(peak) <= 2.5 * double(held.back()));
    // The second step's segments, sized from what the first emitted rather than from
    // the items a front pair is expected to emit, hold what later steps hold (10-12% more
    // on pocl when they were not). On rusticl, whose groups are of 32 work-items, the
    // first step's plan (of the seeds' few groups) leaves more of the second step's
    // groups short, and their spills peak above a settled step: 18.5 MB against 13.9 on
    // the funnel. Its first step had searched again from finer fronts until the front
    // update's work-groups searched together, and peaked at 43 MB (the second at 22.3,
    // settled at 17.6).
    const double second = context.loop_trip_limit() != 0 ? 1.35 : 1.05;
    CHECK(double(peaks[1]) <= second * double(std::max(peaks[0], held.back())));
  }
}

// Replaying frames, the next step's ends upload while a step runs (upload_ahead). The
// contacts must be those of the same positions set before each step: with one body
// given new positions only every other step (it stays in between), an upload replaced
// by a second one and one by set_positions(), and bad ones refused without a trace.
// The static ground and the second half's frames are rounded to floats, which single
// precision takes as the input itself once every position a step reads is a float
// (CcdStreams::exact_floats).
TEST_CASE("positions uploaded ahead give the contacts of positions set before each step", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 12, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  // Through the library's rounding: GCC 12's -O3 leaves the last vertex's y and z
  // unrounded in a loop of p[k] = double(float(p[k])).
  const auto to_floats = [](std::vector<Vec3>& x) {
    const std::vector<float> f = to_float_positions(x);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
  };
  SceneDescription start = describe(bodies, 0);
  for (auto& object : start.objects)
    if (object.kind == ObjectKind::static_) to_floats(object.positions);
  const auto frame = [&](std::size_t f) { return load_step(bodies, std::min(f, steps - 1)); };
  const auto ends = [&](std::size_t step) {  // step k ends at frame k
    auto x = frame(step - 1).x1;
    if (2 * step > steps)
      for (auto& object : x) to_floats(object);
    return x;
  };
  const std::uint32_t lazy = 1, replaced = 2;
  const auto moves = [&](std::uint32_t o, std::size_t step) {
    return bodies.objects[o].kind != ObjectKind::static_ && (o != lazy || step % 2 == 0);
  };
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector set(cstreams::test::device(), start, options), ahead(cstreams::test::device(), start, options);
    const auto first = ends(1);
    for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
      if (moves(o, 1)) ahead.set_positions(o, first[o]);
    std::size_t contacts = 0;
    for (std::size_t step = 1; step <= steps; ++step) {
      INFO("step " << step);
      const auto now = ends(step);
      for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
        if (moves(o, step)) set.set_positions(o, now[o]);
      // Read while the step runs: kept until it returns.
      const auto next = ends(std::min(step + 1, steps));
      if (step < steps) {
        ahead.upload_ahead(0, now[0]);  // replaced below
        for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
          if (moves(o, step + 1)) ahead.upload_ahead(o, next[o]);
        CHECK_THROWS_AS(ahead.upload_ahead(0, std::vector<Vec3>(3)), InputError);
        std::vector<Vec3> broken = next[0];
        broken[0][1] = std::numeric_limits<double>::quiet_NaN();
        CHECK_THROWS_AS(ahead.upload_ahead(0, broken), InputError);
      }
      if (step == 3) {
        const auto before = ends(step - 1);
        set.set_positions(replaced, before[replaced]);
        ahead.set_positions(replaced, before[replaced]);
      }
      set.detect();
      ahead.detect();
      check_same_contacts(set.contacts(), ahead.contacts());
      contacts += set.contacts().size();
    }
    CHECK(contacts > 0);
  }
}

// A repeated step uploads both its ends ahead (upload_ahead(object, start, end)), and
// a step that follows one uploaded ahead starts from its end without a copy: runs of
// each step, uploaded ahead, must give the contacts and earliest times of the same
// positions set before each run. One body is given only its ends, so it starts where
// the run before left it.
TEST_CASE("a repeated step uploaded ahead, both ends, gives the contacts of its ends set before each run",
          "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 6, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const std::uint32_t ends_only = 1;
  const auto moving = [&](std::uint32_t o) { return bodies.objects[o].kind != ObjectKind::static_; };
  const unsigned runs = 3;
  // The positions of every run, in order: each step `runs` times.
  std::vector<Step> order;
  for (std::size_t f = 0; f < steps; ++f)
    for (unsigned r = 0; r < runs; ++r) order.push_back(load_step(bodies, f));
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector set(cstreams::test::device(), describe(bodies, 0), options),
        ahead(cstreams::test::device(), describe(bodies, 0), options);
    std::size_t contacts = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      INFO("run " << k);
      const Step& now = order[k];
      for (std::uint32_t o = 0; o < bodies.objects.size(); ++o) {
        if (!moving(o)) continue;
        if (o == ends_only) set.set_positions(o, now.x1[o]);
        else set.set_step(o, now.x0[o], now.x1[o]);
        if (k == 0) ahead.set_positions(o, now.x1[o]);
        if (k + 1 == order.size()) continue;
        const Step& next = order[k + 1];
        if (o == ends_only) ahead.upload_ahead(o, next.x1[o]);
        else ahead.upload_ahead(o, next.x0[o], next.x1[o]);
      }
      if (k + 1 < order.size())
        CHECK_THROWS_AS(ahead.upload_ahead(0, order[k + 1].x0[0], std::vector<Vec3>(3)), InputError);
      const Report report = k % 4 == 3 ? Report::earliest_toi : Report::contacts;
      set.detect(report);
      ahead.detect(report);
      CHECK(set.earliest_toi() == ahead.earliest_toi());
      if (report == Report::earliest_toi) continue;
      check_same_contacts(set.contacts(), ahead.contacts());
      contacts += set.contacts().size();
    }
    CHECK(contacts > 0);
  }
}

// Positions given object by object are gathered and go up as the step starts, one write
// per run of adjacent objects. Given in slot order they make one run; given backwards,
// some twice (the first a wrong frame) and some through set_step(), every object is a
// run of its own: both must give the same contacts, step after step.
TEST_CASE("positions given in any order, some twice, give the contacts of positions given in order",
          "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 8, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const auto objects = std::uint32_t(bodies.objects.size());
  const auto moving = [&](std::uint32_t o) { return bodies.objects[o].kind != ObjectKind::static_; };
  Detector in_order(cstreams::test::device(), describe(bodies, 0)),
      scrambled(cstreams::test::device(), describe(bodies, 0));
  std::size_t contacts = 0;
  for (std::size_t frame = 0; frame < steps; ++frame) {
    INFO("step from frame " << frame);
    const Step step = load_step(bodies, frame);
    const Step wrong = load_step(bodies, (frame + 3) % steps);
    for (std::uint32_t o = 0; o < objects; ++o)
      if (moving(o)) in_order.set_positions(o, step.x1[o]);
    for (std::uint32_t o = objects; o-- > 0;) {
      if (!moving(o)) continue;
      if (o % 3 == 0) scrambled.set_positions(o, wrong.x1[o]);
      if (o % 2 == 0) scrambled.set_step(o, step.x0[o], step.x1[o]);
      else scrambled.set_positions(o, step.x1[o]);
    }
    in_order.detect();
    scrambled.detect();
    check_same_contacts(in_order.contacts(), scrambled.contacts());
    contacts += in_order.contacts().size();
  }
  CHECK(contacts > 0);
}
