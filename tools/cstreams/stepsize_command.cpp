// `cstreams stepsize A B`: what a simulator's line search asks of one step, through the
// array API (MeshCcd): the collision-free step size, the earliest time of impact, and
// the time a warm call takes.
#include "commands.hpp"
#include "measurement.hpp"

#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <memory>

namespace cstreams::cli {

namespace {

struct StepsizeOptions {
  std::string start, end, device, json;
  std::string solver = "conservative", precision = "single";
  double min_separation = 0, tolerance = CcdParameters{}.tolerance;
  double rescaling = default_conservative_rescaling;
  unsigned repeat = 11;
  bool passes = false;
};

void check(const StepsizeOptions& o)
{
  parse_solver(o.solver);
  parse_precision(o.precision);
  check_option("--min-separation", o.min_separation, option_ranges::min_separation);
  check_option("--tolerance", o.tolerance, option_ranges::tolerance);
  check_option("--rescaling", o.rescaling, option_ranges::conservative_rescaling);
  check_option("--repeat", o.repeat, {1, 1000000});
  if (!o.json.empty()) check_output_path("--json", o.json);
}

// The two frames of one mesh: the same faces, as many vertices.
std::pair<Mesh, Mesh> read_step(const std::string& start, const std::string& end)
{
  Mesh a = read_mesh(start), b = read_mesh(end);
  if (b.positions.size() != a.positions.size())
    throw InputError(end + ": has " + std::to_string(b.positions.size()) + " vertices but " + start + " has " +
                     std::to_string(a.positions.size()));
  if (b.faces != a.faces) throw InputError(end + ": its faces differ from those of " + start);
  return {std::move(a), std::move(b)};
}

void stepsize(const StepsizeOptions& o)
{
  // Named, not bound: a lambda below captures them, which C++17 does not allow of bindings.
  const std::pair<Mesh, Mesh> step = read_step(o.start, o.end);
  const Mesh &a = step.first, &b = step.second;
  runtime::Context context(o.device.empty() ? filter_from_environment() : o.device);
  MeshCcdOptions options;
  options.solver = parse_solver(o.solver);
  options.precision = parse_precision(o.precision);
  options.profile = o.passes;
  MeshCcd ccd(context, CollisionMesh(a.positions, a.faces), options);
  CcdParameters parameters;
  parameters.min_distance = o.min_separation;
  parameters.tolerance = o.tolerance;
  double alpha = 0;
  const std::vector<double> ms = warm_call_ms(o.repeat, [&] {
    alpha = ccd.collision_free_stepsize(a.positions, b.positions, o.min_separation, o.rescaling);
  });
  const double toi = ccd.toi(a.positions, b.positions, parameters);
  const bool free = alpha == 1.0;

  std::printf("mesh      %s: %zu vertices, %zu faces\n", o.start.c_str(), a.positions.size(), a.faces.size());
  std::printf("device    %s (%s)\n", context.device().name.c_str(), context.device().platform_name.c_str());
  std::printf("solver    %s, %s precision, tolerance %g, minimum separation %g\n", o.solver.c_str(),
              o.precision.c_str(), o.tolerance, o.min_separation);
  if (free)
    std::printf("step size 1: the whole step is free of collisions\n");
  else
    std::printf("step size %.9g: the step collides first at t = %.9g, rescaled by %g\n", alpha, toi, o.rescaling);
  std::printf("time      %.3f ms per call (median wall time of %u warm calls)\n", median(ms), o.repeat);
  if (o.passes) print_passes(ccd.stats());
  if (!o.json.empty()) {
    const nlohmann::json j{{"mesh", o.start},
                           {"vertices", a.positions.size()},
                           {"faces", a.faces.size()},
                           {"device", context.device().name},
                           {"solver", o.solver},
                           {"precision", o.precision},
                           {"tolerance", o.tolerance},
                           {"min_separation", o.min_separation},
                           {"rescaling", o.rescaling},
                           {"stepsize", alpha},
                           {"collision_free", free},
                           {"toi", free ? nlohmann::json() : nlohmann::json(toi)},
                           {"median_call_ms", median(ms)},
                           {"call_ms", ms}};
    write_file_atomically(o.json, [&](std::ostream& out) { out << j.dump(1) << "\n"; });
  }
}

}  // namespace

void add_stepsize_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<StepsizeOptions>();
  auto* cmd = app.add_subcommand(
      "stepsize", "The collision-free step size of a step A -> B (ipc-toolkit's compute_collision_free_stepsize) "
                  "through the array API, with its earliest time of impact and the time a call takes");
  cmd->add_option("start", o->start, "The mesh at the start of the step")->required();
  cmd->add_option("end", o->end, "The same mesh at the end of the step")->required();
  cmd->add_option("--min-separation", o->min_separation, "Distance the step keeps every pair apart (max norm)");
  cmd->add_option("--tolerance", o->tolerance, "Solver tolerance, relative to the pair's coordinates");
  cmd->add_option("--rescaling", o->rescaling, "Fraction of the earliest time of impact a colliding step takes");
  cmd->add_option("--solver", o->solver, "conservative or cubic");
  cmd->add_option("--precision", o->precision, "single or double");
  cmd->add_option("--repeat", o->repeat, "Warm calls to time, after a first one");
  cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_flag("--passes,-v", o->passes, "Also print each pass's device time in the last call (times every call's passes)");
  cmd->add_option("--json", o->json, "Write the result and the calls' times as JSON");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { stepsize(*o); };
  });
}

}  // namespace cstreams::cli
