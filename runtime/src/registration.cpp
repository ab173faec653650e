#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/registration.hpp>

#include <algorithm>
#include <string>

namespace cstreams::runtime {

const char* to_string(Registration registration) noexcept
{
  switch (registration) {
    case Registration::global_atomic: return "global-atomic";
    case Registration::segmented_lock: return "segmented-lock";
    case Registration::lock_free: return "lock-free";
  }
  return "?";
}

Registration parse_registration(std::string_view text)
{
  std::string t(text);
  std::replace(t.begin(), t.end(), '_', '-');
  for (auto r : {Registration::global_atomic, Registration::segmented_lock, Registration::lock_free})
    if (t == to_string(r)) return r;
  throw InputError("unknown registration '" + std::string(text) + "' (global-atomic, segmented-lock or lock-free)");
}

}  // namespace cstreams::runtime
