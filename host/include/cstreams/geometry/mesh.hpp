#pragma once
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cstreams {

using Vec3 = Eigen::Vector3d;
using Face = std::array<std::uint32_t, 3>;

// One frame of a triangle mesh. Positions are double: every input format we read
// (float or double) converts exactly, so nothing is rounded before the solvers.
struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Face> faces;
};

}  // namespace cstreams
