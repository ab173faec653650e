#include "test_device.hpp"

const cstreams::runtime::SourceSet& test_kernel_sources();

namespace cstreams::test {

runtime::Context& device()
{
  static runtime::Context context(runtime::filter_from_environment());
  static const bool registered = (context.programs().add_sources(test_kernel_sources()), true);
  (void)registered;
  return context;
}

}  // namespace cstreams::test
