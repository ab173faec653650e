// Close pairs on the device against the brute-force oracle (distance_oracle.hpp): no
// pair closer than dhat missed, none reported beyond it by more than rounding, the
// same distances and, where the closest features are clear, the same types.
#include "../support/test_device.hpp"
#include "distance_oracle.hpp"
#include "plates.hpp"

#include <cstreams/errors.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <catch2/catch.hpp>

#include <limits>
#include <random>

using namespace cstreams;

namespace {

Mesh mesh_of(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
{
  Mesh m;
  for (Eigen::Index v = 0; v < V.rows(); ++v) m.positions.emplace_back(V(v, 0), V(v, 1), V(v, 2));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    m.faces.push_back({std::uint32_t(F(f, 0)), std::uint32_t(F(f, 1)), std::uint32_t(F(f, 2))});
  return m;
}

// The device's set against the oracle's, in both precisions the device has.
void check_against_oracle(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, double dhat)
{
  const Mesh m = mesh_of(V, F);
  const long double scale = V.cwiseAbs().maxCoeff();
  for (const Precision precision : {Precision::double_, Precision::single}) {
    if (precision == Precision::double_ && !test::device().device().fp64) continue;
    // Twice the kernel's allowance: its own rounding and the oracle's margin for it.
    const long double eps = precision == Precision::double_ ? 0x1p-52L : 0x1p-23L, slack = 32 * eps * scale;
    const auto oracle = test::oracle_pairs(m, dhat + slack);
    MeshProximityOptions options;
    options.precision = precision;
    MeshProximity proximity(test::device(), CollisionMesh(V, F), options);
    const std::vector<ClosePair> found = proximity.close_pairs(V, dhat);
    std::size_t within = 0, typed = 0;
    for (const auto& [key, c] : oracle)
      if (c.distance < dhat) ++within;
    std::set<test::PairKey> seen;
    for (const ClosePair& p : found) {
      INFO("pair " << int(p.kind) << " " << p.a << " " << p.b << " distance " << p.distance);
      const auto it = oracle.find(test::key(p));
      REQUIRE(it != oracle.end());  // reported: closer than dhat, within rounding
      seen.insert(it->first);
      CHECK(std::fabs(p.distance - it->second.distance) <= slack + 1e-7L * it->second.distance);
      if (precision == Precision::double_ && it->second.runner_up - it->second.distance > 1e-9L * scale) {
        CHECK(test::key_type(p) == it->second.type);
        ++typed;
      }
    }
    for (const auto& [key, c] : oracle)
      if (c.distance < dhat) CHECK(seen.count(key) == 1);  // none closer than dhat missed
    CHECK(found.size() >= within);
    CHECK(seen.size() == found.size());  // each pair once
    CHECK(std::is_sorted(found.begin(), found.end(),
                         [](const ClosePair& x, const ClosePair& y) { return canonical_less(x, y); }));
    if (precision == Precision::double_) CHECK(typed > 0);
  }
}

Eigen::MatrixXd jittered(Eigen::MatrixXd V, double amplitude, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (Eigen::Index i = 0; i < V.size(); ++i) V.data()[i] += u(rng);
  return V;
}

}  // namespace

TEST_CASE("close pairs of two jittered plates match the oracle", "[simulation]")
{
  const auto p = test::plates(0.02, 12);
  check_against_oracle(jittered(p.V, 0.01, 7), p.F, 0.03);
}

TEST_CASE("close pairs of parallel plates: parallel edges and coplanar points", "[simulation]")
{
  // Parallel plates over each other, on the same grid: every edge of one is parallel to
  // one above it.
  Mesh a = scenes::sheet(6, 6, 1, 1), b = scenes::sheet(6, 6, 1, 1);
  for (Vec3& x : b.positions) x.z() = 0.05;
  Mesh stacked = a;
  scenes::append(stacked, b);
  // Side by side in one plane, 0.02 apart: points coplanar with the other's faces,
  // edges collinear with the other's.
  Mesh c = scenes::sheet(6, 6, 1, 1);
  for (Vec3& x : c.positions) x.x() += 1.02;
  Mesh side = a;
  scenes::append(side, c);
  for (const Mesh* m : {&stacked, &side}) {
    Eigen::MatrixXd V(Eigen::Index(m->positions.size()), 3);
    for (std::size_t v = 0; v < m->positions.size(); ++v) V.row(Eigen::Index(v)) = m->positions[v].transpose();
    Eigen::MatrixXi F(Eigen::Index(m->faces.size()), 3);
    for (std::size_t f = 0; f < m->faces.size(); ++f)
      for (int k = 0; k < 3; ++k) F(Eigen::Index(f), k) = int(m->faces[f][std::size_t(k)]);
    check_against_oracle(V, F, 0.1);
  }
}

TEST_CASE("close pairs with degenerate triangles match the oracle", "[simulation]")
{
  auto p = test::plates(0.02, 8);
  Eigen::MatrixXd V = jittered(p.V, 0.005, 11);
  // Collapse faces of the upper plate: a vertex onto the middle of its face's opposite
  // edge (zero area), and one face's three vertices onto a line.
  const Eigen::Index first = p.lower_vertices;
  for (Eigen::Index f = 0; f < p.F.rows(); ++f) {
    if (p.F(f, 0) < first || f % 5) continue;
    V.row(p.F(f, 2)) = 0.5 * (V.row(p.F(f, 0)) + V.row(p.F(f, 1)));
  }
  check_against_oracle(V, p.F, 0.03);
}

TEST_CASE("candidates and bad input of the proximity calls", "[simulation]")
{
  const auto p = test::plates(0.02, 8);
  MeshProximity proximity(test::device(), CollisionMesh(p.V, p.F));
  const CandidateBlock near = proximity.candidates(p.V, 0.05), far = proximity.candidates(p.V, 0.001);
  CHECK(near.vf.size() > far.vf.size());
  CHECK(near.ee.size() > far.ee.size());
  // Every close pair is among the candidates of the same radius.
  const CandidateBlock same = proximity.candidates(p.V, 0.03);
  for (const ClosePair& c : proximity.close_pairs(p.V, 0.03)) {
    if (c.kind == ContactKind::vertex_face)
      CHECK(std::binary_search(same.vf.begin(), same.vf.end(), VertexFace{c.a, c.b}));
    else
      CHECK(std::binary_search(same.ee.begin(), same.ee.end(), EdgeEdge{std::min(c.a, c.b), std::max(c.a, c.b)}));
  }
  CHECK_THROWS_WITH(proximity.close_pairs(p.V, 0), Catch::StartsWith("dhat = 0: must be"));
  CHECK_THROWS_WITH(proximity.candidates(p.V, -1), Catch::StartsWith("radius = -1: must be"));
  CHECK_THROWS_WITH(proximity.close_pairs(p.V.topRows(4), 0.1), Catch::StartsWith("V:"));
  // A bad value copied (column-major) or read in place (row-major) is named alike.
  Eigen::MatrixXd bad = p.V;
  bad(5, 2) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(proximity.close_pairs(bad, 0.03), Catch::StartsWith("V: row 5"));
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> bad_rows = bad;
  CHECK_THROWS_WITH(proximity.candidates(bad_rows, 0.03), Catch::StartsWith("V: row 5"));
  CHECK_FALSE(proximity.close_pairs(p.V, 0.03).empty());
}

TEST_CASE("a detector of close pairs over several objects finds the merged mesh's pairs", "[simulation]")
{
  Mesh lower = scenes::sheet(8, 8, 1, 1), upper = scenes::sheet(8, 8, 1, 1);
  for (Vec3& x : upper.positions) x += Vec3(0.03, 0.05, 0.02);
  SceneDescription scene;
  scene.add({"upper", upper.faces, upper.positions});
  scene.add({"lower", lower.faces, lower.positions});
  DetectorOptions options;
  options.detects = Detects::close_pairs;
  options.dhat = 0.03;
  options.solver.precision = test::device().device().fp64 ? Precision::double_ : Precision::single;
  Detector detector(test::device(), scene, options);
  detector.detect();
  const std::vector<ClosePair>& found = detector.close_pairs();
  CHECK(std::is_sorted(found.begin(), found.end(),
                       [](const ClosePair& x, const ClosePair& y) { return canonical_less(x, y); }));
  Mesh merged = upper;
  scenes::append(merged, lower);
  MeshProximityOptions one;
  one.precision = options.solver.precision;
  MeshProximity proximity(test::device(), CollisionMesh(merged.positions, merged.faces), one);
  const std::vector<ClosePair>& expected = proximity.close_pairs(merged.positions, 0.03);
  REQUIRE(found.size() == expected.size());
  // The same pairs, by the merged mesh's ids (the upper plate's come first).
  const auto nv = std::uint32_t(upper.positions.size()), nf = std::uint32_t(upper.faces.size());
  const auto merged_key = [&](const ClosePair& p) {
    if (p.kind == ContactKind::vertex_face)
      return test::PairKey{0, p.a + (p.object_a ? nv : 0), p.b + (p.object_b ? nf : 0), 0, 0};
    const std::uint32_t sa = p.object_a ? nv : 0, sb = p.object_b ? nv : 0;
    ClosePair q = p;
    q.v = {p.v[0] + sa, p.v[1] + sa, p.v[2] + sb, p.v[3] + sb};
    return test::key(q);
  };
  std::set<test::PairKey> from_detector, from_mesh;
  for (const ClosePair& p : found) from_detector.insert(merged_key(p));
  for (const ClosePair& p : expected) from_mesh.insert(test::key(p));
  CHECK(from_detector == from_mesh);
  CHECK(std::count_if(found.begin(), found.end(), [](const ClosePair& p) { return p.object_a != p.object_b; }) > 0);
}
