#pragma once
// What `run` and `compare` share: the options of a measured run over a scene's steps,
// and the measurement itself (times per pass and step, memory, contacts) on one device.
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/scene/scene.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace cstreams::cli {

struct MeasureOptions {
  std::vector<std::string> paths;
  bool split = false;
  std::string solver = "conservative";
  std::string precision = "single";
  std::string front = "exact";
  std::string registration = "segmented-lock";
  double tolerance = SolverOptions{}.tolerance;
  double min_separation = 0;
  std::uint32_t max_iterations = SolverOptions{}.max_iterations;
  bool no_escalation = false;
  double front_budget = DetectorOptions{}.front_budget_mb;
  std::uint32_t front_climb = DetectorOptions{}.front_climb_levels;
  // Device memory the whole pipeline may hold, MiB (Context::set_memory_limit); 0: all
  // the device has. Under it, registration gives segments back and falls back to one
  // counter rather than fail; what does not fit even then is an error naming it.
  double memory_budget = 0;
  std::string frames;
  unsigned repeat = 1;
  // Read back only the earliest time of impact per object, not the contacts.
  bool earliest_only = false;
  // Record no OpenCL profiling events: device times unknown, and the wall time without
  // what the events cost the host.
  bool no_profile = false;
  // Upload each step's positions before it runs, rather than while the step (or the
  // run of a repeated step) before it runs (Detector::upload_ahead).
  bool no_upload_ahead = false;
};

// Registers the scene and the pipeline's options on a subcommand.
void add_measure_options(CLI::App& command, MeasureOptions& o);
// Checks them (InputError naming the flag), without reading the scene.
void check(const MeasureOptions& o);
DetectorOptions detector_options(const MeasureOptions& o);
// Whether each step's positions upload while the step before runs (or the run before,
// of a repeated step): unless --no-upload-ahead.
bool uploads_ahead(const MeasureOptions& o);

double median(std::vector<double> v);

// Makes `repeat` + 1 calls and returns the wall times of all but the first, which
// builds what the others reuse (a BVH's front): warm calls, as a solver makes them.
std::vector<double> warm_call_ms(unsigned repeat, const std::function<void()>& call);

// Each pass's device time in a detector's last step, for the commands' --passes.
void print_passes(const DetectorStats& stats);

// The tail of a run's per-step times, so that a hitch shows without a per-step table:
// the 90th percentile (nearest rank) and the slowest step with its first frame. NaN
// times (an untimed device) make every figure NaN.
struct Tail {
  double p90 = 0, max = 0;
  std::size_t max_frame = 0;
};
Tail tail(const std::vector<double>& per_step, std::size_t first_frame);

// The scene to measure: the given one, or the bundled default, generated into a
// temporary folder that is removed with this object, so that commands run anywhere.
struct SceneSource {
  Scene scene;
  std::string temporary;
  SceneSource() = default;
  SceneSource(const SceneSource&) = delete;
  SceneSource& operator=(const SceneSource&) = delete;
  ~SceneSource();
};
std::unique_ptr<SceneSource> scene_source(const MeasureOptions& o);

// One device's run over steps [first, last): per step JSON, per pass medians, contacts.
struct Measurement {
  std::string device, platform;
  bool escalates = false;  // single precision decides in double what float cannot prove (escalates())
  nlohmann::json steps = nlohmann::json::array();
  std::map<std::string, std::vector<double>> pass_ms;
  std::vector<std::string> pass_order;
  std::vector<double> host_ms, device_ms;
  std::vector<double> step_ms;  // wall time of each step's uploads and detect() together
  std::size_t peak_bytes = 0;  // the device's high-water mark over every step run, warm-ups included
  // Wall time to make the detector: the scene's layout and trees, its first front, the
  // programs (where the driver has not cached them) and the scene's uploads.
  double detector_ms = 0;
  std::vector<Contact> contacts;      // every step's, in step order, each step canonical (none if earliest_only)
  std::size_t contact_count = 0;      // over all steps, as the device counted them (DetectorStats::contacts)
  std::vector<std::size_t> step_ends;  // where each step's contacts end in `contacts`
  // The step with the earliest contact of the first step that has one (with
  // earliest_only, the time rounded down to float, as Detector::earliest_toi gives it).
  std::size_t first_contact_frame = 0;
  double first_contact_toi = 2;
};

// Runs each step `repeat` times (the first a warm-up when repeating), showing progress
// on a terminal.
Measurement measure(const MeasureOptions& o, const Scene& scene, std::size_t first, std::size_t last,
                    runtime::Context& context);

}  // namespace cstreams::cli
