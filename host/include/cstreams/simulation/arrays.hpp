#pragma once
// Arrays as simulators hold them (ipc-toolkit's conventions): positions an Eigen matrix
// of #V rows and 3 columns, double or float; faces #F x 3 and edges #E x 2 of integer
// indices. Either storage order. Each is checked as it is copied (or, positions laid out
// as the detector reads them, where they are read), and an InputError names the
// argument, the row and what was wrong.
#include <cstreams/geometry/mesh.hpp>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstddef>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace cstreams {

namespace details {
[[noreturn]] void throw_bad_shape(const char* name, std::ptrdiff_t rows, std::ptrdiff_t cols, std::size_t want_rows,
                                  std::size_t want_cols);
[[noreturn]] void throw_not_finite(const char* name, std::ptrdiff_t row);
[[noreturn]] void throw_bad_index(const char* name, std::ptrdiff_t row, long long index, std::size_t vertices);
}  // namespace details

// Copies positions V (#V x 3; `rows` of them where rows > 0) in double into `out`,
// whose memory is reused: a call's fresh vectors cost more than the copy itself (the
// page faults of 1.1 MB for cloth-ball's 46,598 vertices). Every coordinate must be
// finite and within float's range, which the device computes in.
template <typename Derived>
void positions_into(const Eigen::MatrixBase<Derived>& V, const char* name, std::size_t rows, std::vector<Vec3>& out)
{
  static_assert(std::is_floating_point_v<typename Derived::Scalar>, "positions are float or double");
  if (V.cols() != 3 || (rows > 0 && std::size_t(V.rows()) != rows)) details::throw_bad_shape(name, V.rows(), V.cols(), rows, 3);
  out.resize(std::size_t(V.rows()));
  constexpr double largest = std::numeric_limits<float>::max();
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const Vec3 x(double(V(i, 0)), double(V(i, 1)), double(V(i, 2)));
    if (!(std::abs(x[0]) <= largest && std::abs(x[1]) <= largest && std::abs(x[2]) <= largest))
      details::throw_not_finite(name, i);
    out[std::size_t(i)] = x;
  }
}

// Positions V for a call: read in place where they lie as the detector reads them, three
// doubles a row one row after the other (a row-major matrix, or a numpy float64 array in
// C order), else copied into `copy` as positions_into() does. In place, only the shape
// is checked here; the detector checks the values as it reads them, and where it finds
// a bad one, name_bad_positions() names the argument and the row.
template <typename Derived>
PositionSpan positions_view(const Eigen::MatrixBase<Derived>& V, const char* name, std::size_t rows,
                            std::vector<Vec3>& copy)
{
  constexpr bool direct = bool(int(Derived::Flags) & Eigen::DirectAccessBit);
  if constexpr (std::is_same_v<typename Derived::Scalar, double> && direct) {
    if (V.cols() == 3 && std::size_t(V.rows()) == rows && V.derived().colStride() == 1 &&
        (V.rows() < 2 || V.derived().rowStride() == 3))
      return PositionSpan(V.derived().data(), rows);
  }
  positions_into(V, name, rows, copy);
  return copy;
}

// Throws the InputError positions_into() would for the first position of x with a
// coordinate that is not a finite float (first_not_float); returns where every one is.
void name_bad_positions(PositionSpan x, const char* name);

template <typename Derived>
std::vector<Vec3> positions_from(const Eigen::MatrixBase<Derived>& V, const char* name, std::size_t rows = 0)
{
  std::vector<Vec3> out;
  positions_into(V, name, rows, out);
  return out;
}

// Copies index rows of `Width` columns (faces 3, edges 2), each index below `vertices`.
template <std::size_t Width, typename Derived>
std::vector<std::array<std::uint32_t, Width>> indices_from(const Eigen::MatrixBase<Derived>& I, const char* name,
                                                           std::size_t vertices)
{
  static_assert(std::is_integral_v<typename Derived::Scalar>, "indices are integers");
  if (std::size_t(I.cols()) != Width) details::throw_bad_shape(name, I.rows(), I.cols(), 0, Width);
  std::vector<std::array<std::uint32_t, Width>> out(std::size_t(I.rows()));
  for (Eigen::Index i = 0; i < I.rows(); ++i)
    for (std::size_t k = 0; k < Width; ++k) {
      const long long v = static_cast<long long>(I(i, Eigen::Index(k)));
      if (v < 0 || static_cast<unsigned long long>(v) >= vertices) details::throw_bad_index(name, i, v, vertices);
      out[std::size_t(i)][k] = std::uint32_t(v);
    }
  return out;
}

}  // namespace cstreams
