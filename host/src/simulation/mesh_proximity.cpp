#include <cstreams/errors.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <string>

namespace cstreams {

struct MeshProximity::State {
  runtime::Context& device;
  CollisionMesh mesh;
  MeshProximityOptions options;
  // Built for one distance, which its graph's boxes and kernel take: an active set's
  // dhat stays the same from one iteration to the next.
  std::unique_ptr<Detector> detector;
  double built_for = 0;
  std::vector<Vec3> copy;

  Detector& run(PositionSpan V, double dhat, const char* name)
  {
    check_option(name, dhat, option_ranges::dhat);
    if (V.size() != mesh.vertex_count())
      throw InputError("V: has " + std::to_string(V.size()) + " rows; the mesh has " +
                       std::to_string(mesh.vertex_count()) + " vertices");
    if (!detector || built_for != dhat) {
      SceneDescription scene;
      scene.add(object_of(mesh));
      DetectorOptions d;
      d.detects = Detects::close_pairs;
      d.dhat = dhat;
      // A device without double precision computes the distances in float.
      d.solver.precision = device.device().fp64 ? options.precision : Precision::single;
      d.front = options.front;
      d.profile = options.profile;
      detector.reset();
      detector = std::make_unique<Detector>(device, std::move(scene), d);
      built_for = dhat;
    }
    try {
      detector->set_positions(0, V);
    } catch (const InputError&) {
      // Arrays read in place were checked only by the detector, which names its object.
      name_bad_positions(V, "V");
      throw;
    }
    detector->detect();
    return *detector;
  }
};

MeshProximity::MeshProximity(runtime::Context& device, CollisionMesh mesh, MeshProximityOptions options)
    : state_(new State{device, std::move(mesh), options, nullptr, 0, {}})
{
}

MeshProximity::~MeshProximity() = default;

const std::vector<ClosePair>& MeshProximity::close_pairs(const std::vector<Vec3>& V, double dhat)
{
  return close_pairs(PositionSpan(V), dhat);
}

const std::vector<ClosePair>& MeshProximity::close_pairs(PositionSpan V, double dhat)
{
  return state_->run(V, dhat, "dhat").close_pairs();
}

CandidateBlock MeshProximity::candidates(const std::vector<Vec3>& V, double radius)
{
  return candidates(PositionSpan(V), radius);
}

CandidateBlock MeshProximity::candidates(PositionSpan V, double radius)
{
  Candidates all = state_->run(V, radius, "radius").candidates();
  return all.blocks.empty() ? CandidateBlock{} : std::move(all.blocks.front());
}

std::vector<Vec3>& MeshProximity::copy() { return state_->copy; }

std::size_t MeshProximity::vertex_count() const { return state_->mesh.vertex_count(); }
const CollisionMesh& MeshProximity::mesh() const { return state_->mesh; }

const DetectorStats& MeshProximity::stats() const
{
  if (!state_->detector) throw Error("no call has run on this MeshProximity yet");
  return state_->detector->stats();
}

}  // namespace cstreams
