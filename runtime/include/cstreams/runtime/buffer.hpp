#pragma once
#include <cstreams/runtime/handle.hpp>

#include <cstddef>

namespace cstreams::runtime {

class Context;

// An untyped device allocation. Contents are undefined until written.
class Buffer {
public:
  Buffer() = default;
  Buffer(Context& context, std::size_t bytes, const char* label);

  cl_mem get() const noexcept { return mem_.get(); }
  std::size_t bytes() const noexcept { return bytes_; }
  explicit operator bool() const noexcept { return bool(mem_); }

private:
  Handle<cl_mem> mem_;
  std::size_t bytes_ = 0;
};

// Reallocates `buffer` when it holds fewer than `bytes` (contents are then lost);
// scratch and output buffers only ever grow, so steady-state runs allocate nothing.
void ensure_capacity(Context& context, Buffer& buffer, std::size_t bytes, const char* label);

}  // namespace cstreams::runtime
