// The command line's parsing phase: every bad flag is refused, naming it, before any
// scene is read, device opened or file written.
#include "../support/benchmark_data.hpp"
#include "../support/scratch.hpp"
#include "cli_driver.hpp"

#include <commands.hpp>
#include <inputs.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <nlohmann/json.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;

TEST_CASE("numeric flags out of range are refused before any work, naming the flag and the range", "[cli][quick]")
{
  const std::vector<std::string> scene{funnel_frame("227.ply"), funnel_frame("228.ply")};
  const auto run = [&](std::vector<std::string> flags) {
    std::vector<std::string> args{"run"};
    args.insert(args.end(), scene.begin(), scene.end());
    args.insert(args.end(), flags.begin(), flags.end());
    bool ran = true;
    const std::string error = parse(args, &ran);
    CHECK(!ran);
    return error;
  };
  CHECK(run({"--tolerance", "-1"}) == "--tolerance = -1: must be a finite number in (0, 1]");
  CHECK(run({"--tolerance", "nan"}) == "--tolerance = nan: must be a finite number in (0, 1]");
  CHECK(run({"--tolerance", "inf"}) == "--tolerance = inf: must be a finite number in (0, 1]");
  CHECK(run({"--min-separation", "-0.5"}) == "--min-separation = -0.5: must be a finite number in [0, 1e+30]");
  CHECK(run({"--max-iterations", "0"}) == "--max-iterations = 0: must be a finite number in [1, 4294967295]");
  CHECK_THAT(run({"--max-iterations", "-1"}), Catch::Contains("--max-iterations"));
  CHECK_THAT(run({"--max-iterations", "4294967296"}), Catch::Contains("--max-iterations"));
  CHECK_THAT(run({"--front-budget", "0"}), Catch::StartsWith("--front-budget = 0: must be"));
  CHECK_THAT(run({"--front-climb", "-1"}), Catch::Contains("--front-climb"));
  CHECK_THAT(run({"--repeat", "0"}), Catch::StartsWith("--repeat = 0: must be"));
  CHECK_THAT(run({"--frames", "3abc"}), Catch::StartsWith("--frames '3abc': must be A"));
  CHECK_THAT(run({"--frames", "2:1"}), Catch::Contains("needs A < B"));
  CHECK_THAT(run({"--frames", ":"}), Catch::StartsWith("--frames ':'"));
  CHECK_THAT(run({"--solver", "fast"}), Catch::Contains("unknown solver 'fast'"));
  CHECK_THAT(run({"--front", "x"}), Catch::Contains("unknown front mode 'x'"));

  bool ran = false;
  CHECK(parse({"accuracy", "--tolerance", "1e-6", "--tolerance", "-2"}, &ran) ==
        "--tolerance = -2: must be a finite number in (0, 1]");
  CHECK(!ran);
  CHECK_THAT(parse({"reference", scene[0], "--tolerance", "nan"}), Catch::StartsWith("--tolerance = nan"));
  CHECK_THAT(parse({"generate", "cloth-sphere", "--out", "/tmp/x", "--resolution", "100000"}),
             Catch::StartsWith("--resolution = 100000: must be"));
  CHECK_THAT(parse({"generate", "cloth-sphere", "--out", "/tmp/x", "--frames", "-3"}),
             Catch::StartsWith("--frames = -3: must be"));
  CHECK(parse({"compare", scene[0], "--devices", "pocl"}, &ran) ==
        "--devices: give at least two device filters to compare");
  CHECK(!ran);
  CHECK_THAT(parse({"compare", scene[0], "--devices", "a", "b", "--tolerance", "0"}), Catch::StartsWith("--tolerance"));
  CHECK_THAT(parse({"compare", scene[0], "--devices", "a", "b", "--plot", "/nonexistent/p.png"}),
             Catch::StartsWith("--plot /nonexistent/p.png"));
}

TEST_CASE("output paths are checked when the command line is read", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-outputs");
  const std::string mesh = funnel_frame("227.ply");
  bool ran = true;
  CHECK(parse({"run", mesh, "--out", "/nonexistent/dir/c.csv"}, &ran) ==
        "--out /nonexistent/dir/c.csv: folder /nonexistent/dir does not exist");
  CHECK(!ran);
  CHECK_THAT(parse({"run", mesh, "--json", dir.string()}), Catch::EndsWith("is a folder, not a file"));
  CHECK_THAT(parse({"accuracy", "--plot", "/nonexistent/p.png"}), Catch::StartsWith("--plot /nonexistent/p.png"));
  CHECK_THAT(parse({"reference", mesh, "--out", "/nonexistent/r.csv"}), Catch::StartsWith("--out /nonexistent"));
  CHECK(parse({"run", mesh, "--out", (dir / "c.csv").string(), "--json", (dir / "s.json").string()}, &ran).empty());
  CHECK(ran);
  CHECK(fs::is_empty(dir));  // parsing wrote nothing
}

TEST_CASE("a run writes its contacts and statistics whole", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-run");
  auto cli = cstreams::cli::make_command_line();
  std::vector<std::string> args{"cstreams", "run", funnel_frame("227.ply"), funnel_frame("228.ply"),
                                "--out", (dir / "c.csv").string(), "--json", (dir / "s.json").string()};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  cli->app.parse(int(argv.size()), argv.data());
  cli->command();
  std::ifstream csv(dir / "c.csv");
  std::size_t lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  CHECK(lines > 1);  // a header and the step's contacts
  CHECK(fs::file_size(dir / "s.json") > 0);
  for (const auto& e : fs::directory_iterator(dir)) CHECK(e.path().extension() != ".partial");
}

TEST_CASE("compare runs one scene on several devices and finds their contacts identical", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-compare");
  // The device the tests run on, named twice: the same filter a user would give.
  const std::string device = cstreams::filter_from_environment();
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  execute({"run", a, b, "--device", device, "--json", (dir / "run.json").string()});
  execute({"compare", a, b, "--devices", device, device, "--json", (dir / "compare.json").string()});
  const auto run = nlohmann::json::parse(std::ifstream(dir / "run.json"));
  const auto compared = nlohmann::json::parse(std::ifstream(dir / "compare.json"));
  CHECK(compared["identical"] == true);
  CHECK(compared["differences"].empty());
  REQUIRE(compared["devices"].size() == 2);
  const bool timed = cstreams::runtime::Context(device).device().profiling_timer;
  for (const auto& d : compared["devices"]) {
    CHECK(d["contacts"] == run["steps"][0]["contacts"]);
    CHECK(d["passes"].contains("front update"));
    // A device whose profiling events do not time kernels (rusticl) reports none.
    if (timed) CHECK(d["median_device_ms"].get<double>() > 0);
    else CHECK(d["median_device_ms"].is_null());
  }
}

TEST_CASE("run --no-profile reports the same contacts, its wall time and no device times", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-no-profile");
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  execute({"run", a, b, "--out", (dir / "timed.csv").string()});
  execute({"run", a, b, "--no-profile", "--out", (dir / "untimed.csv").string(), "--json",
           (dir / "untimed.json").string()});
  std::ifstream timed(dir / "timed.csv"), untimed(dir / "untimed.csv");
  CHECK(std::string(std::istreambuf_iterator<char>(timed), {}) == std::string(std::istreambuf_iterator<char>(untimed), {}));
  const auto report = nlohmann::json::parse(std::ifstream(dir / "untimed.json"));
  CHECK(report["median_device_ms"].is_null());
  CHECK(report["median_host_ms"].get<double>() > 0);
  // Making the detector is not part of its first step's time, but a user meets it first.
  CHECK(report["detector_ms"].get<double>() > 0);
  CHECK(report["steps"][0]["passes"]["front update"]["ms"].is_null());
  CHECK(report["steps"][0]["device_span_ms"].is_null());
  CHECK(report["steps"][0]["commands"].empty());
}

TEST_CASE("run --front-climb reaches the detector and leaves the contacts as they are", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-front-climb");
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  execute({"run", a, b, "--repeat", "3", "--out", (dir / "default.csv").string()});
  execute({"run", a, b, "--repeat", "3", "--front-climb", "0", "--out", (dir / "kept.csv").string(), "--json",
           (dir / "kept.json").string()});
  std::ifstream climbed(dir / "default.csv"), kept(dir / "kept.csv");
  CHECK(std::string(std::istreambuf_iterator<char>(climbed), {}) ==
        std::string(std::istreambuf_iterator<char>(kept), {}));
  CHECK(nlohmann::json::parse(std::ifstream(dir / "kept.json"))["front_climb_levels"] == 0);
}

// A user replaying a sequence sees a hitch without a per-step table: the tail names the
// slowest step by its frame and the 90th percentile, from the very steps listed.
TEST_CASE("run --json gives the tail of a sequence's step times: the slowest step and the 90th percentile",
          "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-tail");
  const fs::path cloth = dir / "cloth";
  execute({"generate", "cloth-sphere", "--out", cloth.string(), "--frames", "13", "--resolution", "16"});
  execute({"run", (cloth / "scene.json").string(), "--frames", "2:12", "--json", (dir / "run.json").string()});
  const auto report = nlohmann::json::parse(std::ifstream(dir / "run.json"));
  const auto& steps = report["steps"];
  REQUIRE(steps.size() == 10);
  for (const char* time : {"host_ms", "step_ms"}) {
    INFO(time);
    std::vector<double> per_step;
    for (const auto& s : steps) per_step.push_back(s[time].get<double>());
    const auto slowest = std::max_element(per_step.begin(), per_step.end());
    const auto& t = report["tail"][time];
    CHECK(t["max"].get<double>() == *slowest);
    CHECK(t["max_frame"].get<std::size_t>() == steps[std::size_t(slowest - per_step.begin())]["frame"].get<std::size_t>());
    // Nearest rank: the 9th of 10 sorted steps.
    std::sort(per_step.begin(), per_step.end());
    CHECK(t["p90"].get<double>() == per_step[8]);
    CHECK(t["median"].get<double>() == 0.5 * (per_step[4] + per_step[5]));
  }
  if (!steps[0]["device_ms"].is_null()) CHECK(report["tail"]["device_ms"]["max"].get<double>() > 0);
  else CHECK(report["tail"]["device_ms"]["max"].is_null());
}

// The device's span of a step holds its passes one after another (one in-order queue)
// and the idle time between them: no shorter than their sum, and within the step's
// wall time. Its commands, each timed, show where that idle time went: every launch and
// blocking read of the step, in queue order, and each pass's time is its commands'.
TEST_CASE("run --json gives each step's device span around its passes' time, and each command in it",
          "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-span");
  execute({"run", funnel_frame("227.ply"), funnel_frame("228.ply"), "--repeat", "3", "--json",
           (dir / "run.json").string()});
  const auto step = nlohmann::json::parse(std::ifstream(dir / "run.json"))["steps"][0];
  if (step["device_ms"].is_null()) {  // a device without a kernel timer (rusticl on llvmpipe)
    CHECK(step["device_span_ms"].is_null());
    CHECK(step["commands"].empty());
    return;
  }
  const double device = step["device_ms"].get<double>(), span = step["device_span_ms"].get<double>();
  CHECK(device > 0);
  CHECK(span >= device);
  CHECK(span <= step["host_ms"].get<double>());

  const auto& commands = step["commands"];
  REQUIRE_FALSE(commands.empty());
  CHECK(commands[0]["start_us"].get<double>() == 0);
  unsigned launches = 0, reads = 0;
  std::map<std::string, double> pass_us;
  double ended = 0, host_before = 0;
  for (const auto& c : commands) {
    const std::string what = c["what"];
    const double queued = c["queued_us"], start = c["start_us"], end = c["end_us"], host = c["host_us"];
    CHECK(queued <= start);
    // The host queues in order, from the step's start.
    CHECK(host >= host_before);
    host_before = host;
    CHECK(start <= end);
    CHECK(start >= ended);
    ended = end;
    if (what == "readback") {
      ++reads;
    } else if (what != "fill" && what != "copy" && what != "upload") {
      ++launches;
      pass_us[what] += end - start;
    }
  }
  CHECK(launches == step["launches"].get<unsigned>());
  CHECK(reads == step["blocking_reads"].get<unsigned>());
  for (const auto& [name, pass] : step["passes"].items())
    CHECK(pass["ms"].get<double>() * 1e3 == Approx(pass_us[name]).margin(1e-3));
}

TEST_CASE("run --earliest-only gives the earliest time without reading or sorting the contacts", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-earliest");
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  execute({"run", a, b, "--json", (dir / "all.json").string()});
  execute({"run", a, b, "--earliest-only", "--json", (dir / "earliest.json").string()});
  const auto all = nlohmann::json::parse(std::ifstream(dir / "all.json"));
  const auto earliest = nlohmann::json::parse(std::ifstream(dir / "earliest.json"));
  CHECK(earliest["earliest_only"] == true);
  CHECK_FALSE(earliest["steps"][0]["passes"].contains("canonical contacts"));
  REQUIRE(all["steps"][0]["passes"].contains("canonical contacts"));
  // The conservative solver settles only the pairs that may come first: some, not all.
  const auto &with = all["steps"][0], without = earliest["steps"][0];
  CHECK(without["contacts"].get<int>() > 0);
  CHECK(without["contacts"].get<int>() < with["contacts"].get<int>());
  // Reading the contacts costs the launches of their mapping and sort, and one read;
  // refining the rest, rounds and their counter reads. The minimum over the contacts
  // runs on the device only where they are not read back (the host takes it from them).
  const auto rounds = [](const nlohmann::json& step) { return step["passes"]["refine open queries"]["launches"].get<int>(); };
  const auto minimum = [](const nlohmann::json& step) {
    return step["passes"]["clear earliest toi"]["launches"].get<int>() +
           step["passes"]["earliest toi"]["launches"].get<int>();
  };
  CHECK(rounds(without) < rounds(with));
  CHECK(minimum(with) == 0);
  CHECK(minimum(without) == 2);
  CHECK(with["launches"].get<int>() - without["launches"].get<int>() >=
        with["passes"]["canonical contacts"]["launches"].get<int>() + rounds(with) - rounds(without) - minimum(without));
  CHECK(with["blocking_reads"].get<int>() - without["blocking_reads"].get<int>() >= 1);
  CHECK(without["blocking_reads"].get<int>() >= 1);
  // The earliest time, rounded down to float on the device.
  const double exact = all["earliest_toi"].get<double>(), rounded = earliest["earliest_toi"].get<double>();
  CHECK(rounded <= exact);
  CHECK(rounded >= double(std::nextafter(float(exact), 0.0f)));
  CHECK_THAT(parse({"run", a, b, "--earliest-only", "--out", (dir / "c.csv").string()}),
             Catch::Contains("--earliest-only"));
}

TEST_CASE("run --memory-budget keeps the step under the budget with the same contacts, or names what does not fit",
          "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-memory-budget");
  const std::string a = funnel_frame("227.ply"), b = funnel_frame("228.ply");
  const auto text = [](const fs::path& file) {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  execute({"run", a, b, "--json", (dir / "free.json").string(), "--out", (dir / "free.csv").string()});
  execute({"run", a, b, "--registration", "global-atomic", "--json", (dir / "atomic.json").string()});
  const auto free_run = nlohmann::json::parse(std::ifstream(dir / "free.json"));
  const std::size_t peak = free_run["peak_bytes"];
  const std::size_t floor = nlohmann::json::parse(std::ifstream(dir / "atomic.json"))["peak_bytes"];
  // Segments sit in the step arena beside the streams that live within the step, so
  // either peak may be the higher.
  const std::size_t high = std::max(floor, peak);
  const auto& step = free_run["steps"][0];
  CHECK(step["peak_bytes"].get<std::size_t>() <= peak);
  CHECK(step["peak_bytes"].get<std::size_t>() >= step["device_bytes"].get<std::size_t>());
  for (const auto& s : step["streams"]) CHECK(s["peak_bytes"].get<std::size_t>() >= s["bytes"].get<std::size_t>());

  // From what the step needs with every pass registering through one counter up to the
  // higher of the two peaks: segments go back, stages end early, registration falls back
  // to the counter, and the contacts stay the same.
  for (double share : {0.0, 0.1, 0.5, 0.9}) {
    const double budget_mb = (double(floor) + share * double(high - floor)) / (1 << 20) + 1e-6;
    const fs::path json = dir / "budget.json", csv = dir / "budget.csv";
    INFO("budget " << budget_mb << " MiB, peak " << peak << " bytes, global counter's peak " << floor);
    execute({"run", a, b, "--memory-budget", std::to_string(budget_mb), "--json", json.string(), "--out", csv.string()});
    const auto j = nlohmann::json::parse(std::ifstream(json));
    CHECK(j["memory_budget_mb"].get<double>() == Approx(budget_mb));
    CHECK(j["peak_bytes"].get<double>() <= budget_mb * (1 << 20));
    CHECK(text(csv) == text(dir / "free.csv"));
  }

  // Below that, passes run in slices where they must. Whether the funnel's step leaves
  // room for slices between the least it runs whole in and the least it runs at all
  // depends on the device: on the H200 it leaves none, since slicing its front update
  // saves little beside the whole next front that the slices gather (0.8-0.92 of the
  // global counter's peak fail allocating it, 0.94-0.98 run whole). So slices are asked
  // of the generated bodies, whose steps slice on every device (test_detector.cpp):
  // each budget runs with the same contacts or fails naming the allocation, and some
  // steps run in slices.
  const fs::path bodies = dir / "bodies";
  execute({"generate", "n-body", "--out", bodies.string(), "--seed", "1", "--frames", "24", "--resolution", "40"});
  const std::string scene = (bodies / "scene.json").string();
  execute({"run", scene, "--json", (dir / "bodies.json").string(), "--out", (dir / "bodies.csv").string()});
  const std::size_t bodies_peak = nlohmann::json::parse(std::ifstream(dir / "bodies.json"))["peak_bytes"];
  unsigned sliced = 0;
  for (double share : {0.8, 0.75, 0.7, 0.6, 0.5}) {
    const double budget_mb = share * double(bodies_peak) / (1 << 20);
    const fs::path json = dir / "sliced.json", csv = dir / "sliced.csv";
    INFO("budget " << budget_mb << " MiB, the bodies' unbudgeted peak " << bodies_peak << " bytes");
    try {
      execute({"run", scene, "--memory-budget", std::to_string(budget_mb), "--json", json.string(), "--out", csv.string()});
    } catch (const std::exception& e) {
      CHECK(share < 0.8);
      CHECK_THAT(e.what(), Catch::Contains("allocating"));
      continue;
    }
    const auto j = nlohmann::json::parse(std::ifstream(json));
    for (const auto& step : j["steps"])
      if (step["slices"].get<unsigned>() > 1) {
        ++sliced;
        CHECK_FALSE(step["sliced_pass"].get<std::string>().empty());
      }
    CHECK(j["peak_bytes"].get<double>() <= budget_mb * (1 << 20));
    CHECK(text(csv) == text(dir / "bodies.csv"));
  }
  CHECK(sliced > 0);

  // Far below what the streams need: an error naming the allocation, and no output.
  const fs::path csv = dir / "tiny.csv";
  CHECK_THROWS_WITH(execute({"run", a, b, "--memory-budget", "0.01", "--out", csv.string()}),
                    Catch::Contains("MiB") && Catch::Contains("in use"));
  CHECK_FALSE(fs::exists(csv));
  CHECK_THAT(parse({"run", a, b, "--memory-budget", "-1"}), Catch::StartsWith("--memory-budget = -1: must be"));
}

TEST_CASE("accuracy on several devices reports false negatives and positives per device", "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-accuracy");
  const std::string device = cstreams::filter_from_environment();
  const std::string queries = cstreams::test::benchmark_path("sample-queries/unit-tests");
  execute({"accuracy", "--queries", queries, "--devices", device, device, "--precision", "single", "--repeat", "1",
           "--json", (dir / "accuracy.json").string()});
  const auto out = nlohmann::json::parse(std::ifstream(dir / "accuracy.json"));
  REQUIRE(out["devices"].size() == 2);
  const auto& results = out["results"];
  // Two solvers, two kinds, on each device.
  REQUIRE(results.size() == 8);
  const std::size_t half = results.size() / 2;
  for (std::size_t i = 0; i < half; ++i) {
    const auto &a = results[i], &b = results[half + i];
    CHECK(a["device"] == out["devices"][0]["device"]);
    CHECK(b["device"] == out["devices"][1]["device"]);
    CHECK(a["solver"] == b["solver"]);
    CHECK(a["kind"] == b["kind"]);
    CHECK(a["false_negatives"] == b["false_negatives"]);
    CHECK(a["false_positives"] == b["false_positives"]);
    if (a["solver"] == "conservative") CHECK(a["false_negatives"] == 0);
  }
  CHECK_THAT(parse({"accuracy", "--device", device, "--devices", device, device}), Catch::Contains("excludes"));
}

TEST_CASE("the command-line fuzz corpus parses or is refused", "[cli][fuzz][quick]")
{
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(std::string(CSTREAMS_FUZZ_CORPUS) + "/command_line")) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    INFO(entry.path().string());
    CHECK_NOTHROW(cstreams::fuzz::command_line(bytes));
    ++files;
  }
  CHECK(files >= 8);
}

// Single precision decides in double the contacts float cannot prove, where the device
// has double: rod-twist's step, whose float alone answers 0, comes within [0.5, 1] of
// its exact earliest time; `accuracy` gives that time beside the exact one, and
// `--no-escalation` reaches both commands.
TEST_CASE("run and accuracy report single precision's escalation and the earliest time against the exact one",
          "[cli][quick]")
{
  const fs::path dir = fresh_dir("cstreams-cli-escalation");
  const std::string step = cstreams::test::benchmark_path("scalable-ccd-sample/rod-twist");
  execute({"accuracy", "--queries", step, "--solver", "conservative", "--precision", "single", "--repeat", "1",
           "--json", (dir / "accuracy.json").string()});
  const auto accuracy = nlohmann::json::parse(std::ifstream(dir / "accuracy.json"));
  double exact = 1;
  for (const auto& r : accuracy["results"]) {
    REQUIRE_FALSE(r["exact_earliest"].is_null());
    CHECK(r["earliest"].get<double>() <= r["exact_earliest"].get<double>());
    exact = std::min(exact, r["exact_earliest"].get<double>());
  }
  REQUIRE(exact > 0);
  const std::string a = step + "/frames/3036.ply", b = step + "/frames/3037.ply";
  execute({"run", a, b, "--json", (dir / "run.json").string()});
  execute({"run", a, b, "--no-escalation", "--json", (dir / "float.json").string()});
  const auto run = nlohmann::json::parse(std::ifstream(dir / "run.json"));
  const auto in_float = nlohmann::json::parse(std::ifstream(dir / "float.json"));
  CHECK(in_float["escalation"] == false);
  CHECK(in_float["steps"][0]["escalated"] == 0);
  CHECK(in_float["earliest_toi"].get<double>() <= exact);
  const cstreams::runtime::Context context(cstreams::filter_from_environment());
  if (!context.device().fp64) return;
  CHECK(run["escalation"] == true);
  CHECK(run["steps"][0]["escalated"].get<int>() > 0);
  CHECK(run["earliest_toi"].get<double>() <= exact);
  CHECK(run["earliest_toi"].get<double>() >= 0.5 * exact);
}
