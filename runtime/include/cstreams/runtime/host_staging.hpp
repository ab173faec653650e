#pragma once
#include <cstreams/runtime/handle.hpp>

#include <cstddef>

namespace cstreams::runtime {

class Context;

// Host memory that device reads land in directly: a buffer allocated with
// CL_MEM_ALLOC_HOST_PTR and kept mapped for its whole life. Drivers copy into ordinary
// (pageable) memory through a staging buffer of their own; NVIDIA's driver pins this
// memory and copies straight into it. Host memory, so not counted against the device.
class HostStaging {
public:
  HostStaging() = default;
  HostStaging(Context& context, std::size_t bytes, const char* label);
  ~HostStaging();
  HostStaging(HostStaging&& other) noexcept;
  HostStaging& operator=(HostStaging&& other) noexcept;
  HostStaging(const HostStaging&) = delete;
  HostStaging& operator=(const HostStaging&) = delete;

  void* data() const noexcept { return data_; }
  std::size_t bytes() const noexcept { return bytes_; }

private:
  void release() noexcept;

  Handle<cl_command_queue> queue_;
  Handle<cl_mem> mem_;
  void* data_ = nullptr;
  std::size_t bytes_ = 0;
};

// Replaces `staging` when it holds fewer than `bytes` (contents are then lost).
void ensure_capacity(Context& context, HostStaging& staging, std::size_t bytes, const char* label);

}  // namespace cstreams::runtime
