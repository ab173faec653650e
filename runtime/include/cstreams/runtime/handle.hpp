#pragma once
#include <cstreams/runtime/opencl.hpp>

#include <utility>

namespace cstreams::runtime {

namespace detail {
template <class T> struct ClRefCount;
#define CSTREAMS_CL_REFCOUNT(T, retain, release)         \
  template <> struct ClRefCount<T> {                     \
    static void add(T h) noexcept { retain(h); }         \
    static void drop(T h) noexcept { release(h); }       \
  };
CSTREAMS_CL_REFCOUNT(cl_context, clRetainContext, clReleaseContext)
CSTREAMS_CL_REFCOUNT(cl_command_queue, clRetainCommandQueue, clReleaseCommandQueue)
CSTREAMS_CL_REFCOUNT(cl_mem, clRetainMemObject, clReleaseMemObject)
CSTREAMS_CL_REFCOUNT(cl_program, clRetainProgram, clReleaseProgram)
CSTREAMS_CL_REFCOUNT(cl_kernel, clRetainKernel, clReleaseKernel)
CSTREAMS_CL_REFCOUNT(cl_event, clRetainEvent, clReleaseEvent)
#undef CSTREAMS_CL_REFCOUNT
}  // namespace detail

// Shared ownership of one OpenCL object through its own reference count.
template <class T> class Handle {
public:
  Handle() = default;
  // Takes over a reference the caller already owns (as returned by clCreate*).
  explicit Handle(T raw) noexcept : raw_(raw) {}
  Handle(const Handle& other) noexcept : raw_(other.raw_) { if (raw_) detail::ClRefCount<T>::add(raw_); }
  Handle(Handle&& other) noexcept : raw_(std::exchange(other.raw_, nullptr)) {}
  Handle& operator=(Handle other) noexcept
  {
    std::swap(raw_, other.raw_);
    return *this;
  }
  ~Handle() { if (raw_) detail::ClRefCount<T>::drop(raw_); }

  T get() const noexcept { return raw_; }
  explicit operator bool() const noexcept { return raw_ != nullptr; }

private:
  T raw_ = nullptr;
};

}  // namespace cstreams::runtime
