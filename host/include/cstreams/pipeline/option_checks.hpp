#pragma once
#include <string>

namespace cstreams {

// The values a numeric option may take. The library checks its options against these
// (Detector, DeviceSolver) and the command line checks its flags against the same
// ranges, so a value is refused the same way wherever it comes from.
struct OptionRange {
  double min, max;
  bool min_open = false, max_open = false;  // open: the bound itself is excluded

  bool contains(double value) const;  // false for NaN and infinities
  std::string describe() const;       // "a finite number in (0, 1]"
};

namespace option_ranges {
inline constexpr OptionRange tolerance{0, 1, true, false};
inline constexpr OptionRange min_separation{0, 1e30};
inline constexpr OptionRange max_iterations{1, 4294967295.0};
inline constexpr OptionRange front_budget_mb{0, 1 << 20, true, false};
inline constexpr OptionRange memory_budget_mb{0, 1 << 30, true, false};
inline constexpr OptionRange tmax{0, 1, true, false};
inline constexpr OptionRange dhat{0, 1e30, true, false};
inline constexpr OptionRange conservative_rescaling{0, 1, true, true};
}  // namespace option_ranges

// Throws InputError "<name> = <value>: must be <range>" unless `range` contains `value`.
void check_option(const std::string& name, double value, const OptionRange& range);

}  // namespace cstreams
