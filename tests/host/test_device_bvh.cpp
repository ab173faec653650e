#include "../support/shared_data.hpp"
#include "../support/test_device.hpp"

#include <cstreams/device_bvh.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/reference_ccd.hpp>
#include <cstreams/scenes/generators.hpp>

#include <catch2/catch.hpp>

#include <filesystem>

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
