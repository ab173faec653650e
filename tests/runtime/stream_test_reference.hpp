#pragma once
// Host twin of tests/kernels/stream_test.cl: what the test graph must produce.
#include <array>
#include <cstdint>
#include <vector>

namespace cstreams::test {

inline std::uint32_t test_hash(std::uint32_t x)
{
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

inline std::uint32_t test_emit_count(std::uint32_t value)
{
  const std::uint32_t h = test_hash(value);
  return (h & 63u) == 0 ? 40u : h % 5u;
}

// The smallest value whose test_expand emits `count` items (0 to 4, or 40: a burst).
inline std::uint32_t value_emitting(std::uint32_t count)
{
  std::uint32_t value = 0;
  while (test_emit_count(value) != count) ++value;
  return value;
}

using Pair = std::array<std::uint32_t, 2>;
using Quad = std::array<std::uint32_t, 4>;

struct Expected {
  std::vector<Pair> pairs;
  std::vector<Pair> kept;
  std::vector<std::uint32_t> even;
  std::vector<Quad> odd;
};

inline Expected reference(const std::vector<std::uint32_t>& values)
{
  Expected e;
  for (std::uint32_t i = 0; i < values.size(); ++i)
    for (std::uint32_t k = 0; k < test_emit_count(values[i]); ++k) e.pairs.push_back({i, k});
  for (const auto& p : e.pairs)
    if (test_hash(p[0] * 31u + p[1]) % 3u != 0u) e.kept.push_back(p);
  for (const auto& p : e.kept) {
    const std::uint32_t s = values[p[0]] * values[p[0]];
    if ((s + p[1]) % 2u == 0u) {
      e.even.push_back(s + p[1]);
    } else {
      for (std::uint32_t k = 0; k < p[1] % 3u + 1u; ++k) e.odd.push_back({p[0], p[1], k, s});
    }
  }
  return e;
}

}  // namespace cstreams::test
