// `cstreams proximity FRAME --dhat D`: a barrier's active set at one configuration,
// through the array API (MeshProximity): the pairs closer than dhat by closest
// features, the smallest distance, and the time a warm call takes.
#include "commands.hpp"
#include "measurement.hpp"

#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <ostream>

namespace cstreams::cli {

namespace {

struct ProximityOptions {
  std::string mesh, device, json, out;
  std::string precision = "double";
  double dhat = 0;
  bool relative = false;
  unsigned repeat = 11;
  bool passes = false;
};

void check(const ProximityOptions& o)
{
  parse_precision(o.precision);
  check_option("--dhat", o.dhat, option_ranges::dhat);
  check_option("--repeat", o.repeat, {1, 1000000});
  if (!o.json.empty()) check_output_path("--json", o.json);
  if (!o.out.empty()) check_output_path("--out", o.out);
}

const char* name(ClosestFeatures c)
{
  switch (c) {
    case ClosestFeatures::point_triangle: return "point-triangle";
    case ClosestFeatures::edge_edge: return "edge-edge";
    case ClosestFeatures::point_edge: return "point-edge";
    case ClosestFeatures::point_point: return "point-point";
  }
  return "?";
}

double diagonal(const std::vector<Vec3>& x)
{
  Vec3 lo = x.front(), hi = x.front();
  for (const Vec3& p : x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// CSV: kind (vf or ee), the two features (vertex and face, or two edges), their
// vertices, the closest features and the distance (9 significant digits: a float).
void write_csv(std::ostream& out, const std::vector<ClosePair>& pairs)
{
  out << "kind,a,b,v0,v1,v2,v3,closest,distance\n";
  char line[160];
  for (const ClosePair& p : pairs) {
    std::snprintf(line, sizeof line, "%s,%u,%u,%u,%u,%u,%u,%s,%.9g\n", p.kind == ContactKind::vertex_face ? "vf" : "ee",
                  p.a, p.b, p.v[0], p.v[1], p.v[2], p.v[3], name(p.closest()), double(p.distance));
    out << line;
  }
}

void proximity(const ProximityOptions& o)
{
  const Mesh m = read_mesh(o.mesh);
  const double dhat = o.relative ? o.dhat * diagonal(m.positions) : o.dhat;
  runtime::Context context(o.device.empty() ? filter_from_environment() : o.device);
  MeshProximityOptions options;
  options.precision = parse_precision(o.precision);
  options.profile = o.passes;
  MeshProximity proximity(context, CollisionMesh(m.positions, m.faces), options);
  const std::vector<ClosePair>* found = nullptr;
  const std::vector<double> ms = warm_call_ms(o.repeat, [&] { found = &proximity.close_pairs(m.positions, dhat); });
  const std::vector<ClosePair>& pairs = *found;
  std::map<std::string, std::size_t> by_closest;
  float smallest = std::numeric_limits<float>::infinity();
  for (const ClosePair& p : pairs) {
    ++by_closest[name(p.closest())];
    smallest = std::min(smallest, p.distance);
  }
  std::printf("mesh      %s: %zu vertices, %zu faces\n", o.mesh.c_str(), m.positions.size(), m.faces.size());
  std::printf("device    %s (%s)\n", context.device().name.c_str(), context.device().platform_name.c_str());
  std::printf("dhat      %g%s, distances in %s precision\n", dhat, o.relative ? " (of the bounding box's diagonal)" : "",
              o.precision.c_str());
  std::printf("pairs     %zu closer than dhat", pairs.size());
  for (const auto& [closest, count] : by_closest) std::printf(", %zu %s", count, closest.c_str());
  std::printf("\n");
  if (!pairs.empty()) std::printf("smallest  %.9g\n", double(smallest));
  std::printf("time      %.3f ms per call (median wall time of %u warm calls)\n", median(ms), o.repeat);
  if (o.passes) print_passes(proximity.stats());
  if (!o.out.empty()) write_file_atomically(o.out, [&](std::ostream& out) { write_csv(out, pairs); });
  if (!o.json.empty()) {
    const nlohmann::json j{{"mesh", o.mesh},
                           {"vertices", m.positions.size()},
                           {"faces", m.faces.size()},
                           {"device", context.device().name},
                           {"precision", o.precision},
                           {"dhat", dhat},
                           {"pairs", pairs.size()},
                           {"by_closest_features", by_closest},
                           {"smallest_distance", pairs.empty() ? nlohmann::json() : nlohmann::json(smallest)},
                           {"median_call_ms", median(ms)},
                           {"call_ms", ms}};
    write_file_atomically(o.json, [&](std::ostream& out) { out << j.dump(1) << "\n"; });
  }
}

}  // namespace

void add_proximity_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<ProximityOptions>();
  auto* cmd = app.add_subcommand("proximity",
                                 "The pairs of a mesh closer than dhat (a barrier's active set) through the array API: "
                                 "counts by closest features, the smallest distance, the time a call takes");
  cmd->add_option("mesh", o->mesh, "The mesh at one configuration")->required();
  cmd->add_option("--dhat", o->dhat, "Distance below which a pair is reported")->required();
  cmd->add_flag("--relative", o->relative, "--dhat is a fraction of the mesh's bounding-box diagonal");
  cmd->add_option("--precision", o->precision, "double (single on a device without it) or single");
  cmd->add_option("--repeat", o->repeat, "Warm calls to time, after a first one");
  cmd->add_option("--device", o->device, "Device filter (default: CSTREAMS_DEVICE)");
  cmd->add_flag("--passes,-v", o->passes, "Also print each pass's device time in the last call (times every call's passes)");
  cmd->add_option("--out", o->out, "Write the pairs as CSV");
  cmd->add_option("--json", o->json, "Write the counts and the calls' times as JSON");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { proximity(*o); };
  });
}

}  // namespace cstreams::cli
