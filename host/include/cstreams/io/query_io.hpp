#pragma once
#include <cstreams/errors.hpp>
#include <cstreams/reference/reference_solver.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace cstreams {

// One elementary query with its ground truth.
struct LabeledQuery {
  Query points;
  bool collides = false;
};

// Reads a query CSV of either published format: eight rows per query, each three
// rationals as integer pairs `num,den` (six columns), optionally followed by a 0/1
// ground-truth column (seven columns, the hand-made set). Numerators and denominators
// may exceed 64 bits; both are exact doubles in these files (denominators are powers
// of two), so num / den is exact, and anything that is not is rejected. Without a
// truth column `collides` is false; the caller supplies the truth (mma_bool).
std::vector<LabeledQuery> read_queries(const std::string& path);
// The same from a stream; `name` names it in errors.
std::vector<LabeledQuery> parse_queries(std::istream& in, const std::string& name);

// Reads a JSON array of booleans (the mma_bool ground-truth files).
std::vector<bool> read_bool_array(const std::string& path);

}  // namespace cstreams
