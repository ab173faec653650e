#include <cstreams/errors.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>

#include <string>
#include <utility>

namespace cstreams {

namespace {

void check_parameters(const CcdParameters& p)
{
  check_option("min_distance", p.min_distance, option_ranges::min_separation);
  check_option("tolerance", p.tolerance, option_ranges::tolerance);
  check_option("max_iterations", p.max_iterations, option_ranges::max_iterations);
  check_option("tmax", p.tmax, option_ranges::tmax);
}

}  // namespace

struct MeshCcd::State {
  runtime::Context& device;
  CollisionMesh mesh;
  MeshCcdOptions options;
  // Built for one set of solver settings, which its graph's kernels take: a change of
  // min_distance, tolerance or max_iterations builds another (a line search keeps them).
  std::unique_ptr<Detector> detector;
  SolverOptions built_for;
  std::vector<Vec3> copies[2];  // the Eigen calls' V0 and V1
  std::vector<Vec3> scaled_end;  // V0 + tmax (V1 - V0)

  Detector& detector_for(const CcdParameters& p)
  {
    SolverOptions solver;
    solver.solver = options.solver;
    solver.precision = options.precision;
    solver.tolerance = p.tolerance;
    solver.min_separation = p.min_distance;
    solver.max_iterations = p.max_iterations;
    if (detector && solver.tolerance == built_for.tolerance && solver.min_separation == built_for.min_separation &&
        solver.max_iterations == built_for.max_iterations)
      return *detector;
    check_solver_options(device, solver);
    SceneDescription scene;
    scene.add(object_of(mesh));
    DetectorOptions d;
    d.solver = solver;
    d.front = options.front;
    d.profile = options.profile;
    detector.reset();
    detector = std::make_unique<Detector>(device, std::move(scene), d);
    built_for = solver;
    return *detector;
  }

  // Runs the step V0 -> V0 + tmax (V1 - V0) for the earliest times alone: whether
  // anything collides, and when (in the motion's own time).
  std::pair<bool, double> earliest(PositionSpan V0, PositionSpan V1, const CcdParameters& p)
  {
    check_parameters(p);
    check_count("V0", V0);
    check_count("V1", V1);
    Detector& d = detector_for(p);
    try {
      if (p.tmax < 1) {
        scaled_end.resize(V0.size());
        for (std::size_t v = 0; v < V0.size(); ++v) scaled_end[v] = V0[v] + p.tmax * (V1[v] - V0[v]);
        d.set_step(0, V0, scaled_end);
      } else {
        d.set_step(0, V0, V1);
      }
    } catch (const InputError&) {
      // Arrays read in place were checked only by the detector, which names its object.
      name_bad_positions(V0, "V0");
      name_bad_positions(V1, "V1");
      throw;
    }
    d.detect(Report::earliest_toi);
    if (d.stats().contacts == 0) return {false, 1.0};
    return {true, d.earliest_toi()[0] * p.tmax};
  }

  void check_count(const char* name, PositionSpan x) const
  {
    if (x.size() != mesh.vertex_count())
      throw InputError(std::string(name) + ": has " + std::to_string(x.size()) + " rows; the mesh has " +
                       std::to_string(mesh.vertex_count()) + " vertices");
  }
};

MeshCcd::MeshCcd(runtime::Context& device, CollisionMesh mesh, MeshCcdOptions options)
    : state_(new State{device, std::move(mesh), options, nullptr, {}, {}, {}})
{
}

MeshCcd::~MeshCcd() = default;

double MeshCcd::toi(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, const CcdParameters& parameters)
{
  return toi(PositionSpan(V0), PositionSpan(V1), parameters);
}

double MeshCcd::toi(PositionSpan V0, PositionSpan V1, const CcdParameters& parameters)
{
  return state_->earliest(V0, V1, parameters).second;
}

bool MeshCcd::is_step_collision_free(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, double min_distance)
{
  return is_step_collision_free(PositionSpan(V0), PositionSpan(V1), min_distance);
}

bool MeshCcd::is_step_collision_free(PositionSpan V0, PositionSpan V1, double min_distance)
{
  CcdParameters p;
  p.min_distance = min_distance;
  return !state_->earliest(V0, V1, p).first;
}

double MeshCcd::collision_free_stepsize(const std::vector<Vec3>& V0, const std::vector<Vec3>& V1, double min_distance,
                                        double conservative_rescaling)
{
  return collision_free_stepsize(PositionSpan(V0), PositionSpan(V1), min_distance, conservative_rescaling);
}

double MeshCcd::collision_free_stepsize(PositionSpan V0, PositionSpan V1, double min_distance,
                                        double conservative_rescaling)
{
  check_option("conservative_rescaling", conservative_rescaling, option_ranges::conservative_rescaling);
  CcdParameters p;
  p.min_distance = min_distance;
  const auto [collides, t] = state_->earliest(V0, V1, p);
  return collides ? conservative_rescaling * t : 1.0;
}

std::vector<Vec3>& MeshCcd::copies(int end) { return state_->copies[end]; }

std::size_t MeshCcd::vertex_count() const { return state_->mesh.vertex_count(); }
const CollisionMesh& MeshCcd::mesh() const { return state_->mesh; }

const DetectorStats& MeshCcd::stats() const
{
  if (!state_->detector) throw Error("no call has run on this MeshCcd yet");
  return state_->detector->stats();
}

}  // namespace cstreams
