#include <cstreams/errors.hpp>
#include <cstreams/pipeline/option_checks.hpp>

#include <cmath>
#include <cstdio>

namespace cstreams {

namespace {

std::string number(double v)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

}  // namespace

bool OptionRange::contains(double value) const
{
  if (!std::isfinite(value)) return false;
  if (min_open ? value <= min : value < min) return false;
  return max_open ? value < max : value <= max;
}

std::string OptionRange::describe() const
{
  return "a finite number in " + std::string(min_open ? "(" : "[") + number(min) + ", " + number(max) +
         (max_open ? ")" : "]");
}

void check_option(const std::string& name, double value, const OptionRange& range)
{
  if (!range.contains(value)) throw InputError(name + " = " + number(value) + ": must be " + range.describe());
}

}  // namespace cstreams
