// A program outside the cstreams tree: it finds the installed package, opens the
// device CSTREAMS_DEVICE selects and runs one scan through the installed runtime.
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/primitives.hpp>

#include <cstdio>
#include <vector>

int main()
{
  using namespace cstreams::runtime;
  Context context(filter_from_environment());
  Scan scan(context);
  const std::vector<cl_uint> values{3, 1, 4, 1, 5};
  Buffer in(context, 20, "values"), counters(context, 4, "total");
  context.write(in, values.data(), 20);
  scan.exclusive(in, in, values.size(), counters, 0);
  std::vector<cl_uint> prefix(5);
  cl_uint total = 0;
  context.read(in, prefix.data(), 20);
  context.read(counters, &total, 4);
  const bool ok = prefix == std::vector<cl_uint>{0, 3, 4, 8, 9} && total == 14;
  std::printf("consumer on %s: %s\n", context.device().name.c_str(), ok ? "ok" : "WRONG");
  return ok ? 0 : 1;
}
