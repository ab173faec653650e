#include "commands.hpp"
#include "measurement.hpp"

#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <unistd.h>

namespace cstreams::cli {

namespace {

struct RunOptions : MeasureOptions {
  std::string device;
  std::string out;
  std::string json;
  bool passes = false;
};

// What a first run should tell: the scene, the device, the result, the cost.
void print_summary(const Scene& scene, const RunOptions& o, std::size_t first, std::size_t last,
                   const Measurement& report)
{
  std::printf("scene     %s: %zu objects, %zu faces\n", scene.name.c_str(), scene.objects.size(), scene.face_count());
  std::printf("device    %s (%s)\n", report.device.c_str(), report.platform.c_str());
  std::printf("solver    %s, %s precision%s, tolerance %g; front %s\n", o.solver.c_str(), o.precision.c_str(),
              report.escalates ? " (what float cannot prove, in double)" : "", o.tolerance, o.front.c_str());
  std::printf("steps     %zu (frames %zu to %zu)\n", last - first, first, last);
  if (o.earliest_only)
    std::printf("contacts  %zu settled on the device (--earliest-only reads none back, and leaves pairs that cannot "
                "be an object's earliest unsettled)\n",
                report.contact_count);
  else
    std::printf("contacts  %zu\n", report.contacts.size());
  if (report.first_contact_toi <= 1)
    std::printf("earliest  t = %.6g in step %zu (frame %zu to %zu)\n", report.first_contact_toi,
                report.first_contact_frame - first + 1, report.first_contact_frame, report.first_contact_frame + 1);
  else
    std::printf("earliest  none: nothing collides\n");
  if (std::isnan(median(report.device_ms)))
    std::printf("time      %.3f ms per step (median wall time); the device does not time kernels\n",
                median(report.host_ms));
  else
    std::printf("time      %.3f ms per step (median wall time), %.3f ms of it on the device\n", median(report.host_ms),
                median(report.device_ms));
  if (last - first > 1) {
    // The slowest step by wall time, and what the device took of it; --json has the
    // device's own slowest step too.
    const Tail wall = tail(report.host_ms, first);
    std::printf("tail      %.3f ms at the 90th percentile; slowest step %zu (frame %zu to %zu), %.3f ms", wall.p90,
                wall.max_frame - first + 1, wall.max_frame, wall.max_frame + 1, wall.max);
    const double device_ms = report.device_ms[wall.max_frame - first];
    if (!std::isnan(device_ms)) std::printf(", %.3f ms of it on the device", device_ms);
    std::printf("\n");
  }
  std::printf("uploads   %.3f ms per step with its positions' uploads (%s)\n", median(report.step_ms),
              uploads_ahead(o) ? "made while the step before ran" : "made before it");
  std::printf("memory    %.1f MiB on the device at most (during a step)\n", double(report.peak_bytes) / (1 << 20));
  std::printf("setup     %.1f ms to make the detector (layout, trees, first front, programs, uploads)\n",
              report.detector_ms);
}

// Per step and per pass, for --passes.
void print_tables(Measurement& report)
{
  std::printf("\n%6s %10s %10s %10s %9s %9s %10s %9s %9s %9s %9s\n", "step", "tri pairs", "vf cand", "ee cand",
              "contacts", "escalated", "front", "held MiB", "peak MiB", "device ms", "step ms");
  for (const auto& s : report.steps)
    std::printf("%6zu %10zu %10zu %10zu %9zu %9zu %10zu %9.1f %9.1f %9.3f %9.3f\n", s["frame"].get<std::size_t>(),
                s["triangle_pairs"].get<std::size_t>(), s["vf_candidates"].get<std::size_t>(),
                s["ee_candidates"].get<std::size_t>(), s["contacts"].get<std::size_t>(),
                s["escalated"].get<std::size_t>(),
                s["front_pairs"].get<std::size_t>(), s["device_bytes"].get<double>() / (1 << 20),
                s["peak_bytes"].get<double>() / (1 << 20), s["device_ms"].get<double>(), s["host_ms"].get<double>());
  std::printf("\nmedian device time per pass (ms):\n");
  for (const auto& name : report.pass_order) std::printf("  %-44s %9.3f\n", name.c_str(), median(report.pass_ms[name]));
  std::printf("  %-44s %9.3f\n  %-44s %9.3f\n", "all passes", median(report.device_ms), "step (host wall time)",
              median(report.host_ms));
}

// A NaN (an untimed device's time) is null in JSON.
nlohmann::json tail_json(const std::vector<double>& per_step, std::size_t first)
{
  const Tail t = tail(per_step, first);
  const auto number = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
  return {{"median", number(median(per_step))}, {"p90", number(t.p90)}, {"max", number(t.max)}, {"max_frame", t.max_frame}};
}

void check(const RunOptions& o)
{
  check(static_cast<const MeasureOptions&>(o));
  if (!o.out.empty()) check_output_path("--out", o.out);
  if (o.earliest_only && !o.out.empty())
    throw InputError("--out writes the contacts, which --earliest-only does not read back; give one of them");
  if (!o.json.empty()) check_output_path("--json", o.json);
}

void run(const RunOptions& o)
{
  const auto source = scene_source(o);
  const Scene& scene = source->scene;
  const auto [first, last] = resolve(parse_step_range(o.frames), scene.frame_count());

  runtime::Context context(o.device.empty() ? filter_from_environment() : o.device);
  if (::isatty(STDERR_FILENO))
    std::fprintf(stderr, "scene %s: %zu objects, %zu faces; device %s; %s solver (%s), front %s\n", scene.name.c_str(),
                 scene.objects.size(), scene.face_count(), context.device().name.c_str(), o.solver.c_str(),
                 o.precision.c_str(), o.front.c_str());
  Measurement report = measure(o, scene, first, last, context);

  print_summary(scene, o, first, last, report);
  if (o.passes) print_tables(report);

  if (!o.json.empty()) {
    nlohmann::json j{{"scene", scene.name},
                     {"device", report.device},
                     {"platform", report.platform},
                     {"solver", o.solver},
                     {"precision", o.precision},
                     {"escalation", report.escalates},
                     {"tolerance", o.tolerance},
                     {"front", o.front},
                     {"front_budget_mb", o.front_budget},
                     {"front_climb_levels", o.front_climb},
                     {"memory_budget_mb", o.memory_budget > 0 ? nlohmann::json(o.memory_budget) : nlohmann::json()},
                     {"registration", o.registration},
                     {"repeat", o.repeat},
                     {"earliest_only", o.earliest_only},
                     {"earliest_toi", report.first_contact_toi <= 1 ? nlohmann::json(report.first_contact_toi)
                                                                    : nlohmann::json()},
                     {"faces", scene.face_count()},
                     {"median_host_ms", median(report.host_ms)},
                     {"median_device_ms", median(report.device_ms)},
                     {"median_step_ms", median(report.step_ms)},
                     {"tail", {{"host_ms", tail_json(report.host_ms, first)},
                               {"device_ms", tail_json(report.device_ms, first)},
                               {"step_ms", tail_json(report.step_ms, first)}}},
                     {"peak_bytes", report.peak_bytes},
                     {"detector_ms", report.detector_ms},
                     {"steps", report.steps}};
    write_file_atomically(o.json, [&](std::ostream& out) { out << j.dump(1) << "\n"; });
  }
  if (!o.out.empty()) write_contacts_csv(o.out, report.contacts);
}

}  // namespace

void add_run_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand(
      "run", "Run the device CCD pipeline over a scene's steps: time per pass, stream sizes, memory, contacts");
  add_measure_options(*cmd, *o);
  cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_option("--out", o->out, "Write the contacts of every step, in order, as CSV");
  cmd->add_option("--json", o->json, "Write per-step statistics as JSON");
  cmd->add_flag("--passes,-v", o->passes, "Also print a table per step and the median device time of every pass");
  cmd->add_flag("--earliest-only", o->earliest_only,
                "Read back only the earliest time of impact per object (Report::earliest_toi), not the contacts");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { run(*o); };
  });
}

}  // namespace cstreams::cli
