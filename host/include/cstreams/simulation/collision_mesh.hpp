#pragma once
// The surface a simulator collides, made once from its arrays (arrays.hpp), as
// ipc-toolkit's CollisionMesh: the rest positions V (#V x 3), the faces F (#F x 3) and
// optionally edges E (#E x 2) that belong to no face. Those edges collide as segments
// (rods, seams), and the vertices that belong to no face and no edge as points
// (particles): codimensional geometry, which the conservative solver handles (the
// cubic refuses it).
#include <cstreams/geometry/mesh.hpp>
#include <cstreams/geometry/topology.hpp>
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
  template <typename DerivedV, typename DerivedF, typename DerivedE>
  CollisionMesh(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F,
                const Eigen::MatrixBase<DerivedE>& E)
  {
    std::vector<Vec3> rest = positions_from(V, "V");
    std::vector<Face> faces = indices_from<3>(F, "F", rest.size());
    std::vector<Edge> segments = indices_from<2>(E, "E", rest.size());
    *this = CollisionMesh(std::move(rest), std::move(faces), std::move(segments));
  }
  // Throws InputError naming V (no vertices), F or E (an index out of range, a face or
  // edge that repeats a vertex).
  CollisionMesh(std::vector<Vec3> rest, std::vector<Face> faces, std::vector<Edge> segments = {});

  std::size_t vertex_count() const { return rest_.size(); }
  const std::vector<Vec3>& rest_positions() const { return rest_; }
  const std::vector<Face>& faces() const { return faces_; }
  const std::vector<Edge>& segments() const { return segments_; }  // E's rows
  const std::vector<std::uint32_t>& points() const { return points_; }  // vertices in no face or edge

private:
  std::vector<Vec3> rest_;
  std::vector<Face> faces_;
  std::vector<Edge> segments_;
  std::vector<std::uint32_t> points_;
};

struct ObjectDescription;
// The mesh as a detector's one deformable, self-colliding object.
ObjectDescription object_of(const CollisionMesh& mesh);

}  // namespace cstreams
