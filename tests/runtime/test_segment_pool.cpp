// Segments waiting between stages (runtime/src/scheduler/segment_pool.*): which idle
// buffer a pass takes, and which the pool keeps once a run's stages are known.
// test_scratch.cpp runs it inside the scheduler.
#include "../../runtime/src/scheduler/segment_pool.hpp"
#include "../support/test_device.hpp"

#include <cstreams/runtime/buffer.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

using namespace cstreams::runtime;

namespace {

constexpr std::size_t MiB = std::size_t(1) << 20;

SegmentPool pool_of(const std::vector<std::size_t>& mib)
{
  SegmentPool pool;
  for (std::size_t m : mib) pool.give_back(Buffer(cstreams::test::device(), m * MiB, "idle segments"));
  return pool;
}

std::vector<std::size_t> idle_mib(const SegmentPool& pool)
{
  std::vector<std::size_t> mib;
  for (const Buffer& b : pool.idle()) mib.push_back(b.bytes() / MiB);
  std::sort(mib.begin(), mib.end());
  return mib;
}

}  // namespace

TEST_CASE("a pass takes the smallest idle segments that hold its need without much to spare", "[runtime][quick]")
{
  SegmentPool pool = pool_of({1, 4, 8});
  // 4 MiB for 3.6: an eighth to spare at most.
  auto taken = pool.take(36 * MiB / 10, 0);
  REQUIRE(taken);
  CHECK(taken->bytes() == 4 * MiB);
  CHECK(idle_mib(pool) == std::vector<std::size_t>{1, 8});
  // 8 MiB for 3 spare 5: not where the device lacks room for twice that, and the buffers
  // too small go back before the pass allocates its own.
  CHECK_FALSE(pool.take(3 * MiB, 9 * MiB));
  CHECK(idle_mib(pool) == std::vector<std::size_t>{8});
  CHECK(pool.take(3 * MiB, 10 * MiB));
  CHECK(pool.idle().empty());
}

TEST_CASE("after a run the pool keeps what its stages need, each buffer near the most it served", "[runtime][quick]")
{
  // One stage needed 3 and 2 MiB at once: the 2 MiB buffer goes (3 and 4 serve it as
  // well), the 3 and 4 stay for it; then the 4 goes, more than an eighth and 1 MiB
  // above the 2 it served.
  SegmentPool one = pool_of({2, 3, 4});
  one.start_run();
  one.stage_done({2 * MiB, 3 * MiB});
  one.keep_needed();
  CHECK(idle_mib(one) == std::vector<std::size_t>{3});

  // Two stages, one after the other, share the 5 MiB buffer, which stays.
  SegmentPool shared = pool_of({4, 5});
  shared.start_run();
  shared.stage_done({3 * MiB});
  shared.stage_done({45 * MiB / 10});
  shared.keep_needed();
  CHECK(idle_mib(shared) == std::vector<std::size_t>{5});

  // A burst that has passed: 16 MiB for stages that need 3 and 1 goes back.
  SegmentPool burst = pool_of({16});
  burst.start_run();
  burst.stage_done({3 * MiB});
  burst.stage_done({1 * MiB});
  burst.keep_needed();
  CHECK(burst.idle().empty());

  SegmentPool full = pool_of({1, 2});
  CHECK(full.release());
  CHECK(full.idle().empty());
  CHECK_FALSE(full.release());
}
