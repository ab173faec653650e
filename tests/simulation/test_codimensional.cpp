// Segments and points (codimensional geometry) against motions whose first contact is
// known exactly, and close pairs with them against the oracle.
#include "../support/test_device.hpp"
#include "distance_oracle.hpp"

#include <cstreams/errors.hpp>
#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/scenes/shapes.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <catch2/catch.hpp>

#include <vector>

using namespace cstreams;

namespace {

// A plate of 8 x 8 quads over [0, 1]^2 at z = 0, then whatever is added after it.
struct World {
  std::vector<Vec3> x;
  std::vector<Face> faces;
  std::vector<Edge> rods;
  World()
  {
    const Mesh plate = scenes::sheet(8, 8, 1, 1);
    x = plate.positions;
    faces = plate.faces;
  }
  std::uint32_t point(const Vec3& p)
  {
    x.push_back(p);
    return std::uint32_t(x.size() - 1);
  }
  // A rod of n segments from a to b.
  std::pair<std::uint32_t, std::uint32_t> rod(const Vec3& a, const Vec3& b, int n)
  {
    const auto first = std::uint32_t(x.size());
    for (int k = 0; k <= n; ++k) x.push_back(a + (b - a) * (double(k) / n));
    for (int k = 0; k < n; ++k) rods.push_back({first + std::uint32_t(k), first + std::uint32_t(k) + 1});
    return {first, std::uint32_t(x.size())};
  }
  CollisionMesh mesh() const { return CollisionMesh(x, faces, rods); }
};

// The positions with the vertices [first, last) moved by d.
std::vector<Vec3> moved(std::vector<Vec3> x, std::uint32_t first, std::uint32_t last, const Vec3& d)
{
  for (std::uint32_t v = first; v < last; ++v) x[v] += d;
  return x;
}

void check_toi(double toi, double exact)
{
  CHECK(toi <= exact);
  CHECK(toi >= exact - 1e-4);
}

}  // namespace

TEST_CASE("a point falls onto a plate, a rod and another point", "[simulation]")
{
  World w;
  const std::uint32_t onto_plate = w.point({0.31, 0.42, 0.1});
  const auto [rod_first, rod_last] = w.rod({0.05, 0.73, 0.02}, {0.95, 0.73, 0.02}, 9);
  const std::uint32_t onto_rod = w.point({0.5, 0.73, 0.12});
  const std::uint32_t below = w.point({0.8, 0.2, 0.05}), onto_point = w.point({0.8, 0.2, 0.25});
  const CollisionMesh mesh = w.mesh();
  CHECK(mesh.points() == std::vector<std::uint32_t>{onto_plate, onto_rod, below, onto_point});
  const Precision precision = GENERATE(Precision::single, Precision::double_);
  if (precision == Precision::double_ && !test::device().device().fp64) return;
  MeshCcdOptions options;
  options.precision = precision;
  MeshCcd ccd(test::device(), mesh, options);
  const Vec3 down(0, 0, -0.3);
  // Each alone: the point onto the plate, onto the rod's middle, onto the point below.
  check_toi(ccd.toi(w.x, moved(w.x, onto_plate, onto_plate + 1, down)), 0.1 / 0.3);
  check_toi(ccd.toi(w.x, moved(w.x, onto_rod, onto_rod + 1, down)), 0.1 / 0.3);
  check_toi(ccd.toi(w.x, moved(w.x, onto_point, onto_point + 1, down)), 0.2 / 0.3);
  // The rod falls onto the plate: it lies 0.02 above it.
  check_toi(ccd.toi(w.x, moved(w.x, rod_first, rod_last, down)), 0.02 / 0.3);
  // Nothing moves toward anything: free.
  CHECK(ccd.is_step_collision_free(w.x, moved(w.x, onto_plate, onto_plate + 1, Vec3(0, 0, 0.3))));
  // A step size keeps the separation.
  const auto end = moved(w.x, onto_plate, onto_plate + 1, down);
  const double alpha = ccd.collision_free_stepsize(w.x, end, 0.01);
  CHECK(w.x[onto_plate].z() + alpha * -0.3 > 0.01);
  CHECK(alpha >= 0.8 * (0.1 - std::sqrt(3.0) * 0.01) / 0.3 - 1e-4);
}

TEST_CASE("two rods cross: the first contact is inside both segments", "[simulation]")
{
  World w;
  const auto [a_first, a_last] = w.rod({0.05, 0.47, 0.3}, {0.95, 0.47, 0.3}, 9);
  const auto [b_first, b_last] = w.rod({0.52, 0.05, 0.2}, {0.52, 0.95, 0.2}, 9);
  (void)b_first;
  (void)b_last;
  MeshCcd ccd(test::device(), w.mesh());
  // Rod a comes down 0.2 onto rod b, 0.1 below it: at a third of the step.
  check_toi(ccd.toi(w.x, moved(w.x, a_first, a_last, Vec3(0, 0, -0.3))), 0.1 / 0.3);
  // Sliding along, parallel to rod b, it never meets it.
  CHECK(ccd.toi(w.x, moved(w.x, a_first, a_last, Vec3(0.01, 0, 0))) == 1.0);
}

TEST_CASE("segments and points need the conservative solver", "[simulation]")
{
  World w;
  w.point({0.5, 0.5, 0.1});
  MeshCcdOptions cubic;
  cubic.solver = Solver::cubic;
  MeshCcd ccd(test::device(), w.mesh(), cubic);
  CHECK_THROWS_AS(ccd.toi(w.x, w.x), InputError);
}

TEST_CASE("close pairs with segments and points match the oracle", "[simulation]")
{
  World w;
  w.rod({0.05, 0.43, 0.015}, {0.95, 0.51, 0.025}, 12);
  w.rod({0.5, 0.05, 0.03}, {0.52, 0.95, 0.02}, 12);
  for (int k = 0; k < 20; ++k) w.point({0.05 + 0.045 * k, 0.3 + 0.01 * (k % 3), 0.01 + 0.002 * (k % 5)});
  const CollisionMesh mesh = w.mesh();
  // The oracle sees the degenerate faces the detector collides.
  Mesh as_faces;
  as_faces.positions = w.x;
  ObjectDescription o = object_of(mesh);
  as_faces.faces = collision_faces(o);
  const double dhat = 0.03;
  const auto oracle = test::oracle_pairs(as_faces, dhat + 1e-9);
  MeshProximity proximity(test::device(), mesh);
  const std::vector<ClosePair>& found = proximity.close_pairs(w.x, dhat);
  std::set<test::PairKey> seen;
  std::size_t codimensional = 0;
  for (const ClosePair& p : found) {
    const auto it = oracle.find(test::key(p));
    REQUIRE(it != oracle.end());
    seen.insert(it->first);
    CHECK(std::fabs(p.distance - it->second.distance) <= 1e-6L);
    codimensional += p.kind == ContactKind::vertex_face && p.b >= w.faces.size();
  }
  for (const auto& [key, c] : oracle)
    if (c.distance < dhat) CHECK(seen.count(key) == 1);
  CHECK(seen.size() == found.size());  // each pair once
  CHECK(codimensional > 0);
}
