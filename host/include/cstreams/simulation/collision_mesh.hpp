#pragma once
// The surface a simulator collides, made once from its arrays (arrays.hpp): the rest
// positions V (#V x 3) and the faces F (#F x 3). Every vertex must belong to a face:
// vertices and edges that belong to no face (codimensional points and rods) do not
// collide yet, and a mesh with them is refused rather than missing their contacts.
#include <cstreams/geometry/mesh.hpp>
#include <cstreams/simulation/arrays.hpp>

#include <cstddef>
#include <utility>
#include <vector>

namespace cstreams {

class CollisionMesh {
public:
  template <typename DerivedV, typename DerivedF>
  CollisionMesh(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F)
  {
    std::vector<Vec3> rest = positions_from(V, "V");
    std::vector<Face> faces = indices_from<3>(F, "F", rest.size());
    *this = CollisionMesh(std::move(rest), std::move(faces));
  }
  // Throws InputError naming F (no faces, a face that repeats a vertex) or V (a vertex
  // in no face).
  CollisionMesh(std::vector<Vec3> rest, std::vector<Face> faces);

  std::size_t vertex_count() const { return rest_.size(); }
  const std::vector<Vec3>& rest_positions() const { return rest_; }
  const std::vector<Face>& faces() const { return faces_; }

private:
  std::vector<Vec3> rest_;
  std::vector<Face> faces_;
};

}  // namespace cstreams
