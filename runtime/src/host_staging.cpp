#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/host_staging.hpp>

#include <algorithm>
#include <string>
#include <utility>

namespace cstreams::runtime {

HostStaging::HostStaging(Context& context, std::size_t bytes, const char* label)
{
  const std::string what = "allocating " + std::to_string(bytes) + " bytes of host memory for " + label;
  cl_int status = CL_SUCCESS;
  mem_ = Handle<cl_mem>(clCreateBuffer(context.get(), CL_MEM_ALLOC_HOST_PTR | CL_MEM_READ_WRITE,
                                       std::max<std::size_t>(bytes, 4), nullptr, &status));
  check(status, "clCreateBuffer", what);
  clRetainCommandQueue(context.queue());
  queue_ = Handle<cl_command_queue>(context.queue());
  data_ = clEnqueueMapBuffer(queue_.get(), mem_.get(), CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0,
                             std::max<std::size_t>(bytes, 4), 0, nullptr, nullptr, &status);
  check(status, "clEnqueueMapBuffer", what);
  bytes_ = bytes;
}

HostStaging::~HostStaging() { release(); }

HostStaging::HostStaging(HostStaging&& other) noexcept
    : queue_(std::move(other.queue_)), mem_(std::move(other.mem_)), data_(std::exchange(other.data_, nullptr)),
      bytes_(std::exchange(other.bytes_, 0))
{
}

HostStaging& HostStaging::operator=(HostStaging&& other) noexcept
{
  if (this != &other) {
    release();
    queue_ = std::move(other.queue_);
    mem_ = std::move(other.mem_);
    data_ = std::exchange(other.data_, nullptr);
    bytes_ = std::exchange(other.bytes_, 0);
  }
  return *this;
}

// The buffer is released once the unmap has run; a failure here has no one to tell.
void HostStaging::release() noexcept
{
  if (data_) clEnqueueUnmapMemObject(queue_.get(), mem_.get(), data_, 0, nullptr, nullptr);
  data_ = nullptr;
  bytes_ = 0;
  mem_ = Handle<cl_mem>();
  queue_ = Handle<cl_command_queue>();
}

void ensure_capacity(Context& context, HostStaging& staging, std::size_t bytes, const char* label)
{
  if (staging.bytes() < bytes || !staging.data()) staging = HostStaging(context, bytes, label);
}

}  // namespace cstreams::runtime
