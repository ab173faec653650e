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
    Allocation(const Allocation&) = delete;
    Allocation& operator=(const Allocation&) = delete;
    ~Allocation() { account->remove(bytes); }

    Handle<cl_mem> mem;
    std::size_t bytes;
    std::shared_ptr<MemoryAccount> account;
  };
  std::shared_ptr<const Allocation> allocation_;
};

// Reallocates `buffer` when it holds fewer than `bytes` (contents are then lost);
// scratch and output buffers only ever grow, so steady-state runs allocate nothing.
void ensure_capacity(Context& context, Buffer& buffer, std::size_t bytes, const char* label);

}  // namespace cstreams::runtime
