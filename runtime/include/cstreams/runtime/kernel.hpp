#pragma once
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/handle.hpp>

#include <cstddef>
#include <string>
#include <type_traits>

namespace cstreams::runtime {

// One cl_kernel, created once by the program registry and shared by every launch.
// Arguments are captured by clEnqueueNDRangeKernel, so resetting them between
// launches on one thread is safe.
class Kernel {
public:
  Kernel() = default;
  Kernel(Handle<cl_kernel> kernel, std::string name, std::size_t max_work_group_size)
      : kernel_(std::move(kernel)), name_(std::move(name)), max_work_group_size_(max_work_group_size)
  {
  }

  cl_kernel get() const noexcept { return kernel_.get(); }
  const std::string& name() const noexcept { return name_; }
  std::size_t max_work_group_size() const noexcept { return max_work_group_size_; }

  void set_arg(unsigned index, const Buffer& buffer) const
  {
    cl_mem mem = buffer.get();
    set_raw(index, sizeof(mem), &mem);
  }
  template <class T, class = std::enable_if_t<std::is_trivially_copyable_v<T> && !std::is_same_v<T, Buffer>>>
  void set_arg(unsigned index, const T& value) const
  {
    set_raw(index, sizeof(T), &value);
  }
  void set_local(unsigned index, std::size_t bytes) const { set_raw(index, bytes, nullptr); }
  void set_raw(unsigned index, std::size_t size, const void* value) const;

  template <class... Args> void set_args(const Args&... args) const
  {
    unsigned index = 0;
    (set_arg(index++, args), ...);
  }

private:
  Handle<cl_kernel> kernel_;
  std::string name_;
  std::size_t max_work_group_size_ = 0;
};

}  // namespace cstreams::runtime
