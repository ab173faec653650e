// Options and files a user gets wrong: each is refused with a message naming the
// option or the file, before any work, and changes nothing.
#include "../support/scratch.hpp"
#include "../support/test_device.hpp"

#include <cstreams/detector.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/io/query_io.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

using namespace cstreams;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) { return cstreams::test::fresh_scratch("input-checks-" + name); }

SceneDescription two_balls()
{
  SceneDescription scene;
  for (double x : {0.0, 1.2}) {
    Mesh m = scenes::icosphere(1, 0.5);
    for (auto& p : m.positions) p.x() += x;
    scene.add({"ball" + std::to_string(scene.objects.size()), m.faces, m.positions});
  }
  return scene;
}

// Eight rows of one query with the given first coordinate, in the hand-made format.
std::string query_rows(const std::string& first_x)
{
  std::string rows = first_x + ",0,1,0,1,1\n";
  for (int i = 1; i < 8; ++i) rows += std::to_string(i) + ",4,0,1,1,2,1\n";
  return rows;
}

}  // namespace

TEST_CASE("option ranges refuse NaN, infinities and values outside, naming the option", "[options][quick]")
{
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  for (double bad : {-1.0, 0.0, 1.5, nan, inf, -inf})
    CHECK_THROWS_WITH(check_option("--tolerance", bad, option_ranges::tolerance),
                      Catch::StartsWith("--tolerance = ") && Catch::Contains("must be a finite number in (0, 1]"));
  for (double good : {1e-12, 1e-5, 1.0}) CHECK_NOTHROW(check_option("--tolerance", good, option_ranges::tolerance));
  CHECK_THROWS_WITH(check_option("--min-separation", -1e-9, option_ranges::min_separation),
                    Catch::Contains("[0, 1e+30]"));
  CHECK_NOTHROW(check_option("--min-separation", 0, option_ranges::min_separation));
  CHECK_THROWS_AS(check_option("x", 0, option_ranges::max_iterations), InputError);
  CHECK_THROWS_AS(check_option("x", 0, option_ranges::front_budget_mb), InputError);
}

TEST_CASE("a detector and a solver refuse options out of range before building anything", "[options][quick]")
{
  auto& device = cstreams::test::device();
  const auto refused = [&](DetectorOptions o, const std::string& name) {
    CHECK_THROWS_WITH(Detector(device, two_balls(), o), Catch::Contains(name) && Catch::Contains("must be"));
    CHECK_THROWS_AS(Detector(device, two_balls(), o), InputError);
  };
  DetectorOptions o;
  o.solver.tolerance = -1;
  refused(o, "SolverOptions::tolerance = -1");
  o.solver.tolerance = std::nan("");
  refused(o, "SolverOptions::tolerance = nan");
  o = {};
  o.solver.min_separation = std::numeric_limits<double>::infinity();
  refused(o, "SolverOptions::min_separation = inf");
  o = {};
  o.solver.max_iterations = 0;
  refused(o, "SolverOptions::max_iterations = 0");
  o = {};
  o.front_budget_mb = -3;
  refused(o, "DetectorOptions::front_budget_mb = -3");

  SolverOptions s;
  s.tolerance = 0;
  CHECK_THROWS_WITH(DeviceSolver(device, s), Catch::Contains("SolverOptions::tolerance = 0"));

  // The defaults pass, and a detector built after the refusals works.
  const SceneDescription scene = two_balls();
  Detector detector(device, scene);
  auto closer = scene.objects[1].positions;
  for (auto& p : closer) p.x() -= 0.5;
  detector.set_positions(1, closer);
  detector.detect();
  CHECK(!detector.contacts().empty());
}

TEST_CASE("a folder where a file belongs is named as such", "[io][quick]")
{
  const fs::path dir = scratch("folders");
  fs::create_directories(dir / "mesh.ply");
  fs::create_directories(dir / "scene.json");
  fs::create_directories(dir / "queries.csv");
  CHECK_THROWS_WITH(read_mesh((dir / "mesh.ply").string()), Catch::EndsWith("mesh.ply: is a directory, not a mesh file"));
  CHECK_THROWS_WITH(load_scene((dir / "mesh.ply").string()), Catch::Contains("is a directory, not a mesh file"));
  CHECK_THROWS_WITH(load_scene((dir / "scene.json").string()),
                    Catch::EndsWith("scene.json: is a directory, not a scene manifest"));
  CHECK_THROWS_WITH(read_queries((dir / "queries.csv").string()),
                    Catch::EndsWith("queries.csv: is a directory, not a query file"));
  CHECK_THROWS_WITH(read_mesh((dir / "missing.obj").string()), Catch::EndsWith("missing.obj: no such mesh file"));
  CHECK_THROWS_WITH(read_ply("/dev/zero"), Catch::Equals("/dev/zero: is not a regular file, not a mesh file"));
}

TEST_CASE("query files hold exact rationals only", "[io][quick]")
{
  std::istringstream exact(query_rows("6,3"));
  const auto queries = parse_queries(exact, "exact.csv");
  REQUIRE(queries.size() == 1);
  CHECK(queries[0].points[0].x() == 2);
  CHECK(queries[0].points[1].x() == 0.25);

  // 1/3 has no double; its nearest double times 3 rounds back to 1, which an unfused
  // check would take for exact.
  std::istringstream third(query_rows("1,3"));
  CHECK_THROWS_WITH(parse_queries(third, "third.csv"), Catch::Contains("third.csv:1: 1/3 is not exact in double"));
  std::istringstream tenth(query_rows("1,10"));
  CHECK_THROWS_WITH(parse_queries(tenth, "tenth.csv"), Catch::Contains("tenth.csv:1: 1/10 is not exact"));
  std::istringstream zero(query_rows("1,0"));
  CHECK_THROWS_WITH(parse_queries(zero, "zero.csv"), Catch::Contains("zero.csv:1: zero denominator"));
  const std::string rows = query_rows("1,2");
  std::istringstream cut(rows.substr(0, rows.find("3,4")));
  CHECK_THROWS_WITH(parse_queries(cut, "cut.csv"), Catch::Contains("truncated"));
}

TEST_CASE("output paths are checked before work and written whole or not at all", "[io][quick]")
{
  const fs::path dir = scratch("outputs");
  CHECK_THROWS_WITH(check_output_path("--out", "/nonexistent/dir/c.csv"),
                    Catch::Equals("--out /nonexistent/dir/c.csv: folder /nonexistent/dir does not exist"));
  CHECK_THROWS_WITH(check_output_path("--json", dir.string()), Catch::Contains("is a folder, not a file"));
  std::ofstream((dir / "plain").string()) << "x";
  CHECK_THROWS_WITH(check_output_path("--plot", (dir / "plain" / "p.png").string()), Catch::Contains("is not a folder"));
  CHECK_NOTHROW(check_output_path("--out", (dir / "c.csv").string()));

  const std::string target = (dir / "c.csv").string();
  write_file_atomically(target, [](std::ostream& out) { out << "old\n"; });
  CHECK_THROWS(write_file_atomically(target, [](std::ostream& out) {
    out << "half";
    throw InputError("interrupted");
  }));
  std::ifstream in(target);
  std::string line;
  std::getline(in, line);
  CHECK(line == "old");
  CHECK(!fs::exists(target + ".partial"));
}
