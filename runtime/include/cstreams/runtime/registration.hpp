#pragma once
// How the scheduler packs what a pass emits (cl_kernels/runtime/registration.h). A
// scheduler choice, not part of a graph: one graph runs under any registration.
#include <string_view>

namespace cstreams::runtime {

enum class Registration { global_atomic, segmented_lock, lock_free };
const char* to_string(Registration registration) noexcept;
// Accepts "global-atomic", "segmented-lock", "lock-free" (or with underscores).
Registration parse_registration(std::string_view text);

}  // namespace cstreams::runtime
