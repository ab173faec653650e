#pragma once
#include <cstreams/runtime/handle.hpp>

#include <atomic>
#include <cstddef>
#include <memory>

namespace cstreams::runtime {

class Context;

// What a context's live buffers hold, and the most they have held since the mark was
// last reset: a step's peak, where what is held after it leaves out its passing scratch.
struct MemoryAccount {
  std::atomic<std::size_t> in_use{0};
  std::atomic<std::size_t> high_water{0};

  void add(std::size_t bytes) noexcept
  {
    const std::size_t now = in_use += bytes;
    std::size_t mark = high_water.load();
    while (now > mark && !high_water.compare_exchange_weak(mark, now)) {
    }
  }
  void remove(std::size_t bytes) noexcept { in_use -= bytes; }
};

// An untyped device allocation, counted against its context's memory limit for as
// long as any copy of it lives. Contents are undefined until written.
class Buffer {
public:
  Buffer() = default;
  // Throws DeviceMemoryExhausted, naming `label`, when the allocation would exceed the
  // device's largest allocation or the context's memory limit.
  Buffer(Context& context, std::size_t bytes, const char* label);

  // Bytes [offset, offset + bytes) of this buffer as a buffer of their own (an OpenCL
  // sub-buffer), counted in this one's memory and keeping it alive; `offset` must be a
  // multiple of the device's base_address_align. A slice of a slice is a sub-buffer of
  // the whole (OpenCL has no sub-buffers of sub-buffers).
  Buffer slice(std::size_t offset, std::size_t bytes) const;

  cl_mem get() const noexcept { return allocation_ ? allocation_->mem.get() : nullptr; }
  std::size_t bytes() const noexcept { return allocation_ ? allocation_->bytes : 0; }
  explicit operator bool() const noexcept { return bool(allocation_); }

private:
  struct Allocation {
    Allocation(Handle<cl_mem> m, std::size_t b, std::shared_ptr<MemoryAccount> a)
        : mem(std::move(m)), bytes(b), account(std::move(a))
    {
      account->add(bytes);
    }
    Allocation(Handle<cl_mem> m, std::size_t b, std::shared_ptr<const Allocation> w, std::size_t o)
        : whole(std::move(w)), mem(std::move(m)), bytes(b), offset(o)
    {
    }
    Allocation(const Allocation&) = delete;
    Allocation& operator=(const Allocation&) = delete;
    ~Allocation()
    {
      if (account) account->remove(bytes);
    }

    std::shared_ptr<const Allocation> whole;  // of a slice; declared first, so released after it
    Handle<cl_mem> mem;
    std::size_t bytes;
    std::size_t offset = 0;                  // of a slice, in the whole
    std::shared_ptr<MemoryAccount> account;  // of a whole buffer
  };
  std::shared_ptr<const Allocation> allocation_;
};

// Reallocates `buffer` when it holds fewer than `bytes` (contents are then lost);
// scratch and output buffers only ever grow, so steady-state runs allocate nothing.
void ensure_capacity(Context& context, Buffer& buffer, std::size_t bytes, const char* label);

}  // namespace cstreams::runtime
