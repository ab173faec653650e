// Benchmark of the runtime's primitives against Boost.Compute and a single global
// atomic counter, and of the sort, after what the host pays for a launch and a read.
// Prints Markdown tables (those in BENCHMARKS.md):
//   build/bin/bench_runtime [--sizes 1000000,4000000] [--repeat 15]
// Times are wall-clock medians after one warm-up, each repeat ending in clFinish (or
// the scheduler's own blocking counter read), so launches and host round trips count.
#include "../support/test_device.hpp"

#include <cstreams/runtime/baselines.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>

using namespace cstreams::runtime;

namespace {

double median(std::vector<double> values)
{
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

double median_ms(int repeat, const std::function<void()>& op)
{
  op();
  std::vector<double> ms;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    op();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  return median(std::move(ms));
}

void row(const char* op, const char* impl, std::size_t items, std::size_t outputs, double ms)
{
  std::printf("| %-12s | %-22s | %10zu | %10zu | %9.3f | %9.1f |\n", op, impl, items, outputs, ms,
              double(items) / ms / 1e3);
}

void require(bool ok, const std::string& what)
{
  if (!ok) throw Error("benchmark self-check failed: " + what);
}

double microseconds_since(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
}

// What a step of few items costs beyond its kernels: the host's time to queue a launch
// (binding one buffer, or eight like the pipeline's busier kernels), a launch of one
// group followed by a blocking 4-byte read (a stage's counter read with the device
// idle), and a read of 4 MiB into mapped host memory (as the contacts' is). Medians of
// 400 after as many warm-ups.
void host_costs(Context& ctx)
{
  // The file's emitting kernels need a registration to build with.
  const char* options = "-DCS_REGISTRATION=2";
  const Kernel one = ctx.programs().kernel("kernels/stream_test.cl", "test_plus_one", options);
  const Kernel eight = ctx.programs().kernel("kernels/stream_test.cl", "test_sum_into_first", options);
  const std::size_t wg = ctx.work_group_size(), items = wg, bytes = std::size_t(4) << 20;
  std::vector<Buffer> buffers;
  for (int b = 0; b < 8; ++b) {
    buffers.emplace_back(ctx, items * 4, "bench buffer");
    ctx.fill_u32(buffers.back(), 0, 0, items);
  }
  Buffer large(ctx, bytes, "bench read");
  ctx.fill_u32(large, 1, 0, bytes / 4);
  HostStaging staging(ctx, bytes, "bench read");
  const auto* host = static_cast<const cl_uint*>(staging.data());
  const auto bind_one = [&] { one.set_args(buffers[0], cl_uint(items)); };
  const auto bind_eight = [&] {
    eight.set_args(buffers[0], buffers[1], buffers[2], buffers[3], buffers[4], buffers[5], buffers[6], buffers[7],
                   cl_uint(items));
  };
  const auto median_us = [](const std::function<double()>& sample) {
    for (int r = 0; r < 400; ++r) sample();
    std::vector<double> us;
    for (int r = 0; r < 400; ++r) us.push_back(sample());
    return median(std::move(us));
  };
  // Twenty launches in a row, as a stage queues them; the finish is not timed.
  const auto queued = [&](const Kernel& k, const std::function<void()>& bind) {
    return median_us([&] {
      ctx.finish();
      const auto start = std::chrono::steady_clock::now();
      for (int l = 0; l < 20; ++l) {
        bind();
        ctx.launch(k, items, wg);
      }
      return microseconds_since(start) / 20;
    });
  };
  const double launch_one = queued(one, bind_one), launch_eight = queued(eight, bind_eight);
  const double round_trip = median_us([&] {
    ctx.finish();
    const auto start = std::chrono::steady_clock::now();
    bind_one();
    ctx.launch(one, items, wg);
    ctx.read(buffers[0], staging.data(), 4);
    return microseconds_since(start);
  });
  const double large_read = median_us([&] {
    ctx.finish();
    const auto start = std::chrono::steady_clock::now();
    ctx.read(large, staging.data(), bytes);
    return microseconds_since(start);
  });
  require(host[0] == 1 && host[bytes / 4 - 1] == 1, "the 4 MiB read returned other values than were written");
  std::printf("| host cost                               | median us |\n");
  std::printf("|-----------------------------------------|----------:|\n");
  std::printf("| queue a launch binding 1 buffer         | %9.2f |\n", launch_one);
  std::printf("| queue a launch binding 8 buffers        | %9.2f |\n", launch_eight);
  std::printf("| launch 1 group, then a 4-byte read      | %9.2f |\n", round_trip);
  std::printf("| read 4 MiB (%5.1f GB/s)                 | %9.2f |\n\n", double(bytes) / large_read * 1e-3,
              large_read);
}

}  // namespace

int main(int argc, char** argv)
try {
  CLI::App app{"cstreams runtime benchmark: scan, compaction, sort and stream registration"};
  std::vector<std::size_t> sizes{1'000'000, 4'000'000, 16'000'000};
  int repeat = 15;
  app.add_option("--sizes", sizes, "item counts")->delimiter(',');
  app.add_option("--repeat", repeat, "timed repeats after one warm-up")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  auto& ctx = cstreams::test::device();
  const auto& d = ctx.device();
  std::printf("Device: %s (%s, driver %s, %u compute units, work-group %zu)\n\n", d.name.c_str(),
              d.platform_name.c_str(), d.driver_version.c_str(), d.compute_units, ctx.work_group_size());
  host_costs(ctx);
  std::printf("| operation    | implementation         |      items |    output | median ms |  Mitems/s |\n");
  std::printf("|--------------|------------------------|-----------:|----------:|----------:|----------:|\n");

  Scan scan(ctx);
  BoostComputeBaselines boost(ctx);
  const Kernel flag_odd = ctx.programs().kernel("kernels/stream_test.cl", "test_flag_odd", "-DCS_REGISTRATION=2");

  for (std::size_t n : sizes) {
    std::mt19937 rng{std::uint32_t(n)};
    std::vector<cl_uint> values(n);
    for (auto& v : values) v = rng() % 1000;
    Buffer in(ctx, n * 4, "values"), out(ctx, n * 4, "out"), flags(ctx, n * 4, "flags"), counters(ctx, 4, "c");
    ctx.write(in, values.data(), n * 4);

    std::vector<cl_uint> ours(n), theirs(n);
    const double scan_ours = median_ms(repeat, [&] {
      scan.exclusive(in, out, n, counters, 0);
      ctx.finish();
    });
    ctx.read(out, ours.data(), n * 4);
    const double scan_boost = median_ms(repeat, [&] {
      boost.exclusive_scan(in, out, n);
      ctx.finish();
    });
    ctx.read(out, theirs.data(), n * 4);
    require(ours == theirs, "scan results differ from Boost.Compute's");
    row("scan", "cstreams", n, n, scan_ours);
    row("scan", "Boost.Compute", n, n, scan_boost);

    const std::size_t odd = std::size_t(std::count_if(values.begin(), values.end(), [](cl_uint v) { return v & 1; }));
    const double compact_ours = median_ms(repeat, [&] {
      flag_odd.set_args(in, cl_uint(n), flags);
      ctx.launch(flag_odd, n, ctx.work_group_size());
      scan.compact(in, 1, flags, n, out, n, counters, 0);
      ctx.finish();
    });
    cl_uint kept = 0;
    ctx.read(counters, &kept, 4);
    require(kept == odd, "compaction kept the wrong number of items");
    std::size_t boost_kept = 0;
    const double compact_boost = median_ms(repeat, [&] {
      boost_kept = boost.copy_if_odd(in, out, n);
      ctx.finish();
    });
    require(boost_kept == odd, "Boost.Compute copy_if kept the wrong number of items");
    row("compaction", "cstreams (flag+scan)", n, odd, compact_ours);
    row("compaction", "Boost.Compute copy_if", n, odd, compact_boost);

    // Records shaped like contacts (contacts.cl): two small object words, four vertex
    // ids and a time. The block sort and the merge passes are timed apart (device time).
    {
      constexpr std::size_t words = 8;
      std::vector<cl_uint> records(n * words);
      for (std::size_t i = 0; i < n; ++i) {
        cl_uint* r = &records[i * words];
        r[0] = rng() % 2;
        r[1] = r[0] + rng() % 2;
        for (std::size_t w = 2; w < words; ++w) r[w] = rng() % (w < 6 ? 1'000'000 : 0xffffffffu);
      }
      Buffer unsorted(ctx, records.size() * 4, "records"), sorting(ctx, records.size() * 4, "sorting");
      ctx.write(unsorted, records.data(), records.size() * 4);
      Sorter sorter(ctx, words);
      std::vector<double> blocks_ms, merges_ms;
      const Buffer* sorted = nullptr;
      const double ms = median_ms(repeat, [&] {
        ctx.copy(unsorted, sorting, records.size() * 4);
        Timeline timeline;
        sorted = &sorter.sort(sorting, n, &timeline);
        const auto entries = timeline.resolve();
        blocks_ms.push_back(entries.empty() ? 0 : entries.front().nanoseconds * 1e-6);
        double merges = 0;
        for (std::size_t e = 1; e < entries.size(); ++e) merges += entries[e].nanoseconds * 1e-6;
        merges_ms.push_back(merges);
      });
      std::vector<cl_uint> back(records.size());
      ctx.read(*sorted, back.data(), back.size() * 4);
      std::vector<std::array<cl_uint, words>> expected(n);
      std::memcpy(expected.data(), records.data(), records.size() * 4);
      std::sort(expected.begin(), expected.end());
      require(std::memcmp(expected.data(), back.data(), back.size() * 4) == 0, "sorted records differ from the host's sort");
      row("sort 8 words", "cstreams (wall)", n, n, ms);
      row("sort 8 words", "block sort (device)", n, n, median(blocks_ms));
      row("sort 8 words", "merge passes (device)", n, n, median(merges_ms));
    }

    for (auto registration : {Registration::global_atomic, Registration::segmented_lock, Registration::lock_free}) {
      StreamGraph g;
      auto input = g.fixed("values", 4, n);
      auto pairs = g.variable("pairs", 8, 1);
      g.pass("expand", {"kernels/stream_test.cl", "test_expand"})
          .launch_over(input)
          .emit(pairs)
          .arg(buffer_of(input))
          .arg(count_of(input));
      Scheduler scheduler(ctx, g, {registration, false});
      scheduler.upload(input, values);
      const double ms = median_ms(repeat, [&] { scheduler.run(); });
      const std::string name = registration == Registration::global_atomic
                                   ? "single atomic counter"
                                   : std::string(to_string(registration));
      row("registration", name.c_str(), n, scheduler.count(pairs), ms);
    }
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_runtime: %s\n", e.what());
  return 1;
}
