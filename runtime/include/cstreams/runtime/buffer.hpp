#pragma once
#include <cstreams/runtime/handle.hpp>

#include <atomic>
#include <cstddef>
#include <memory>

namespace cstreams::runtime {

class Context;

// An untyped device allocation, counted against its context's memory limit for as
// long as any copy of it lives. Contents are undefined until written.
class Buffer {
public:
  Buffer() = default;
  // Throws DeviceMemoryExhausted, naming `label`, when the allocation would exceed the
  // device's largest allocation or the context's memory limit.
  Buffer(Context& context, std::size_t bytes, const char* label);

  cl_mem get() const noexcept { return allocation_ ? allocation_->mem.get() : nullptr; }
  std::size_t bytes() const noexcept { return allocation_ ? allocation_->bytes : 0; }
  explicit operator bool() const noexcept { return bool(allocation_); }

private:
  struct Allocation {
    Allocation(Handle<cl_mem> m, std::size_t b, std::shared_ptr<std::atomic<std::size_t>> account)
        : mem(std::move(m)), bytes(b), in_use(std::move(account))
    {
      *in_use += bytes;
    }
    Allocation(const Allocation&) = delete;
    Allocation& operator=(const Allocation&) = delete;
    ~Allocation() { *in_use -= bytes; }

    Handle<cl_mem> mem;
    std::size_t bytes;
    std::shared_ptr<std::atomic<std::size_t>> in_use;
  };
  std::shared_ptr<const Allocation> allocation_;
};

// Reallocates `buffer` when it holds fewer than `bytes` (contents are then lost);
// scratch and output buffers only ever grow, so steady-state runs allocate nothing.
void ensure_capacity(Context& context, Buffer& buffer, std::size_t bytes, const char* label);

}  // namespace cstreams::runtime
