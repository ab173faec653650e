#include "commands.hpp"

#include <cstreams/detector.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/scenes/generators.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <unistd.h>

namespace cstreams::cli {

namespace {

struct RunOptions {
  std::vector<std::string> paths;
  bool split = false;
  std::string device;
  std::string solver = "conservative";
  std::string precision = "single";
  std::string front = "exact";
  std::string registration = "segmented-lock";
  double tolerance = SolverOptions{}.tolerance;
  double min_separation = 0;
  std::uint32_t max_iterations = SolverOptions{}.max_iterations;
  double front_budget = DetectorOptions{}.front_budget_mb;
  std::string frames;
  unsigned repeat = 1;
  std::string out;
  std::string json;
  bool passes = false;
};

double median(std::vector<double> v)
{
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// The scene to run: the given one, or the bundled default, generated into a
// temporary folder (removed afterwards) so that the command runs anywhere.
struct SceneSource {
  Scene scene;
  std::string temporary;
  ~SceneSource()
  {
    std::error_code ignored;
    if (!temporary.empty()) std::filesystem::remove_all(temporary, ignored);
  }
};

std::unique_ptr<SceneSource> scene_source(const RunOptions& o)
{
  auto source = std::make_unique<SceneSource>();
  if (!o.paths.empty()) {
    source->scene = open_scene(o.paths, o.split);
    return source;
  }
  source->temporary =
      (std::filesystem::temp_directory_path() / ("cstreams-default-scene-" + std::to_string(::getpid()))).string();
  // A 30x30 cloth dropped on a static sphere: self-contacts and contacts with the
  // sphere within a few seconds on any device.
  source->scene = load_scene(scenes::generate_scene({"cloth-sphere", source->temporary, 1, 24, 30}));
  return source;
}

// One line per step, and per-pass medians over the steps.
struct Report {
  nlohmann::json steps = nlohmann::json::array();
  std::map<std::string, std::vector<double>> pass_ms;
  std::vector<std::string> pass_order;
  std::vector<double> host_ms, device_ms;
  std::size_t contacts = 0, peak_bytes = 0;
  // The step with the earliest contact of the first step that has one.
  std::size_t first_contact_frame = 0;
  double first_contact_toi = 2;
};

nlohmann::json step_json(std::size_t frame, const DetectorStats& s, double host_ms)
{
  nlohmann::json passes = nlohmann::json::object(), streams = nlohmann::json::object();
  for (const auto& p : s.run.passes) {
    auto& pass = passes[p.name] = {
        {"ms", p.device_ns * 1e-6}, {"launches", p.launches}, {"reruns", p.reruns}, {"scratch_bytes", p.scratch_bytes}};
    if (p.rounds) pass.update({{"rounds", p.rounds}, {"list_items", p.list_items}, {"widest_list", p.widest_list}});
  }
  for (const auto& st : s.run.streams)
    streams[st.name] = {{"count", st.count}, {"capacity", st.capacity}, {"bytes", st.bytes}};
  return {{"frame", frame},
          {"host_ms", host_ms},
          {"device_ms", s.device_ns() * 1e-6},
          {"readbacks", s.run.readbacks},
          {"triangle_pairs", s.triangle_pairs},
          {"vf_candidates", s.vf_candidates},
          {"ee_candidates", s.ee_candidates},
          {"contacts", s.contacts},
          {"front_pairs", s.front_pairs},
          {"front_level_cap", s.front_level_cap},
          {"front_retries", s.front_retries},
          {"device_bytes", s.device_bytes()},
          {"scratch_bytes", s.run.scratch_bytes},
          {"passes", passes},
          {"streams", streams}};
}

// What a first run should tell: the scene, the device, the result, the cost.
void print_summary(const Scene& scene, const runtime::Context& context, const RunOptions& o, std::size_t first,
                   std::size_t last, const Report& report)
{
  std::printf("scene     %s: %zu objects, %zu faces\n", scene.name.c_str(), scene.objects.size(), scene.face_count());
  std::printf("device    %s (%s)\n", context.device().name.c_str(), context.device().platform_name.c_str());
  std::printf("solver    %s, %s precision, tolerance %g; front %s\n", o.solver.c_str(), o.precision.c_str(), o.tolerance,
              o.front.c_str());
  std::printf("steps     %zu (frames %zu to %zu)\n", last - first, first, last);
  std::printf("contacts  %zu\n", report.contacts);
  if (report.first_contact_toi <= 1)
    std::printf("earliest  t = %.6g in step %zu (frame %zu to %zu)\n", report.first_contact_toi,
                report.first_contact_frame - first + 1, report.first_contact_frame, report.first_contact_frame + 1);
  else
    std::printf("earliest  none: nothing collides\n");
  std::printf("time      %.3f ms per step (median wall time), %.3f ms of it on the device\n", median(report.host_ms),
              median(report.device_ms));
  std::printf("memory    %.1f MiB on the device at most\n", double(report.peak_bytes) / (1 << 20));
}

// Per step and per pass, for --passes.
void print_tables(Report& report)
{
  std::printf("\n%6s %10s %10s %10s %9s %10s %9s %9s %9s\n", "step", "tri pairs", "vf cand", "ee cand", "contacts",
              "front", "MiB", "device ms", "step ms");
  for (const auto& s : report.steps)
    std::printf("%6zu %10zu %10zu %10zu %9zu %10zu %9.1f %9.3f %9.3f\n", s["frame"].get<std::size_t>(),
                s["triangle_pairs"].get<std::size_t>(), s["vf_candidates"].get<std::size_t>(),
                s["ee_candidates"].get<std::size_t>(), s["contacts"].get<std::size_t>(),
                s["front_pairs"].get<std::size_t>(), s["device_bytes"].get<double>() / (1 << 20),
                s["device_ms"].get<double>(), s["host_ms"].get<double>());
  std::printf("\nmedian device time per pass (ms):\n");
  for (const auto& name : report.pass_order) std::printf("  %-44s %9.3f\n", name.c_str(), median(report.pass_ms[name]));
  std::printf("  %-44s %9.3f\n  %-44s %9.3f\n", "all passes", median(report.device_ms), "step (host wall time)",
              median(report.host_ms));
}

DetectorOptions detector_options(const RunOptions& o)
{
  DetectorOptions options;
  options.solver.solver = parse_solver(o.solver);
  options.solver.precision = parse_precision(o.precision);
  options.solver.tolerance = o.tolerance;
  options.solver.min_separation = o.min_separation;
  options.solver.max_iterations = o.max_iterations;
  options.front = parse_front_mode(o.front);
  options.front_budget_mb = o.front_budget;
  options.registration = runtime::parse_registration(o.registration);
  return options;
}

void check(const RunOptions& o)
{
  check_option("--tolerance", o.tolerance, option_ranges::tolerance);
  check_option("--min-separation", o.min_separation, option_ranges::min_separation);
  check_option("--max-iterations", o.max_iterations, option_ranges::max_iterations);
  check_option("--front-budget", o.front_budget, option_ranges::front_budget_mb);
  check_option("--repeat", o.repeat, {1, 1000000});
  detector_options(o);
  parse_step_range(o.frames);
  if (!o.out.empty()) check_output_path("--out", o.out);
  if (!o.json.empty()) check_output_path("--json", o.json);
}

void run(const RunOptions& o)
{
  const auto source = scene_source(o);
  const Scene& scene = source->scene;
  const auto [first, last] = resolve(parse_step_range(o.frames), scene.frame_count());
  const DetectorOptions options = detector_options(o);

  runtime::Context context(o.device.empty() ? filter_from_environment() : o.device);
  Detector detector(context, describe(scene, first), options);
  const bool terminal = ::isatty(STDERR_FILENO);
  if (terminal)
    std::fprintf(stderr, "scene %s: %zu objects, %zu faces; device %s; %s solver (%s), front %s\n", scene.name.c_str(),
               scene.objects.size(), scene.face_count(), context.device().name.c_str(), o.solver.c_str(),
               o.precision.c_str(), o.front.c_str());

  Report report;
  std::vector<Contact> all;
  for (std::size_t frame = first; frame < last; ++frame) {
    const Step step = load_step(scene, frame);
    std::vector<double> host, device;
    DetectorStats stats;
    for (unsigned r = 0; r < o.repeat; ++r) {
      for (std::uint32_t obj = 0; obj < scene.objects.size(); ++obj) {
        if (scene.objects[obj].kind == ObjectKind::static_) continue;
        // Steps that follow each other need only the new end; a repeated step both.
        if (r == 0) detector.set_positions(obj, step.x1[obj]);
        else detector.set_step(obj, step.x0[obj], step.x1[obj]);
      }
      detector.detect();
      stats = detector.stats();
      // With repeats, the first run of a step is a warm-up.
      if (o.repeat == 1 || r > 0) {
        host.push_back(stats.host_ms);
        device.push_back(stats.device_ns() * 1e-6);
        for (const auto& p : stats.run.passes) report.pass_ms[p.name].push_back(p.device_ns * 1e-6);
      }
    }
    if (report.pass_order.empty())
      for (const auto& p : stats.run.passes) report.pass_order.push_back(p.name);
    const double host_ms = median(host), device_ms = median(device);
    report.host_ms.push_back(host_ms);
    report.device_ms.push_back(device_ms);
    report.steps.push_back(step_json(frame, stats, host_ms));
    report.steps.back()["device_ms"] = device_ms;
    const auto& contacts = detector.contacts();
    all.insert(all.end(), contacts.begin(), contacts.end());
    report.contacts += contacts.size();
    report.peak_bytes = std::max(report.peak_bytes, stats.device_bytes());
    if (report.first_contact_toi > 1)
      for (const Contact& c : contacts)
        if (c.toi < report.first_contact_toi) {
          report.first_contact_toi = c.toi;
          report.first_contact_frame = frame;
        }
    if (terminal)
      std::fprintf(stderr, "\rstep %zu/%zu: %zu contacts, %.3f ms   ", frame - first + 1, last - first,
                   contacts.size(), host_ms);
  }
  if (terminal) std::fprintf(stderr, "\n");

  print_summary(scene, context, o, first, last, report);
  if (o.passes) print_tables(report);

  if (!o.json.empty()) {
    nlohmann::json j{{"scene", scene.name},
                     {"device", context.device().name},
                     {"platform", context.device().platform_name},
                     {"solver", o.solver},
                     {"precision", o.precision},
                     {"tolerance", o.tolerance},
                     {"front", o.front},
                     {"front_budget_mb", o.front_budget},
                     {"registration", o.registration},
                     {"repeat", o.repeat},
                     {"faces", scene.face_count()},
                     {"median_host_ms", median(report.host_ms)},
                     {"median_device_ms", median(report.device_ms)},
                     {"steps", report.steps}};
    write_file_atomically(o.json, [&](std::ostream& out) { out << j.dump(1) << "\n"; });
  }
  if (!o.out.empty()) write_contacts_csv(o.out, all);
}

}  // namespace

void add_run_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand(
      "run", "Run the device CCD pipeline over a scene's steps: time per pass, stream sizes, memory, contacts");
  cmd->add_option("scene", o->paths,
                  "A scene manifest (.json), a mesh file, or the frame files of one mesh; default: a bundled "
                  "cloth-on-sphere scene");
  cmd->add_flag("--split", o->split, "Treat each connected component of the mesh as an object");
  cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_option("--solver", o->solver, "conservative (never misses) or cubic (the paper's)");
  cmd->add_option("--precision", o->precision, "single or double");
  cmd->add_option("--tolerance", o->tolerance, "Solver tolerance, relative to the query's coordinates");
  cmd->add_option("--min-separation", o->min_separation, "Distance below which primitives count as colliding");
  cmd->add_option("--max-iterations", o->max_iterations,
                  "Conservative solver's work limit per pair; reaching it reports a collision");
  cmd->add_option("--front", o->front, "BVTT front: none, exact or deferred");
  cmd->add_option("--front-budget", o->front_budget, "Deferred front: device memory for the front, MiB");
  cmd->add_option("--registration", o->registration, "segmented-lock, lock-free or global-atomic");
  cmd->add_option("--frames", o->frames, "Steps A:B (from frame A to B), or one step A; default: all");
  cmd->add_option("--repeat", o->repeat, "Run each step this many times and report medians (the first is a warm-up)");
  cmd->add_option("--out", o->out, "Write the contacts of every step, in order, as CSV");
  cmd->add_option("--json", o->json, "Write per-step statistics as JSON");
  cmd->add_flag("--passes,-v", o->passes, "Also print a table per step and the median device time of every pass");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { run(*o); };
  });
}

}  // namespace cstreams::cli
