#include <cstreams/runtime/error.hpp>

#include <cstdio>

namespace cstreams::runtime {

namespace {
std::string describe(cl_int status, const std::string& call, const std::string& context)
{
  std::string text = call + " failed with " + cl_status_name(status) + " (" + std::to_string(status) + ")";
  if (!context.empty()) text += " while " + context;
  return text;
}

// The line of a build log that best says what failed: the first one naming an error,
// else the last non-empty one (some drivers only say "fatal" or end with a summary).
std::string headline(const std::string& log)
{
  std::string last;
  std::size_t start = 0;
  while (start < log.size()) {
    std::size_t end = log.find('\n', start);
    if (end == std::string::npos) end = log.size();
    std::string line = log.substr(start, end - start);
    if (line.find("error") != std::string::npos || line.find("fatal") != std::string::npos) return line;
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
    start = end + 1;
  }
  return last.empty() ? "the compiler gave no log" : last;
}
}  // namespace

ClError::ClError(cl_int status, std::string call, std::string context)
    : Error(describe(status, call, context)), status_(status), call_(std::move(call))
{
}

// what() stays one line (the first compiler error) so a CLI can print it as is;
// log() carries the whole compiler output.
BuildError::BuildError(std::string program, std::string device, std::string options, std::string log)
    : Error("building OpenCL program " + program + " for " + device + " failed: " + headline(log) +
            " [options: " + options + "]"),
      program_(std::move(program)),
      log_(std::move(log))
{
}

const char* cl_status_name(cl_int status) noexcept
{
  switch (status) {
#define CASE(x) case x: return #x;
    CASE(CL_SUCCESS)
    CASE(CL_DEVICE_NOT_FOUND)
    CASE(CL_DEVICE_NOT_AVAILABLE)
    CASE(CL_COMPILER_NOT_AVAILABLE)
    CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    CASE(CL_OUT_OF_RESOURCES)
    CASE(CL_OUT_OF_HOST_MEMORY)
    CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
    CASE(CL_MEM_COPY_OVERLAP)
    CASE(CL_BUILD_PROGRAM_FAILURE)
    CASE(CL_MAP_FAILURE)
    CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    CASE(CL_COMPILE_PROGRAM_FAILURE)
    CASE(CL_LINKER_NOT_AVAILABLE)
    CASE(CL_LINK_PROGRAM_FAILURE)
    CASE(CL_INVALID_VALUE)
    CASE(CL_INVALID_DEVICE_TYPE)
    CASE(CL_INVALID_PLATFORM)
    CASE(CL_INVALID_DEVICE)
    CASE(CL_INVALID_CONTEXT)
    CASE(CL_INVALID_QUEUE_PROPERTIES)
    CASE(CL_INVALID_COMMAND_QUEUE)
    CASE(CL_INVALID_HOST_PTR)
    CASE(CL_INVALID_MEM_OBJECT)
    CASE(CL_INVALID_BINARY)
    CASE(CL_INVALID_BUILD_OPTIONS)
    CASE(CL_INVALID_PROGRAM)
    CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    CASE(CL_INVALID_KERNEL_NAME)
    CASE(CL_INVALID_KERNEL_DEFINITION)
    CASE(CL_INVALID_KERNEL)
    CASE(CL_INVALID_ARG_INDEX)
    CASE(CL_INVALID_ARG_VALUE)
    CASE(CL_INVALID_ARG_SIZE)
    CASE(CL_INVALID_KERNEL_ARGS)
    CASE(CL_INVALID_WORK_DIMENSION)
    CASE(CL_INVALID_WORK_GROUP_SIZE)
    CASE(CL_INVALID_WORK_ITEM_SIZE)
    CASE(CL_INVALID_GLOBAL_OFFSET)
    CASE(CL_INVALID_EVENT_WAIT_LIST)
    CASE(CL_INVALID_EVENT)
    CASE(CL_INVALID_OPERATION)
    CASE(CL_INVALID_BUFFER_SIZE)
    CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    CASE(CL_INVALID_PROPERTY)
#undef CASE
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return "unknown OpenCL status";
  }
}

DeviceMemoryExhausted::DeviceMemoryExhausted(const std::string& label, std::size_t bytes, const std::string& why)
    : Error("device memory exhausted: allocating " + mebibytes(bytes) + " for " + label + ", but " + why),
      requested_(bytes)
{
}

std::string mebibytes(std::size_t bytes)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MiB", double(bytes) / (1 << 20));
  return text;
}

RunStopped::RunStopped(const std::string& pass) : Error("pass " + pass + " stopped the run") {}

StreamLimitExceeded::StreamLimitExceeded(const std::string& stream, std::size_t needed, std::size_t limit)
    : Error("stream " + stream + " needs " + std::to_string(needed) + " items, over its limit of " +
            std::to_string(limit)),
      needed_(needed)
{
}

}  // namespace cstreams::runtime
