#pragma once
#include <cstreams/runtime/buffer.hpp>

#include <cstddef>
#include <memory>

namespace cstreams::runtime {

class Context;

// Boost.Compute's exclusive_scan and copy_if on a cstreams context: the reference
// points of the runtime benchmark. Boost.Compute stays inside baselines.cpp.
class BoostComputeBaselines {
public:
  explicit BoostComputeBaselines(Context& context);
  ~BoostComputeBaselines();

  void exclusive_scan(const Buffer& in, const Buffer& out, std::size_t n);
  // Copies the odd values among the first n of `in` to `out`; returns how many.
  std::size_t copy_if_odd(const Buffer& in, const Buffer& out, std::size_t n);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cstreams::runtime
