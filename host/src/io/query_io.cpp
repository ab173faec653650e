#include <cstreams/io/file_input.hpp>
#include <cstreams/io/query_io.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace cstreams {

namespace {

// Parses a decimal integer into a double, failing unless the value is exact.
double exact_integer(const std::string& text, const std::string& where)
{
  if (text.empty()) throw InputError(where + ": empty field");
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(value) || value != std::floor(value))
    throw InputError(where + ": '" + text + "' is not an integer");
  // A decimal that strtod rounded would print differently; exact ones print back the same.
  std::size_t first = text[0] == '-' || text[0] == '+' ? 1 : 0;
  while (first + 1 < text.size() && text[first] == '0') ++first;
  char printed[400];
  std::snprintf(printed, sizeof printed, "%.0f", std::abs(value));
  if (text.substr(first) != printed)
    throw InputError(where + ": '" + text + "' is not exactly representable as a double");
  return value;
}

}  // namespace

std::vector<LabeledQuery> read_queries(const std::string& path)
{
  std::ifstream file = open_input(path, "query file");
  return parse_queries(file, path);
}

std::vector<LabeledQuery> parse_queries(std::istream& file, const std::string& path)
{
  std::vector<LabeledQuery> queries;
  std::string line;
  std::size_t line_number = 0, row = 0;
  int columns = 0;
  while (std::getline(file, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number);
    std::vector<std::string> fields;
    std::stringstream in(line);
    for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
    if (fields.size() != 6 && fields.size() != 7)
      throw InputError(where + ": expected 6 or 7 columns, found " + std::to_string(fields.size()));
    if (columns == 0) columns = int(fields.size());
    if (int(fields.size()) != columns) throw InputError(where + ": column count changes within the file");
    if (row % 8 == 0) queries.emplace_back();
    LabeledQuery& q = queries.back();
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      const double num = exact_integer(fields[std::size_t(2 * k)], where);
      const double den = exact_integer(fields[std::size_t(2 * k + 1)], where);
      if (den == 0) throw InputError(where + ": zero denominator");
      p[k] = num / den;
      // The residual of the rounded quotient, computed exactly: 1/3 rounds to a double
      // whose product with 3 rounds back to 1, so checking p * den == num would pass it.
      if (std::fma(p[k], den, -num) != 0) throw InputError(where + ": " + fields[std::size_t(2 * k)] + "/" +
                                              fields[std::size_t(2 * k + 1)] + " is not exact in double");
    }
    q.points[row % 8] = p;
    if (columns == 7) {
      const bool truth = fields[6] == "1";
      if (fields[6] != "0" && fields[6] != "1") throw InputError(where + ": truth column must be 0 or 1");
      if (row % 8 != 0 && truth != q.collides) throw InputError(where + ": truth differs between rows of one query");
      q.collides = truth;
    }
    ++row;
  }
  if (file.bad()) throw InputError(path + ": read error");
  if (row % 8 != 0)
    throw InputError(path + ": " + std::to_string(row) + " rows is not a whole number of 8-row queries (truncated)");
  return queries;
}

std::vector<bool> read_bool_array(const std::string& path)
{
  std::ifstream file = open_input(path, "JSON file");
  try {
    const auto json = nlohmann::json::parse(file);
    std::vector<bool> out;
    for (const auto& v : json) {
      if (!v.is_boolean()) throw InputError(path + ": expected an array of booleans");
      out.push_back(v.get<bool>());
    }
    return out;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace cstreams
