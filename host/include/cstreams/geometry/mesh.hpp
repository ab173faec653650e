#pragma once
#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cstreams {

using Vec3 = Eigen::Vector3d;
using Face = std::array<std::uint32_t, 3>;

static_assert(sizeof(Vec3) == 3 * sizeof(double), "positions are read as one array of coordinates");

// Positions read in place, not copied: a std::vector<Vec3>'s, or `size` rows of three
// doubles one after the other (an (n, 3) array of doubles in row-major order).
class PositionSpan {
public:
  PositionSpan(const std::vector<Vec3>& x) : xyz_(x.empty() ? nullptr : x.front().data()), size_(x.size()) {}
  PositionSpan(const double* xyz, std::size_t size) : xyz_(xyz), size_(size) {}
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  Eigen::Map<const Vec3> operator[](std::size_t i) const { return Eigen::Map<const Vec3>(xyz_ + 3 * i); }
  // The coordinates, three a position (null where there are none).
  const double* coordinates() const noexcept { return xyz_; }

private:
  const double* xyz_;
  std::size_t size_;
};

// One frame of a triangle mesh. Positions are double: every input format we read
// (float or double) converts exactly, so nothing is rounded before the solvers.
struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Face> faces;
};

}  // namespace cstreams
