// The commands of the array API: what they print and write, and the flags they refuse.
#include "cli_driver.hpp"

#include <nlohmann/json.hpp>

#include <catch2/catch.hpp>

#include <fstream>

TEST_CASE("stepsize gives the collision-free step size and the earliest time of a step", "[cli][quick]")
{
  const auto dir = fresh_dir("cstreams-cli-stepsize");
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  execute({"stepsize", a, b, "--repeat", "2", "--json", (dir / "s.json").string()});
  execute({"run", a, b, "--json", (dir / "run.json").string()});
  const auto step = nlohmann::json::parse(std::ifstream(dir / "s.json"));
  const auto run = nlohmann::json::parse(std::ifstream(dir / "run.json"));
  CHECK(step["collision_free"] == false);
  // The step's earliest time as `run` finds it, rounded down to float, and 0.8 of it.
  const double toi = step["toi"].get<double>(), earliest = run["earliest_toi"].get<double>();
  CHECK(toi <= earliest);
  CHECK(toi >= double(std::nextafter(float(earliest), 0.0f)));
  CHECK(step["stepsize"].get<double>() == 0.8 * toi);
  CHECK(step["call_ms"].size() == 2);

  execute({"stepsize", a, a, "--repeat", "1", "--json", (dir / "still.json").string()});
  const auto still = nlohmann::json::parse(std::ifstream(dir / "still.json"));
  CHECK(still["collision_free"] == true);
  CHECK(still["stepsize"] == 1.0);
  CHECK(still["toi"].is_null());
}

TEST_CASE("stepsize refuses bad flags and mismatched frames, naming them", "[cli][quick]")
{
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  bool ran = true;
  CHECK_THAT(parse({"stepsize", a, b, "--rescaling", "1"}, &ran), Catch::StartsWith("--rescaling = 1: must be"));
  CHECK(!ran);
  CHECK_THAT(parse({"stepsize", a, b, "--min-separation", "-1"}), Catch::StartsWith("--min-separation = -1"));
  CHECK_THAT(parse({"stepsize", a, b, "--tolerance", "0"}), Catch::StartsWith("--tolerance = 0"));
  CHECK_THAT(parse({"stepsize", a, b, "--precision", "half"}), Catch::Contains("half"));
  CHECK_THAT(parse({"stepsize", a}), Catch::Contains("end"));
  const std::string other = cstreams::test::benchmark_path("scalable-ccd-sample/rod-twist/frames/3036.ply");
  CHECK_THROWS_WITH(execute({"stepsize", a, other}), Catch::StartsWith(other + ": has"));
}

TEST_CASE("proximity counts the close pairs of a mesh and writes them", "[cli][quick]")
{
  const auto dir = fresh_dir("cstreams-cli-proximity");
  const std::string a = funnel_frame("227.ply");
  execute({"proximity", a, "--dhat", "0.002", "--relative", "--repeat", "1", "--json", (dir / "p.json").string(),
           "--out", (dir / "p.csv").string()});
  const auto j = nlohmann::json::parse(std::ifstream(dir / "p.json"));
  const std::size_t pairs = j["pairs"].get<std::size_t>();
  CHECK(pairs > 0);
  std::size_t by_kind = 0;
  for (const auto& [closest, count] : j["by_closest_features"].items()) by_kind += count.get<std::size_t>();
  CHECK(by_kind == pairs);
  CHECK(j["smallest_distance"].get<double>() < j["dhat"].get<double>());
  std::ifstream csv(dir / "p.csv");
  std::size_t lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  CHECK(lines == pairs + 1);

  bool ran = true;
  CHECK_THAT(parse({"proximity", a, "--dhat", "0"}, &ran), Catch::StartsWith("--dhat = 0: must be"));
  CHECK(!ran);
  CHECK_THAT(parse({"proximity", a}), Catch::Contains("--dhat"));
  CHECK_THAT(parse({"proximity", a, "--dhat", "1", "--out", "/nonexistent/p.csv"}), Catch::StartsWith("--out"));
}
