#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/simulation/arrays.hpp>

namespace cstreams::details {

void throw_bad_shape(const char* name, std::ptrdiff_t rows, std::ptrdiff_t cols, std::size_t want_rows,
                     std::size_t want_cols)
{
  const std::string want = (want_rows > 0 ? std::to_string(want_rows) : std::string("any number of")) + " rows and " +
                           std::to_string(want_cols) + " columns";
  throw InputError(std::string(name) + ": has " + std::to_string(rows) + " rows and " + std::to_string(cols) +
                   " columns; it needs " + want);
}

void throw_not_finite(const char* name, std::ptrdiff_t row)
{
  throw InputError(std::string(name) + ": row " + std::to_string(row) +
                   " holds a coordinate that is not finite or is beyond float's range");
}

void throw_bad_index(const char* name, std::ptrdiff_t row, long long index, std::size_t vertices)
{
  throw InputError(std::string(name) + ": row " + std::to_string(row) + " holds vertex " + std::to_string(index) +
                   "; the positions have " + std::to_string(vertices) + " rows");
}

}  // namespace cstreams::details

namespace cstreams {

void name_bad_positions(PositionSpan x, const char* name)
{
  const std::size_t i = first_not_float(x);
  if (i < x.size()) details::throw_not_finite(name, std::ptrdiff_t(i));
}

}  // namespace cstreams
