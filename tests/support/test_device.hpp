#pragma once
#include <cstreams/runtime/context.hpp>

namespace cstreams::test {

// The device a user would get from CSTREAMS_DEVICE (pocl in CI), opened once per test
// program with the test kernels registered beside the runtime's.
runtime::Context& device();

}  // namespace cstreams::test
