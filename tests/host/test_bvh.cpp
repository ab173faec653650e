#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/scenes/shapes.hpp>

#include "../support/scratch.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <random>

using namespace cstreams;

namespace {

Mesh cloth_and_ball(double drop)
{
  Mesh m = scenes::sheet(12, 12, 2, 2);
  for (auto& p : m.positions) p += Vec3(-1, -1, 1.0 - drop + 0.3 * std::sin(3 * p.x()) * std::sin(2 * p.y()));
  scenes::append(m, scenes::icosphere(2, 0.8, Vec3(0.1, 0, 0)));
  return m;
}

}  // namespace

TEST_CASE("swept 18-DOPs contain the swept primitive", "[host][bvh][quick]")
{
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> coord(-1e3, 1e3), unit(0, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Vec3> x0(3), x1(3);
    for (int i = 0; i < 3; ++i) {
      x0[std::size_t(i)] = Vec3(coord(rng), coord(rng), coord(rng));
      x1[std::size_t(i)] = x0[std::size_t(i)] + Vec3(coord(rng), coord(rng), coord(rng)) * 1e-3;
    }
    const std::uint32_t ids[3] = {0, 1, 2};
    const Kdop18 box = swept_kdop(x0.data(), x1.data(), ids, 3, 0.0);
    const double t = unit(rng), u = unit(rng), v = unit(rng) * (1 - u);
    auto at = [&](int i) { return Vec3(x0[std::size_t(i)] + t * (x1[std::size_t(i)] - x0[std::size_t(i)])); };
    const Vec3 p = (1 - u - v) * at(0) + u * at(1) + v * at(2);
    Kdop18 point = Kdop18::empty();
    point.add(p);
    CHECK(box.overlaps(point));
    // A point at the minimum separation from the primitive is inside the inflated box.
    const Kdop18 grown = swept_kdop(x0.data(), x1.data(), ids, 3, 0.5);
    Kdop18 near = Kdop18::empty();
    near.add(at(0) + Vec3(0.5, 0, 0) * (trial % 2 ? 1 : -1));
    CHECK(grown.overlaps(near));
  }
}

TEST_CASE("the BVH holds every face once and every node contains its children", "[host][bvh][quick]")
{
  const Mesh m = cloth_and_ball(0);
  const Topology t = build_topology(m.faces, m.positions.size());
  const SweptBounds b = swept_bounds(t, m.positions, m.positions, 0);
  const Bvh bvh = build_bvh(b.faces);
  CHECK(bvh.nodes.size() == 2 * m.faces.size() - 1);
  std::vector<int> seen(m.faces.size(), 0);
  for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
    const BvhNode& n = bvh.nodes[i];
    if (n.left < 0) {
      ++seen[std::size_t(n.face)];
      continue;
    }
    for (int c = 0; c < 2; ++c) {
      const std::size_t child = std::size_t(n.left + c);
      CHECK(child > i);
      CHECK(bvh.nodes[child].parent == std::int32_t(i));
      Kdop18 merged = bvh.boxes[i];
      merged.merge(bvh.boxes[child]);
      CHECK(merged.lo == bvh.boxes[i].lo);
      CHECK(merged.hi == bvh.boxes[i].hi);
    }
  }
  for (int s : seen) CHECK(s == 1);
  // Median splits keep the tree balanced.
  CHECK(bvh.depth() <= std::size_t(std::ceil(std::log2(double(m.faces.size())))) + 1);
  CHECK(bvh.level_offsets.back() == bvh.nodes.size());
}

TEST_CASE("BVH traversal and brute force find the same candidates", "[host][bvh][quick]")
{
  const Mesh a = cloth_and_ball(0), b = cloth_and_ball(0.45);
  for (bool split : {false, true}) {
    const std::string dir = cstreams::test::fresh_scratch("bvh").string();
    // Two frames written to disk, as a user's scene would be.
    write_ply(dir + "/cstreams_bvh_0.ply", a);
    write_ply(dir + "/cstreams_bvh_1.ply", b);
    const Scene scene = scene_from_frames({dir + "/cstreams_bvh_0.ply", dir + "/cstreams_bvh_1.ply"}, split);
    CHECK(scene.objects.size() == (split ? 2u : 1u));
    const Step step = load_step(scene, 0);
    ReferenceOptions bvh, brute;
    brute.broad_phase = BroadPhase::brute_force;
    const Candidates x = reference_broad_phase(step, bvh), y = reference_broad_phase(step, brute);
    CHECK(x.vf_count() > 0);
    CHECK(x.ee_count() > 0);
    CHECK(x == y);
    // With a minimum separation the BVs grow, and so does the candidate set.
    bvh.solver.min_separation = brute.solver.min_separation = 0.05;
    const Candidates xs = reference_broad_phase(step, bvh);
    CHECK(xs == reference_broad_phase(step, brute));
    CHECK(xs.vf_count() > x.vf_count());
    // The device's float boxes: traversal and brute force agree there too.
    bvh.bounds = brute.bounds = BoundsPrecision::single;
    CHECK(reference_broad_phase(step, bvh) == reference_broad_phase(step, brute));
  }
}

namespace {
template <class Pair> bool includes(const std::vector<Pair>& big, const std::vector<Pair>& small)
{
  return std::includes(big.begin(), big.end(), small.begin(), small.end());
}
}  // namespace

TEST_CASE("float-box candidates contain the exact-box candidates", "[host][bvh][quick]")
{
  const Mesh a = cloth_and_ball(0), b = cloth_and_ball(0.45);
  const std::string dir = cstreams::test::fresh_scratch("bvh-float").string();
  write_ply(dir + "/0.ply", a);
  write_ply(dir + "/1.ply", b);
  const Scene scene = scene_from_frames({dir + "/0.ply", dir + "/1.ply"}, true);
  const Step step = load_step(scene, 0);
  for (double separation : {0.0, 0.01}) {
    ReferenceOptions exact, single;
    exact.solver.min_separation = single.solver.min_separation = separation;
    single.bounds = BoundsPrecision::single;
    const Candidates x = reference_broad_phase(step, exact), f = reference_broad_phase(step, single);
    REQUIRE(x.blocks.size() == f.blocks.size());
    for (std::size_t i = 0; i < x.blocks.size(); ++i) {
      CHECK(includes(f.blocks[i].vf, x.blocks[i].vf));
      CHECK(includes(f.blocks[i].ee, x.blocks[i].ee));
    }
    CHECK(f.vf_count() >= x.vf_count());
  }
}

// The float positions the device reads, whether they are the input itself (then single
// precision takes them as exact) and whether each is a finite float (else the input is
// refused): every coordinate rounded to nearest as a cast rounds it, and one coordinate
// off a float or out of range, wherever it sits among the vector lanes or the tail,
// tells for the whole array, as the check that names it does.
TEST_CASE("positions round to the nearest floats, exact only where every coordinate is one, finite where each is",
          "[host][bvh][quick]")
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1e3, 1e3);
  for (std::size_t vertices : {0, 1, 2, 3, 5, 8}) {
    std::vector<Vec3> floats(vertices);
    for (auto& p : floats)
      for (int k = 0; k < 3; ++k) p[k] = double(float(coordinate(random)));
    std::vector<float> out(3 * vertices, -1.0f);
    const FloatRounding exact = round_to_float(floats, out.data());
    CHECK(exact.finite);
    CHECK(exact.exact);
    for (std::size_t j = 0; j < out.size(); ++j) CHECK(double(out[j]) == floats[j / 3][int(j % 3)]);
    for (std::size_t j = 0; j < 3 * vertices; ++j) {
      INFO(vertices << " vertices, coordinate " << j);
      std::vector<Vec3> one_off = floats;
      double& c = one_off[j / 3][int(j % 3)];
      c = std::nextafter(c, 2e3);
      const FloatRounding off = round_to_float(one_off, out.data());
      CHECK(off.finite);
      CHECK_FALSE(off.exact);
      CHECK(out[j] == float(c));
      for (double bad : {std::nan(""), -std::numeric_limits<double>::infinity(), 1e39, -double(FLT_MAX) * 1.0000001}) {
        INFO("coordinate " << bad);
        c = bad;
        CHECK_FALSE(round_to_float(one_off, out.data()).finite);
        CHECK_THROWS_AS(check_float_positions(one_off), InputError);
      }
      c = double(FLT_MAX);
      CHECK(round_to_float(one_off, out.data()).finite);
    }
  }
}

// Large inputs are rounded and checked block by block on several threads: what any one
// block finds (a coordinate off a float, one out of range) still tells for the whole
// array, the check names the vertex, every coordinate lands where it belongs, and the
// exact copy is the input.
TEST_CASE("positions of a large object round and copy in blocks, each block's finding telling for the whole",
          "[host][bvh][quick]")
{
  std::mt19937 random(11);
  std::uniform_real_distribution<double> coordinate(-1e3, 1e3);
  const std::size_t vertices = 40000;
  std::vector<Vec3> x(vertices);
  for (auto& p : x)
    for (int k = 0; k < 3; ++k) p[k] = double(float(coordinate(random)));
  std::vector<float> out(3 * vertices);
  std::vector<Vec3> copy(vertices);
  const FloatRounding exact = round_to_float(x, out.data(), copy.data());
  CHECK(exact.finite);
  CHECK(exact.exact);
  CHECK(copy == x);
  CHECK_NOTHROW(check_float_positions(x));
  for (const std::size_t j : {std::size_t(0), std::size_t(3 * 8192 + 1), 3 * vertices / 2, 3 * vertices - 1}) {
    INFO("coordinate " << j);
    std::vector<Vec3> one_off = x;
    double& c = one_off[j / 3][int(j % 3)];
    c = c / 3 + 1e-3;
    const FloatRounding off = round_to_float(one_off, out.data(), copy.data());
    CHECK(off.finite);
    CHECK_FALSE(off.exact);
    CHECK(copy == one_off);
    bool rounded = true;
    for (std::size_t i = 0; i < out.size(); ++i) rounded &= out[i] == float(one_off[i / 3][int(i % 3)]);
    CHECK(rounded);
    c = std::nan("");
    CHECK_FALSE(round_to_float(one_off, out.data()).finite);
    CHECK_THROWS_WITH(check_float_positions(one_off), Catch::Contains("vertex " + std::to_string(j / 3) + " "));
  }
}
