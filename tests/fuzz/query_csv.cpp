// libFuzzer entry: see inputs.hpp for what an input must do, tests/fuzz/CMakeLists.txt
// for how CI runs it.
#include "inputs.hpp"

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  cstreams::fuzz::query_csv({reinterpret_cast<const char*>(data), size});
  return 0;
}
