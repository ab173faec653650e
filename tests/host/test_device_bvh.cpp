#include "../support/shared_data.hpp"
#include "../support/test_device.hpp"

#include <cstreams/device_broad_phase.hpp>
#include <cstreams/device_bvh.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/narrow_phase.hpp>
#include <cstreams/query_io.hpp>
#include <cstreams/reference_ccd.hpp>
#include <cstreams/scenes/generators.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

using namespace cstreams;

namespace {

void check_step(const Scene& scene, std::uint32_t object, std::size_t frame, float separation)
{
  const Step step = load_step(scene, frame);
  const Topology& t = scene.objects[object].topology;
  const SweptBounds exact = swept_bounds(t, step.x0[object], step.x1[object], separation);
  const Bvh bvh = build_bvh(exact.faces);
  DeviceBvh device(cstreams::test::device(), t, bvh, separation);
  device.refit(step.x0[object], step.x1[object]);
  const FloatBounds got = device.download();
  const FloatBounds host = float_bounds(t, bvh, step.x0[object], step.x1[object], separation);
  // Bit for bit the host's float arithmetic: device candidates can equal the host's.
  CHECK(got.faces == host.faces);
  CHECK(got.edges == host.edges);
  CHECK(got.vertices == host.vertices);
  CHECK(got.nodes == host.nodes);
  // Conservative: every float box contains the exact (double, outward-rounded) one.
  std::size_t outside = 0;
  for (std::size_t f = 0; f < t.faces.size(); ++f) outside += !host.faces[f].contains(exact.faces[f]);
  for (std::size_t e = 0; e < t.edges.size(); ++e) outside += !host.edges[e].contains(exact.edges[e]);
  for (std::size_t v = 0; v < t.vertex_count; ++v) outside += !host.vertices[v].contains(exact.vertices[v]);
  CHECK(outside == 0);
  // Three bounds passes and one refit pass per level, with no counter to read back.
  CHECK(device.stats().passes.size() == 3 + bvh.depth());
  CHECK(device.stats().readbacks == 0);

  // A second step through the same device object: only positions change.
  device.refit(step.x1[object], step.x0[object]);
  CHECK(device.download().nodes == float_bounds(t, bvh, step.x1[object], step.x0[object], separation).nodes);
}

}  // namespace

TEST_CASE("device swept bounds and BVH refit equal the host's float twin and contain the exact bounds",
          "[device-bvh][quick]")
{
  const std::string dir = cstreams::test::shared_path("scenes-data/scalable-ccd-sample/cloth-funnel/frames/");
  const Scene funnel = scene_from_frames({dir + "227.ply", dir + "228.ply"});
  check_step(funnel, 0, 0, 0.0f);
  check_step(funnel, 0, 0, 1e-3f);

  const auto folder = (std::filesystem::temp_directory_path() / "cstreams-device-bvh").string();
  std::filesystem::remove_all(folder);
  const Scene cloth = load_scene(scenes::generate_scene({"cloth-sphere", folder, 1, 24, 40}));
  check_step(cloth, 0, 20, 0.0f);
}

TEST_CASE("refit rejects positions of the wrong size or out of float range", "[device-bvh][quick]")
{
  const std::string dir = cstreams::test::shared_path("scenes-data/scalable-ccd-sample/cloth-funnel/frames/");
  const Scene funnel = scene_from_frames({dir + "227.ply", dir + "228.ply"});
  const Step step = load_step(funnel, 0);
  const Topology& t = funnel.objects[0].topology;
  const Bvh bvh = build_bvh(swept_bounds(t, step.x0[0], step.x1[0], 0).faces);
  DeviceBvh device(cstreams::test::device(), t, bvh, 0);
  auto fewer = step.x1[0];
  fewer.pop_back();
  CHECK_THROWS_WITH(device.refit(step.x0[0], fewer), Catch::Contains("9449 vertices given to a mesh of 9450"));
  auto huge = step.x1[0];
  huge[17].x() = 1e300;
  CHECK_THROWS_WITH(device.refit(step.x0[0], huge), Catch::Contains("vertex 17"));
  device.refit(step.x0[0], step.x1[0]);  // still usable after bad input
  CHECK(device.download().faces.size() == t.faces.size());
}

namespace {

// The device's candidates for object 0 against itself, and the host's in float boxes.
void check_broad_phase(const Scene& scene, std::size_t frame, double separation)
{
  const Step step = load_step(scene, frame);
  const Topology& t = scene.objects[0].topology;
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  host.solver.min_separation = separation;
  const Candidates expected = reference_broad_phase(step, host);
  REQUIRE(expected.blocks.front().object_a == 0);
  REQUIRE(expected.blocks.front().object_b == 0);
  const Bvh bvh = build_bvh(swept_bounds(t, step.x0[0], step.x1[0], separation).faces);
  const float device_separation = float_above(separation);
  for (auto registration : {runtime::Registration::segmented_lock, runtime::Registration::lock_free,
                            runtime::Registration::global_atomic}) {
    INFO(runtime::to_string(registration) << ", separation " << separation);
    DeviceBroadPhase device(cstreams::test::device(), t, bvh, device_separation, registration);
    const Candidates got = device.run(step.x0[0], step.x1[0]);
    CHECK(got.blocks.front().vf == expected.blocks.front().vf);
    CHECK(got.blocks.front().ee == expected.blocks.front().ee);
    CHECK(got.vf_count() > 0);
    // A second step on the same object grows nothing and reruns nothing.
    device.run(step.x0[0], step.x1[0]);
    for (const auto& p : device.scheduler().stats().passes) CHECK(p.reruns == 0);
  }
}

}  // namespace

TEST_CASE("device broad phase candidates equal the host's in float boxes exactly", "[device-bvh][quick]")
{
  const std::string dir = cstreams::test::shared_path("scenes-data/scalable-ccd-sample/cloth-funnel/frames/");
  const Scene funnel = scene_from_frames({dir + "227.ply", dir + "228.ply"});
  check_broad_phase(funnel, 0, 0.0);
  check_broad_phase(funnel, 0, 1e-3);
  const auto folder = (std::filesystem::temp_directory_path() / "cstreams-device-broad").string();
  std::filesystem::remove_all(folder);
  const Scene cloth = load_scene(scenes::generate_scene({"cloth-sphere", folder, 1, 36, 40}));
  check_broad_phase(cloth, 33, 0.0);
}

TEST_CASE("the seed front covers the tree", "[device-bvh][quick]")
{
  const std::string dir = cstreams::test::shared_path("scenes-data/scalable-ccd-sample/cloth-funnel/frames/");
  const Scene funnel = scene_from_frames({dir + "227.ply", dir + "228.ply"});
  const Step step = load_step(funnel, 0);
  const Bvh bvh = build_bvh(swept_bounds(funnel.objects[0].topology, step.x0[0], step.x1[0], 0).faces);
  CHECK(seed_front(bvh, 1).size() == 1);
  const auto seeds = seed_front(bvh, 5000);
  CHECK(seeds.size() >= 5000);
  // Distinct pairs: no part of the BVTT is traversed twice (the equality test above
  // shows none is missed).
  auto sorted = seeds;
  std::sort(sorted.begin(), sorted.end());
  CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
}

TEST_CASE("device CCD of one mesh: every true pair, and the solver's answers on the host's candidates",
          "[device-bvh][quick]")
{
  const std::string dir = cstreams::test::shared_path("scenes-data/scalable-ccd-sample/cloth-funnel/");
  const Scene funnel = scene_from_frames({dir + "frames/227.ply", dir + "frames/228.ply"});
  const Step step = load_step(funnel, 0);
  const Topology& t = funnel.objects[0].topology;
  const Bvh bvh = build_bvh(swept_bounds(t, step.x0[0], step.x1[0], 0).faces);
  const SolverOptions solver;  // conservative, single precision
  DeviceBroadPhase device(cstreams::test::device(), t, bvh, 0.0f, runtime::Registration::segmented_lock, solver);
  device.run(step.x0[0], step.x1[0]);
  const std::vector<Contact> contacts = device.contacts();

  // The same solver over the host's float-box candidates gives the same contacts.
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  const Candidates candidates = reference_broad_phase(step, host);
  const CandidateBlock& block = candidates.blocks.front();
  DeviceSolver elementary(cstreams::test::device(), solver);
  std::vector<Query> vf, ee;
  for (const auto& p : block.vf) vf.push_back(vertex_face_query(step, 0, 0, p));
  for (const auto& p : block.ee) ee.push_back(edge_edge_query(step, 0, 0, p));
  const auto vf_results = elementary.solve(ContactKind::vertex_face, vf);
  const auto ee_results = elementary.solve(ContactKind::edge_edge, ee);
  std::vector<Contact> expected;
  for (std::size_t i = 0; i < vf.size(); ++i)
    if (vf_results[i].collides()) expected.push_back(make_contact(step, 0, 0, block.vf[i], vf_results[i].toi));
  for (std::size_t i = 0; i < ee.size(); ++i)
    if (ee_results[i].collides()) expected.push_back(make_contact(step, 0, 0, block.ee[i], ee_results[i].toi));
  sort_canonical(expected);
  REQUIRE(contacts.size() == expected.size());
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    CHECK(contacts[i].same_features(expected[i]));
    CHECK(contacts[i].toi == expected[i].toi);
  }

  // Every pair the exact ground truth marks as colliding is among them.
  const auto truth_vf = read_bool_array(dir + "mma_bool/227vf_mma_bool.json");
  const auto truth_ee = read_bool_array(dir + "mma_bool/227ee_mma_bool.json");
  std::size_t positives = std::count(truth_vf.begin(), truth_vf.end(), true) + std::count(truth_ee.begin(), truth_ee.end(), true);
  CHECK(positives == 134);
  std::set<std::array<std::uint32_t, 4>> reported;
  for (const auto& c : contacts) reported.insert(c.v);
  std::ifstream vf_boxes(dir + "boxes/227vf.json"), ee_boxes(dir + "boxes/227ee.json");
  const auto vf_ids = nlohmann::json::parse(vf_boxes).get<std::vector<std::array<std::uint64_t, 2>>>();
  const auto ee_ids = nlohmann::json::parse(ee_boxes).get<std::vector<std::array<std::uint64_t, 2>>>();
  const std::uint64_t nv = t.vertex_count, ne = t.edges.size();
  std::size_t missed = 0;
  for (std::size_t i = 0; i < vf_ids.size(); ++i)
    if (truth_vf[i])
      missed += !reported.count(make_contact(step, 0, 0, VertexFace{std::uint32_t(vf_ids[i][0]), std::uint32_t(vf_ids[i][1] - nv - ne)}, 0).v);
  for (std::size_t i = 0; i < ee_ids.size(); ++i)
    if (truth_ee[i])
      missed += !reported.count(make_contact(step, 0, 0, EdgeEdge{std::uint32_t(ee_ids[i][0] - nv), std::uint32_t(ee_ids[i][1] - nv)}, 0).v);
  CHECK(missed == 0);
}
