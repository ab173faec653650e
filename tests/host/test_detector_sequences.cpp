// A detector over a sequence of steps: its memory settles, and positions given ahead
// or in any order give the contacts of positions set before each step.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"
#include "../support/test_scenes.hpp"
#include "detector_steps.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>

using namespace cstreams;
using namespace cstreams::test;

TEST_CASE("no step of cloth-ball peaks above 200 MiB, nor far above what a settled one holds", "[detector][slow]")
{
  // Issue 12 asks for 200 MiB on cloth-ball, which settled cubic steps hold (161 MiB on
  // pocl and the H100). The first step, searched from the roots, sized its candidates'
  // segments for two of each a triangle pair (201 MiB); the third, the first with a
  // step arena, ran beside the contact readback's scratch of the step before (203 MiB).
  // The first steps, whose segments no run has planned yet, peak at up to 172 MiB, 7%
  // above a settled step.
  const Scene scene = cstreams::test::cloth_ball();
  const Step step = load_step(scene, 0);
  runtime::Context context(filter_from_environment());
  DetectorOptions options;
  options.solver.solver = Solver::cubic;
  Detector detector(context, describe(scene, 0), options);
  std::vector<std::size_t> peaks;
  for (int repeat = 0; repeat < 5; ++repeat) {
    run_step(detector, step);
    peaks.push_back(detector.stats().peak_bytes);
  }
  const std::size_t held = context.memory_in_use();
  for (std::size_t k = 0; k < peaks.size(); ++k) {
    INFO("step " << k << " peaks at " << peaks[k] << " bytes; settled, the detector holds " << held);
    CHECK(peaks[k] <= std::size_t(200) << 20);
    CHECK(double(peaks[k]) <= 1.1 * double(held));
  }
}

TEST_CASE("a detector's memory settles at what its steps plan, and no step peaks far above it", "[detector][quick]")
{
  // The first step searches from seeds; the second is the first from a whole front,
  // before any run has planned its registration segments; later steps plan from the
  // last. A step repeated, as a benchmark runs it, on a context of its own so that the
  // high-water mark and what is in use are the detector's.
  const Scene scene = cstreams::test::cloth_funnel();
  const Step step = load_step(scene, 0);
  for (Solver solver : {Solver::cubic, Solver::conservative}) {
    runtime::Context context(filter_from_environment());
    DetectorOptions options;
    options.solver.solver = solver;
    Detector detector(context, describe(scene, 0), options);
    std::vector<std::size_t> peaks, held;
    for (int repeat = 0; repeat < 5; ++repeat) {
      run_step(detector, step);
      peaks.push_back(detector.stats().peak_bytes);
      held.push_back(context.memory_in_use());
    }
    INFO(to_string(solver) << ": held " << held.back() << " bytes; peaks " << peaks[0] << " " << peaks[1] << " "
                           << peaks[2]);
    CHECK(held[4] == held[3]);
    CHECK(peaks[4] == held[4]);  // a settled step allocates nothing
    // Segments sized for four items a front pair, as they were, took 2.7 times what a
    // settled step then held, which has since held less (segments an eighth over their
    // plan, not a quarter) where a first step, unplanned, does not: on rusticl, whose
    // loops end early and whose first step searches again from a finer front, that
    // step peaks at 2.4 times.
    for (std::size_t peak : peaks) CHECK(double(peak) <= 2.5 * double(held.back()));
    // The second step's segments, sized from what the first emitted rather than from
    // the items a front pair is expected to emit, hold what later steps hold (10-12% more
    // on pocl when they were not). On rusticl, whose groups are of 32 work-items, the
    // first step's plan (of the seeds' few groups) leaves more of the second step's
    // groups short, and their spills peak above a settled step: 18.5 MB against 13.9 on
    // the funnel. Its first step had searched again from finer fronts until the front
    // update's work-groups searched together, and peaked at 43 MB (the second at 22.3,
    // settled at 17.6).
    const double second = context.loop_trip_limit() != 0 ? 1.35 : 1.05;
    CHECK(double(peaks[1]) <= second * double(std::max(peaks[0], held.back())));
  }
}

// Replaying frames, the next step's ends upload while a step runs (upload_ahead). The
// contacts must be those of the same positions set before each step: with one body
// given new positions only every other step (it stays in between), an upload replaced
// by a second one and one by set_positions(), and bad ones refused without a trace.
// The static ground and the second half's frames are rounded to floats, which single
// precision takes as the input itself once every position a step reads is a float
// (CcdStreams::exact_floats).
TEST_CASE("positions uploaded ahead give the contacts of positions set before each step", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 12, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  // Through the library's rounding: GCC 12's -O3 leaves the last vertex's y and z
  // unrounded in a loop of p[k] = double(float(p[k])).
  const auto to_floats = [](std::vector<Vec3>& x) {
    const std::vector<float> f = to_float_positions(x);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
  };
  SceneDescription start = describe(bodies, 0);
  for (auto& object : start.objects)
    if (object.kind == ObjectKind::static_) to_floats(object.positions);
  const auto frame = [&](std::size_t f) { return load_step(bodies, std::min(f, steps - 1)); };
  const auto ends = [&](std::size_t step) {  // step k ends at frame k
    auto x = frame(step - 1).x1;
    if (2 * step > steps)
      for (auto& object : x) to_floats(object);
    return x;
  };
  const std::uint32_t lazy = 1, replaced = 2;
  const auto moves = [&](std::uint32_t o, std::size_t step) {
    return bodies.objects[o].kind != ObjectKind::static_ && (o != lazy || step % 2 == 0);
  };
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector set(cstreams::test::device(), start, options), ahead(cstreams::test::device(), start, options);
    const auto first = ends(1);
    for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
      if (moves(o, 1)) ahead.set_positions(o, first[o]);
    std::size_t contacts = 0;
    for (std::size_t step = 1; step <= steps; ++step) {
      INFO("step " << step);
      const auto now = ends(step);
      for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
        if (moves(o, step)) set.set_positions(o, now[o]);
      // Read while the step runs: kept until it returns.
      const auto next = ends(std::min(step + 1, steps));
      if (step < steps) {
        ahead.upload_ahead(0, now[0]);  // replaced below
        for (std::uint32_t o = 0; o < bodies.objects.size(); ++o)
          if (moves(o, step + 1)) ahead.upload_ahead(o, next[o]);
        CHECK_THROWS_AS(ahead.upload_ahead(0, std::vector<Vec3>(3)), InputError);
        std::vector<Vec3> broken = next[0];
        broken[0][1] = std::numeric_limits<double>::quiet_NaN();
        CHECK_THROWS_AS(ahead.upload_ahead(0, broken), InputError);
      }
      if (step == 3) {
        const auto before = ends(step - 1);
        set.set_positions(replaced, before[replaced]);
        ahead.set_positions(replaced, before[replaced]);
      }
      set.detect();
      ahead.detect();
      check_same_contacts(set.contacts(), ahead.contacts());
      contacts += set.contacts().size();
    }
    CHECK(contacts > 0);
  }
}

// A repeated step uploads both its ends ahead (upload_ahead(object, start, end)), and
// a step that follows one uploaded ahead starts from its end without a copy: runs of
// each step, uploaded ahead, must give the contacts and earliest times of the same
// positions set before each run. One body is given only its ends, so it starts where
// the run before left it.
TEST_CASE("a repeated step uploaded ahead, both ends, gives the contacts of its ends set before each run",
          "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 6, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const std::uint32_t ends_only = 1;
  const auto moving = [&](std::uint32_t o) { return bodies.objects[o].kind != ObjectKind::static_; };
  const unsigned runs = 3;
  // The positions of every run, in order: each step `runs` times.
  std::vector<Step> order;
  for (std::size_t f = 0; f < steps; ++f)
    for (unsigned r = 0; r < runs; ++r) order.push_back(load_step(bodies, f));
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector set(cstreams::test::device(), describe(bodies, 0), options),
        ahead(cstreams::test::device(), describe(bodies, 0), options);
    std::size_t contacts = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      INFO("run " << k);
      const Step& now = order[k];
      for (std::uint32_t o = 0; o < bodies.objects.size(); ++o) {
        if (!moving(o)) continue;
        if (o == ends_only) set.set_positions(o, now.x1[o]);
        else set.set_step(o, now.x0[o], now.x1[o]);
        if (k == 0) ahead.set_positions(o, now.x1[o]);
        if (k + 1 == order.size()) continue;
        const Step& next = order[k + 1];
        if (o == ends_only) ahead.upload_ahead(o, next.x1[o]);
        else ahead.upload_ahead(o, next.x0[o], next.x1[o]);
      }
      if (k + 1 < order.size())
        CHECK_THROWS_AS(ahead.upload_ahead(0, order[k + 1].x0[0], std::vector<Vec3>(3)), InputError);
      const Report report = k % 4 == 3 ? Report::earliest_toi : Report::contacts;
      set.detect(report);
      ahead.detect(report);
      CHECK(set.earliest_toi() == ahead.earliest_toi());
      if (report == Report::earliest_toi) continue;
      check_same_contacts(set.contacts(), ahead.contacts());
      contacts += set.contacts().size();
    }
    CHECK(contacts > 0);
  }
}

// Positions given object by object are gathered and go up as the step starts, one write
// per run of adjacent objects. Given in slot order they make one run; given backwards,
// some twice (the first a wrong frame) and some through set_step(), every object is a
// run of its own: both must give the same contacts, step after step.
TEST_CASE("positions given in any order, some twice, give the contacts of positions given in order",
          "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 8, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const auto objects = std::uint32_t(bodies.objects.size());
  const auto moving = [&](std::uint32_t o) { return bodies.objects[o].kind != ObjectKind::static_; };
  Detector in_order(cstreams::test::device(), describe(bodies, 0)),
      scrambled(cstreams::test::device(), describe(bodies, 0));
  std::size_t contacts = 0;
  for (std::size_t frame = 0; frame < steps; ++frame) {
    INFO("step from frame " << frame);
    const Step step = load_step(bodies, frame);
    const Step wrong = load_step(bodies, (frame + 3) % steps);
    for (std::uint32_t o = 0; o < objects; ++o)
      if (moving(o)) in_order.set_positions(o, step.x1[o]);
    for (std::uint32_t o = objects; o-- > 0;) {
      if (!moving(o)) continue;
      if (o % 3 == 0) scrambled.set_positions(o, wrong.x1[o]);
      if (o % 2 == 0) scrambled.set_step(o, step.x0[o], step.x1[o]);
      else scrambled.set_positions(o, step.x1[o]);
    }
    in_order.detect();
    scrambled.detect();
    check_same_contacts(in_order.contacts(), scrambled.contacts());
    contacts += in_order.contacts().size();
  }
  CHECK(contacts > 0);
}

// Contacts past the pinned memory (DetectorOptions::pinned_contact_bytes) are read
// through it in chunks, half of it at a time, into ordinary memory. With the median
// step's contacts pinned, some steps read at once and the others in chunks (the last
// one short), in turn: each step's contacts must be those read at once.
TEST_CASE("contacts past the pinned memory come back in chunks as they would at once", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 12, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const auto at_once = run_frames(bodies, DetectorOptions{}, 0, steps);
  std::vector<std::size_t> sizes;
  for (const auto& c : at_once) sizes.push_back(c.size());
  std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
  const std::size_t pinned = sizes[sizes.size() / 2];
  DetectorOptions chunked;
  chunked.pinned_contact_bytes = pinned * sizeof(Contact);
  CHECK(same(at_once, run_frames(bodies, chunked, 0, steps)));
  // Steps past the pinned memory, each after one within it (whose read gave back the
  // ordinary memory), in chunks of about half the pinned contacts.
  const auto fresh_pages = [&](const auto& a, const auto& b) { return a.size() <= pinned && b.size() > pinned; };
  CHECK(std::adjacent_find(at_once.begin(), at_once.end(), fresh_pages) != at_once.end());
  CHECK(pinned > 100);
  // Each chunk's wait counts as a blocking read: a step past the pinned memory takes
  // at least two more than the same step read at once.
  const auto past = std::find_if(at_once.begin(), at_once.end(), [&](const auto& c) { return c.size() > pinned; });
  REQUIRE(past != at_once.end());
  const Step step = load_step(bodies, std::size_t(past - at_once.begin()));
  Detector whole(cstreams::test::device(), describe(bodies, 0));
  Detector chunks(cstreams::test::device(), describe(bodies, 0), chunked);
  run_step(whole, step);
  run_step(chunks, step);
  check_same_contacts(whole.contacts(), chunks.contacts());
  CHECK(chunks.stats().blocking_reads >= whole.stats().blocking_reads + 2);
}
