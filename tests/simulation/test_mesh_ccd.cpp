// The array API's CCD calls against motions whose first contact is known exactly
// (plates.hpp) and against the exact earliest time of a real step.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"
#include "plates.hpp"

#include <cstreams/datasets/datasets.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace cstreams;

namespace {

// Never later than the exact time, and no earlier than a small slack below it.
void check_toi(double toi, double exact)
{
  CHECK(toi <= exact);
  CHECK(toi >= exact - 1e-4);
}

// The plates' exact first contact at a separation measured in the Euclidean norm (the
// latest time allowed) and in the max norm, which the solvers use (the earliest).
double plates_contact(double separation, double drop = 0.3) { return (0.1 - separation) / drop; }
double plates_contact_max_norm(double separation, double drop = 0.3)
{
  return (0.1 - std::sqrt(3.0) * separation) / drop;
}

}  // namespace

TEST_CASE("toi of a motion is the exact first contact, never later", "[simulation]")
{
  const auto p = test::plates(0.1);
  MeshCcd ccd(test::device(), CollisionMesh(p.V, p.F));
  const Eigen::MatrixXd V1 = p.dropped(0.3);
  // The lowest corner comes down 0.1 of 0.3.
  check_toi(ccd.toi(p.V, V1), 0.1 / 0.3);
  // The separation is measured in the max norm: a pair up to sqrt(3) times as far
  // apart may count as colliding, never a closer one as free.
  CcdParameters apart;
  apart.min_distance = 0.01;
  const double separated = ccd.toi(p.V, V1, apart);
  CHECK(separated <= plates_contact(0.01));
  CHECK(separated >= plates_contact_max_norm(0.01));
  // Only [0, tmax] is checked: nothing collides before 0.3, and the time keeps the
  // motion's own scale.
  CcdParameters early;
  early.tmax = 0.3;
  CHECK(ccd.toi(p.V, V1, early) == 1.0);
  early.tmax = 0.5;
  check_toi(ccd.toi(p.V, V1, early), 0.1 / 0.3);
  // A motion that stops short collides with nothing.
  CHECK(ccd.toi(p.V, p.dropped(0.05)) == 1.0);
}

TEST_CASE("is_step_collision_free and collision_free_stepsize keep ipc-toolkit's meaning", "[simulation]")
{
  const auto p = test::plates(0.1);
  MeshCcd ccd(test::device(), CollisionMesh(p.V, p.F));
  const Eigen::MatrixXd V1 = p.dropped(0.3), short_of = p.dropped(0.05);
  CHECK_FALSE(ccd.is_step_collision_free(p.V, V1));
  CHECK(ccd.is_step_collision_free(p.V, short_of));
  // Stopping 0.05 above the plate is not free with a separation of 0.06.
  CHECK_FALSE(ccd.is_step_collision_free(p.V, short_of, 0.06));

  // A full step where it is free; otherwise a step that ends short of the contact.
  CHECK(ccd.collision_free_stepsize(p.V, short_of) == 1.0);
  for (const double separation : {0.0, 0.01}) {
    const double alpha = ccd.collision_free_stepsize(p.V, V1, separation);
    CHECK(alpha >= default_conservative_rescaling * (plates_contact_max_norm(separation) - 1e-4));
    CHECK(alpha <= default_conservative_rescaling * plates_contact(separation));
    const Eigen::MatrixXd reached = p.V + alpha * (V1 - p.V);
    CHECK(p.lowest_upper(reached) > separation);
    CHECK(ccd.is_step_collision_free(p.V, reached, separation));
  }
  CHECK(ccd.collision_free_stepsize(p.V, V1, 0, 0.5) <= 0.5 * 0.1 / 0.3);
  // Starting in contact allows no step at all.
  CHECK(ccd.collision_free_stepsize(p.V, V1, 0.2) == 0.0);
}

TEST_CASE("positions come as float or double, in either storage order", "[simulation]")
{
  const auto p = test::plates(0.1);
  MeshCcd ccd(test::device(), CollisionMesh(p.V, p.F));
  const Eigen::MatrixXd V1 = p.dropped(0.3);
  const double toi = ccd.toi(p.V, V1);
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> row_major0 = p.V, row_major1 = V1;
  CHECK(ccd.toi(row_major0, row_major1) == toi);
  // Float positions are other positions (rounded), so the time moves by a rounding.
  const Eigen::MatrixXf float0 = p.V.cast<float>(), float1 = V1.cast<float>();
  CHECK(std::abs(ccd.toi(float0, float1) - toi) < 1e-5);
  const Eigen::Matrix<long, Eigen::Dynamic, 3, Eigen::RowMajor> long_faces = p.F.cast<long>();
  MeshCcd from_long_faces(test::device(), CollisionMesh(p.V, long_faces));
  CHECK(from_long_faces.toi(p.V, V1) == toi);
}

TEST_CASE("a line search's repeated calls stay on the warm path with the same answers", "[simulation]")
{
  const auto p = test::plates(0.1);
  MeshCcd ccd(test::device(), CollisionMesh(p.V, p.F));
  const Eigen::MatrixXd V1 = p.dropped(0.3);
  double alpha = 1;
  std::vector<double> answers;
  for (int call = 0; call < 4; ++call, alpha *= 0.5) answers.push_back(ccd.toi(p.V, p.V + alpha * (V1 - p.V)));
  CHECK(ccd.stats().front_pairs > 0);
  alpha = 1;
  for (int call = 0; call < 4; ++call, alpha *= 0.5) {
    MeshCcd cold(test::device(), CollisionMesh(p.V, p.F));
    CHECK(cold.toi(p.V, p.V + alpha * (V1 - p.V)) == answers[std::size_t(call)]);
  }
  check_toi(answers[0], 0.1 / 0.3);
  check_toi(answers[1], 0.1 / 0.15);
  CHECK(answers[2] == 1.0);
}

TEST_CASE("bad arrays and parameters name themselves and leave the object usable", "[simulation]")
{
  const auto p = test::plates(0.1, 4);
  MeshCcd ccd(test::device(), CollisionMesh(p.V, p.F));
  const Eigen::MatrixXd V1 = p.dropped(0.3);
  const double toi = ccd.toi(p.V, V1);
  const auto fails_naming = [](auto&& call, const char* name) {
    CHECK_THROWS_MATCHES(call(), InputError, Catch::Matchers::Predicate<InputError>([name](const InputError& e) {
                           return std::string(e.what()).rfind(name, 0) == 0;
                         }, std::string("starts with ") + name));
  };
  fails_naming([&] { ccd.toi(p.V.topRows(3), V1); }, "V0");
  Eigen::MatrixXd bad = V1;
  bad(2, 1) = std::numeric_limits<double>::quiet_NaN();
  fails_naming([&] { ccd.toi(p.V, bad); }, "V1");
  bad(2, 1) = 1e300;
  fails_naming([&] { ccd.is_step_collision_free(p.V, bad); }, "V1");
  // Row-major doubles are read in place, where the detector's own check finds the bad
  // value: the argument is still the one named.
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  Rows bad_rows = V1;
  bad_rows(2, 1) = std::numeric_limits<double>::quiet_NaN();
  fails_naming([&] { ccd.toi(Rows(p.V), bad_rows); }, "V1: row 2");
  bad_rows = p.V;
  bad_rows(3, 0) = -1e300;
  fails_naming([&] { ccd.collision_free_stepsize(bad_rows, Rows(V1)); }, "V0: row 3");
  fails_naming([&] { ccd.toi(p.V, Eigen::MatrixXd(V1.leftCols(2))); }, "V1");
  CcdParameters wrong;
  wrong.tmax = 0;
  fails_naming([&] { ccd.toi(p.V, V1, wrong); }, "tmax");
  wrong = {};
  wrong.min_distance = -1;
  fails_naming([&] { ccd.toi(p.V, V1, wrong); }, "min_distance");
  wrong = {};
  wrong.tolerance = 0;
  fails_naming([&] { ccd.toi(p.V, V1, wrong); }, "tolerance");
  fails_naming([&] { ccd.collision_free_stepsize(p.V, V1, 0, 1.0); }, "conservative_rescaling");
  CHECK(ccd.toi(p.V, V1) == toi);

  Eigen::MatrixXi faces = p.F;
  faces(3, 2) = int(p.V.rows());
  fails_naming([&] { CollisionMesh(p.V, faces); }, "F");
  faces(3, 2) = -1;
  fails_naming([&] { CollisionMesh(p.V, faces); }, "F");
  faces = p.F;
  faces(1, 1) = faces(1, 0);
  fails_naming([&] { CollisionMesh(p.V, faces); }, "F");
  fails_naming([&] { CollisionMesh(p.V, Eigen::MatrixXi(p.F.leftCols(2))); }, "F");
  Eigen::MatrixXi edges(1, 2);
  edges << 0, int(p.V.rows());
  fails_naming([&] { CollisionMesh(p.V, p.F, edges); }, "E");
  edges << 3, 3;
  fails_naming([&] { CollisionMesh(p.V, p.F, edges); }, "E");
  fails_naming([&] { CollisionMesh(Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3)); }, "V");
}

TEST_CASE("toi of a real step lies within a tolerance below its exact earliest time", "[simulation]")
{
  const test::RealStep& s = test::real_steps[0];
  REQUIRE(std::string(s.scene) == "cloth-funnel");
  const std::string folder = test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene);
  const Mesh a = read_mesh(folder + "/frames/" + s.frame0), b = read_mesh(folder + "/frames/" + s.frame1);
  long double exact = 1;
  for (const ContactKind kind : {ContactKind::vertex_face, ContactKind::edge_edge})
    for (const long double t : real_step_dataset(folder, kind).exact_toi)
      if (!std::isnan(t)) exact = std::min(exact, t);
  REQUIRE(exact < 1);
  for (const Precision precision : {Precision::single, Precision::double_}) {
    if (precision == Precision::double_ && !test::device().device().fp64) continue;
    MeshCcdOptions options;
    options.precision = precision;
    MeshCcd ccd(test::device(), CollisionMesh(a.positions, a.faces), options);
    const double toi = ccd.toi(a.positions, b.positions);
    CHECK(toi <= double(exact));
    CHECK(toi >= 0.99 * double(exact));
  }
}
