#include "../support/test_device.hpp"

#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/primitives.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <numeric>
#include <random>

using namespace cstreams::runtime;

namespace {
std::vector<cl_uint> random_values(std::size_t n, std::uint32_t seed, cl_uint max_value)
{
  std::mt19937 rng(seed);
  std::uniform_int_distribution<cl_uint> dist(0, max_value);
  std::vector<cl_uint> v(n);
  for (auto& x : v) x = dist(rng);
  return v;
}

std::vector<std::size_t> sizes_around_powers_of_two(std::size_t up_to)
{
  std::vector<std::size_t> sizes{0, 1, 2, 3};
  for (std::size_t p = 4; p <= up_to; p *= 2)
    for (std::size_t s : {p - 1, p, p + 1}) sizes.push_back(s);
  return sizes;
}

void check_scan(std::size_t n, bool in_place)
{
  auto& ctx = cstreams::test::device();
  Scan scan(ctx);
  const auto values = random_values(n, std::uint32_t(n), 1000);
  Buffer in(ctx, n * 4, "scan input"), out(ctx, n * 4, "scan output"), counters(ctx, 8, "counters");
  ctx.write(in, values.data(), n * 4);
  ctx.fill_u32(counters, 0xdeadbeef, 0, 2);
  scan.exclusive(in, in_place ? in : out, n, counters, 1);
  std::vector<cl_uint> result(n), totals(2);
  ctx.read(in_place ? in : out, result.data(), n * 4);
  ctx.read(counters, totals.data(), 8);

  std::vector<cl_uint> expected(n);
  std::exclusive_scan(values.begin(), values.end(), expected.begin(), cl_uint(0));
  INFO("n = " << n);
  CHECK(result == expected);
  CHECK(totals[1] == std::accumulate(values.begin(), values.end(), cl_uint(0)));
  CHECK(totals[0] == 0xdeadbeef);  // other slots untouched
}

void check_compaction(std::size_t n, std::size_t capacity_factor_percent)
{
  auto& ctx = cstreams::test::device();
  Scan scan(ctx);
  // Two-word items check that whole elements move, not words.
  std::vector<cl_uint> items(2 * n);
  std::vector<cl_uint> keep = random_values(n, std::uint32_t(n) + 7, 1);
  for (std::size_t i = 0; i < n; ++i) items[2 * i] = cl_uint(i), items[2 * i + 1] = cl_uint(~i);
  std::vector<cl_uint> expected;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) expected.insert(expected.end(), {cl_uint(i), cl_uint(~i)});
  const std::size_t kept = expected.size() / 2;
  const std::size_t capacity = kept * capacity_factor_percent / 100;

  Buffer src(ctx, n * 8, "src"), flags(ctx, n * 4, "flags"), dst(ctx, capacity * 8, "dst"), counters(ctx, 4, "c");
  ctx.write(src, items.data(), n * 8);
  ctx.write(flags, keep.data(), n * 4);
  scan.compact(src, 2, flags, n, dst, capacity, counters, 0);
  cl_uint count = 0;
  ctx.read(counters, &count, 4);
  std::vector<cl_uint> result(2 * std::min(capacity, kept));
  ctx.read(dst, result.data(), result.size() * 4);
  INFO("n = " << n << ", capacity = " << capacity);
  CHECK(count == kept);  // the count is exact even when the destination is too small
  CHECK(std::equal(result.begin(), result.end(), expected.begin()));
}

enum class Order { random, ascending, descending };

// Records whose leading words repeat often, so that comparisons reach the later
// words, and some records equal in every word. Records already in order, or in
// reverse, make every tile of a merge come from one run alone.
void check_sort(std::size_t n, std::size_t words, Order order = Order::random)
{
  auto& ctx = cstreams::test::device();
  Sorter sorter(ctx, words);
  std::vector<cl_uint> values = random_values(n * words, std::uint32_t(n * words), 3);
  const auto last_words = random_values(n, std::uint32_t(n) + 1, 0xffffffffu);
  for (std::size_t i = 0; i < n; ++i)
    if (i % 5 != 0) values[i * words + words - 1] = last_words[i];
  if (order != Order::random)
    for (std::size_t i = 0; i < n; ++i) values[i * words] = cl_uint(order == Order::ascending ? i : n - i);
  Buffer records(ctx, std::max<std::size_t>(n, 1) * words * 4, "records");
  ctx.write(records, values.data(), values.size() * 4);
  const Buffer& sorted = sorter.sort(records, n);
  std::vector<cl_uint> result(n * words);
  ctx.read(sorted, result.data(), result.size() * 4);

  std::vector<std::vector<cl_uint>> expected(n);
  for (std::size_t i = 0; i < n; ++i) expected[i].assign(values.begin() + i * words, values.begin() + (i + 1) * words);
  std::sort(expected.begin(), expected.end());
  std::vector<cl_uint> flat;
  for (const auto& r : expected) flat.insert(flat.end(), r.begin(), r.end());
  INFO("n = " << n << ", words = " << words);
  CHECK(result == flat);
}
}  // namespace

TEST_CASE("sorting records equals the host's sort at sizes 0, 1, 2^k-1, 2^k, 2^k+1", "[runtime][sort][quick]")
{
  for (std::size_t n : sizes_around_powers_of_two(std::size_t(1) << 13)) check_sort(n, 3);
  for (std::size_t words : {1, 2, 5, 8, 16}) check_sort(1000, words);
  check_sort(100000, 8);
  check_sort(20000, 8, Order::ascending);
  check_sort(20000, 8, Order::descending);
  REQUIRE_THROWS_WITH(Sorter(cstreams::test::device(), 17), Catch::Contains("records of 17 words"));
}

TEST_CASE("exclusive scan equals the host's at sizes 0, 1, 2^k-1, 2^k, 2^k+1", "[runtime][scan][quick]")
{
  for (std::size_t n : sizes_around_powers_of_two(std::size_t(1) << 17)) check_scan(n, false);
  check_scan(100000, true);
}

TEST_CASE("a scan of a few tiles takes one launch, and is right in place", "[runtime][scan][quick]")
{
  auto& ctx = cstreams::test::device();
  Scan scan(ctx);
  const std::size_t tile = scan.tile_items();
  Buffer data(ctx, 8 * tile * 4, "scan data"), counters(ctx, 4, "counters");
  ctx.fill_u32(data, 1, 0, 8 * tile);
  auto launches = [&](std::size_t n) {
    const std::uint64_t before = ctx.kernel_launches();
    scan.exclusive(data, data, n, counters, 0);
    return ctx.kernel_launches() - before;
  };
  for (std::size_t n : {std::size_t(1), tile, tile + 1, 4 * tile}) {
    INFO("n = " << n);
    CHECK(launches(n) == 1);
    check_scan(n, true);
  }
  // Beyond: the tiles' sums, then the tiles, each group adding up the sums before it.
  CHECK(launches(4 * tile + 1) == 2);
  check_scan(4 * tile + 1, true);
}

// A pass's two outputs' segment counts: scanned together in one launch while each is a
// few tiles long, in two scans each beyond, always equal to the host's scans of each,
// each total in its own counter.
TEST_CASE("two scans at once equal the host's, in one launch while each input is short", "[runtime][scan][quick]")
{
  auto& ctx = cstreams::test::device();
  Scan scan(ctx);
  const std::size_t tile = scan.tile_items();
  for (const auto& [na, nb] : std::vector<std::pair<std::size_t, std::size_t>>{
           {1, 1}, {tile + 1, 3}, {11 * tile + 5, 5 * tile}, {16 * tile, 16 * tile}, {16 * tile + 1, 2}, {0, 7}}) {
    INFO("sizes " << na << " and " << nb);
    const auto a = random_values(na, std::uint32_t(na), 1000), b = random_values(nb, std::uint32_t(nb) + 1, 1000);
    Buffer in_a(ctx, na * 4 + 4, "scan input"), out_a(ctx, na * 4 + 4, "scan output");
    Buffer in_b(ctx, nb * 4 + 4, "scan input"), counters(ctx, 12, "counters");
    ctx.write(in_a, a.data(), na * 4);
    ctx.write(in_b, b.data(), nb * 4);
    ctx.fill_u32(counters, 0xdeadbeef, 0, 3);
    const std::uint64_t before = ctx.kernel_launches();
    scan.exclusive_both({&in_a, &out_a, na, 2}, {&in_b, &in_b, nb, 0}, counters);
    const std::uint64_t launches = ctx.kernel_launches() - before;
    // An empty input launches nothing.
    if (na > 0 && nb > 0) CHECK((launches == 1) == (na <= 16 * tile && nb <= 16 * tile));
    std::vector<cl_uint> result_a(na), result_b(nb), totals(3), expected_a(na), expected_b(nb);
    ctx.read(out_a, result_a.data(), na * 4);
    ctx.read(in_b, result_b.data(), nb * 4);
    ctx.read(counters, totals.data(), 12);
    std::exclusive_scan(a.begin(), a.end(), expected_a.begin(), cl_uint(0));
    std::exclusive_scan(b.begin(), b.end(), expected_b.begin(), cl_uint(0));
    CHECK(result_a == expected_a);
    CHECK(result_b == expected_b);
    CHECK(totals[2] == std::accumulate(a.begin(), a.end(), cl_uint(0)));
    CHECK(totals[0] == std::accumulate(b.begin(), b.end(), cl_uint(0)));
    CHECK(totals[1] == 0xdeadbeef);
  }
}

TEST_CASE("exclusive scan equals the host's at millions of items", "[runtime][scan][slow]")
{
  for (std::size_t n : {std::size_t(1) << 22, (std::size_t(1) << 22) + 1, std::size_t(5'000'011)}) check_scan(n, false);
  // More tiles than one tile holds the sums of: those sums are scanned first, as a
  // scan of their own.
  const std::size_t tile = Scan(cstreams::test::device()).tile_items();
  check_scan(tile * tile + 1, true);
}

TEST_CASE("compaction keeps flagged items in order and counts past capacity", "[runtime][compaction][quick]")
{
  for (std::size_t n : sizes_around_powers_of_two(std::size_t(1) << 16)) check_compaction(n, 100);
  check_compaction(50000, 50);
  check_compaction(50000, 0);
}

TEST_CASE("compaction at millions of items", "[runtime][compaction][slow]")
{
  check_compaction(std::size_t(1) << 22, 100);
  check_compaction(3'000'017, 100);
  // More tiles than one tile holds the sums of: the placing launch takes scanned sums.
  const std::size_t tile = Scan(cstreams::test::device()).tile_items();
  check_compaction(tile * tile + 1, 50);
}

TEST_CASE("device reads land whole in host staging memory, which grows and moves", "[runtime][staging][quick]")
{
  auto& ctx = cstreams::test::device();
  HostStaging staging;
  for (std::size_t n : {1, 1000, 300000, 10}) {
    const auto values = random_values(n, std::uint32_t(n), 0xffffffffu);
    Buffer b(ctx, n * 4, "values");
    ctx.write(b, values.data(), n * 4);
    const void* before = staging.data();
    ensure_capacity(ctx, staging, n * 4, "test staging");
    INFO("n = " << n);
    CHECK(staging.bytes() >= n * 4);
    if (n == 10) CHECK(staging.data() == before);  // smaller reads reuse it
    ctx.read(b, staging.data(), n * 4);
    const auto* got = static_cast<const cl_uint*>(staging.data());
    CHECK(std::equal(values.begin(), values.end(), got));
  }
  HostStaging moved = std::move(staging);
  CHECK(staging.data() == nullptr);
  CHECK(moved.bytes() >= 300000 * 4);
}
