#pragma once
// Two plates as a simulator's arrays: a 1 x 1 plate at z = 0 and a tilted 0.5 x 0.5
// plate above it (lowest corner at height `low`), which a motion moves straight down.
// The first contact of such a motion is known exactly: the lowest corner reaches the
// plane of the big plate, inside it, when it has come down `low` (less the separation).
#include <cstreams/scenes/shapes.hpp>

#include <Eigen/Core>

namespace cstreams::test {

struct Plates {
  Eigen::MatrixXd V;  // #V x 3
  Eigen::MatrixXi F;  // #F x 3
  Eigen::Index lower_vertices = 0;  // the big plate's vertices come first

  // The positions with the upper plate moved down by `drop`.
  Eigen::MatrixXd dropped(double drop) const
  {
    Eigen::MatrixXd out = V;
    out.col(2).tail(V.rows() - lower_vertices).array() -= drop;
    return out;
  }
  // The upper plate's lowest height.
  double lowest_upper(const Eigen::MatrixXd& X) const { return X.col(2).tail(X.rows() - lower_vertices).minCoeff(); }
};

inline Plates plates(double low = 0.1, int resolution = 16)
{
  Mesh lower = scenes::sheet(resolution, resolution, 1, 1);
  Mesh upper = scenes::sheet(resolution / 2, resolution / 2, 0.5, 0.5);
  for (Vec3& p : upper.positions) p = Vec3(p.x() + 0.26, p.y() + 0.27, low + 0.04 * p.x() + 0.02 * p.y());
  Plates out;
  out.lower_vertices = Eigen::Index(lower.positions.size());
  scenes::append(lower, upper);
  out.V.resize(Eigen::Index(lower.positions.size()), 3);
  for (std::size_t v = 0; v < lower.positions.size(); ++v) out.V.row(Eigen::Index(v)) = lower.positions[v].transpose();
  out.F.resize(Eigen::Index(lower.faces.size()), 3);
  for (std::size_t f = 0; f < lower.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) out.F(Eigen::Index(f), k) = int(lower.faces[f][std::size_t(k)]);
  return out;
}

}  // namespace cstreams::test
