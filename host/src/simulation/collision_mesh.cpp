#include <cstreams/errors.hpp>
#include <cstreams/simulation/collision_mesh.hpp>

#include <string>

namespace cstreams {

CollisionMesh::CollisionMesh(std::vector<Vec3> rest, std::vector<Face> faces) : rest_(std::move(rest)), faces_(std::move(faces))
{
  if (faces_.empty()) throw InputError("F: has no faces");
  std::vector<bool> used(rest_.size(), false);
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const Face& face = faces_[f];
    for (const std::uint32_t v : face) {
      if (v >= rest_.size())
        throw InputError("F: row " + std::to_string(f) + " holds vertex " + std::to_string(v) + "; V has " +
                         std::to_string(rest_.size()) + " rows");
      used[v] = true;
    }
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2])
      throw InputError("F: row " + std::to_string(f) + " repeats a vertex");
  }
  for (std::size_t v = 0; v < used.size(); ++v)
    if (!used[v])
      throw InputError("V: vertex " + std::to_string(v) +
                       " belongs to no face of F; points and edges outside faces (codimensional geometry) do not "
                       "collide yet: pass the surface's vertices alone");
}

}  // namespace cstreams
