#pragma once
#include <cstreams/runtime/opencl.hpp>

#include <stdexcept>
#include <string>
#include <string_view>

namespace cstreams::runtime {

// Base of every error the runtime raises; what() is one line that names the context.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Bad input from a file or from the caller: the message names the file, line, option,
// element or object at fault.
class InputError : public Error {
public:
  using Error::Error;
};

// An OpenCL call returned an error status.
class ClError : public Error {
public:
  ClError(cl_int status, std::string call, std::string context);
  cl_int status() const noexcept { return status_; }
  const std::string& call() const noexcept { return call_; }

private:
  cl_int status_;
  std::string call_;
};

// A program failed to build; log() is the compiler's full output.
class BuildError : public Error {
public:
  BuildError(std::string program, std::string device, std::string options, std::string log);
  const std::string& program() const noexcept { return program_; }
  const std::string& log() const noexcept { return log_; }

private:
  std::string program_;
  std::string log_;
};

// No device matched a filter; what() lists the devices that exist.
class DeviceNotFound : public Error {
public:
  using Error::Error;
};

// A variable stream needed more items than the limit set on it (Scheduler::set_limit);
// the run stopped, leaving the streams it reads as they were.
class StreamLimitExceeded : public Error {
public:
  StreamLimitExceeded(const std::string& stream, std::size_t needed, std::size_t limit);
  std::size_t needed() const noexcept { return needed_; }

private:
  std::size_t needed_;
};

// A pass raised its stop flag (PassSpec::stop_if): the run stopped after it, its
// outputs incomplete, for the caller to change the inputs and run again.
class RunStopped : public Error {
public:
  explicit RunStopped(const std::string& pass);
};

// An allocation the device cannot hold: over its largest single allocation, or over
// the memory left under the context's limit (Context::memory_limit()).
class DeviceMemoryExhausted : public Error {
public:
  DeviceMemoryExhausted(const std::string& label, std::size_t bytes, const std::string& why);
  std::size_t requested() const noexcept { return requested_; }

private:
  std::size_t requested_;
};

// A work list whose inputs would take more than its pass lets it (Worklist::most_bytes):
// the run goes on in slices as where memory runs short, but the memory is there, so
// nothing idle is given back for it.
class WorkListOverBudget : public DeviceMemoryExhausted {
public:
  using DeviceMemoryExhausted::DeviceMemoryExhausted;
};

// Runs `allocate`; when the device has no memory left, runs `make_room` and, if that
// gave any memory back, tries once more.
template <class Allocate, class MakeRoom> void allocate_making_room(Allocate allocate, MakeRoom make_room)
{
  try {
    allocate();
    return;
  } catch (const DeviceMemoryExhausted&) {
    if (!make_room()) throw;
  }
  allocate();
}

// "12.5 MiB"
std::string mebibytes(std::size_t bytes);

const char* cl_status_name(cl_int status) noexcept;

// Throws ClError when status is not CL_SUCCESS. `context` says what was being done.
inline void check(cl_int status, const char* call, std::string_view context = {})
{
  if (status != CL_SUCCESS) throw ClError(status, call, std::string(context));
}

// The same where the call runs a thousand times a step: `describe()` builds the
// context only on failure.
template <class Describe> void check_with(cl_int status, const char* call, Describe describe)
{
  if (status != CL_SUCCESS) throw ClError(status, call, describe());
}

}  // namespace cstreams::runtime
