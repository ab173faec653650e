#include <cstreams/detector.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/simulation/collision_mesh.hpp>

#include <string>

namespace cstreams {

namespace {

void check_index(const char* name, std::size_t row, std::uint32_t v, std::size_t vertices)
{
  if (v >= vertices)
    throw InputError(std::string(name) + ": row " + std::to_string(row) + " holds vertex " + std::to_string(v) +
                     "; V has " + std::to_string(vertices) + " rows");
}

}  // namespace

CollisionMesh::CollisionMesh(std::vector<Vec3> rest, std::vector<Face> faces, std::vector<Edge> segments)
    : rest_(std::move(rest)), faces_(std::move(faces)), segments_(std::move(segments))
{
  if (rest_.empty()) throw InputError("V: has no vertices");
  std::vector<bool> used(rest_.size(), false);
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const Face& face = faces_[f];
    for (const std::uint32_t v : face) {
      check_index("F", f, v, rest_.size());
      used[v] = true;
    }
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2])
      throw InputError("F: row " + std::to_string(f) + " repeats a vertex");
  }
  for (std::size_t e = 0; e < segments_.size(); ++e) {
    for (const std::uint32_t v : segments_[e]) {
      check_index("E", e, v, rest_.size());
      used[v] = true;
    }
    if (segments_[e][0] == segments_[e][1]) throw InputError("E: row " + std::to_string(e) + " repeats a vertex");
  }
  for (std::uint32_t v = 0; v < used.size(); ++v)
    if (!used[v]) points_.push_back(v);
}

ObjectDescription object_of(const CollisionMesh& mesh)
{
  ObjectDescription o("mesh", mesh.faces(), mesh.rest_positions());
  o.segments = mesh.segments();
  o.points = mesh.points();
  return o;
}

}  // namespace cstreams
