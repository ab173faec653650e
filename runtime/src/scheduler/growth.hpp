#pragma once
// How the scheduler's parts grow what overflowed. Private to the runtime.
#include <cstddef>

namespace cstreams::runtime {

// Slack on growth, so that a count that creeps up frame by frame does not rerun each time.
inline std::size_t grown(std::size_t needed) { return needed + needed / 8 + 16; }

}  // namespace cstreams::runtime
