// Earliest times of impact: alone (Report::earliest_toi) they equal the full list's, and
// single precision takes positions that are floats as exact.
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

namespace {

// The conservative refinement's pass of a step (no name where the step had none).
runtime::PassStats refinement(const DetectorStats& stats)
{
  for (const auto& p : stats.run.passes)
    if (p.name == "refine open queries") return p;
  return {};
}

// `scene`'s positions in `frame`, moved by `shift`.
std::vector<Vec3> shifted(const Scene& scene, std::uint32_t object, std::size_t frame, const Vec3& shift)
{
  std::vector<Vec3> x = scene.positions(object, frame);
  for (Vec3& p : x) p += shift;
  return x;
}

// Steps `scene` from frame 0 through two detectors, one reporting contacts and one
// (on `earliest_device`) only the earliest times, and checks that they give the same
// times, object by object. `start` is where the first step starts from (frame 0's
// positions where empty).
struct EarliestRun {
  std::uint64_t all_boxes = 0, earliest_boxes = 0;  // refined, over the steps
  std::size_t at_zero = 0, later = 0;               // objects' earliest times: 0, and in (0, 1)
  std::size_t all_contacts = 0, earliest_contacts = 0;  // settled, over the steps
  std::size_t earliest_peak = 0;                    // the most the earliest times' device held
  unsigned sliced = 0;                              // their steps that ran in slices
};

EarliestRun compare_earliest(const Scene& scene, std::size_t steps, const DetectorOptions& options,
                             runtime::Context& earliest_device = cstreams::test::device(),
                             const SceneDescription& start = {})
{
  const SceneDescription first = start.objects.empty() ? describe(scene, 0) : start;
  Detector all(cstreams::test::device(), first, options);
  Detector earliest(earliest_device, first, options);
  EarliestRun run;
  for (std::size_t frame = 0; frame < steps; ++frame) {
    INFO("frame " << frame);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].kind != ObjectKind::static_) {
        all.set_positions(o, scene.positions(o, frame + 1));
        earliest.set_positions(o, scene.positions(o, frame + 1));
      }
    all.detect();
    earliest.detect(Report::earliest_toi);
    const std::vector<double> expected = all.earliest_toi();
    CHECK(earliest.earliest_toi() == expected);
    run.at_zero += std::count(expected.begin(), expected.end(), 0.0);
    run.later += std::count_if(expected.begin(), expected.end(), [](double t) { return t > 0 && t < 1; });
    run.all_boxes += refinement(all.stats()).list_items;
    run.earliest_boxes += refinement(earliest.stats()).list_items;
    run.all_contacts += all.stats().contacts;
    run.earliest_contacts += earliest.stats().contacts;
    run.earliest_peak = std::max(run.earliest_peak, earliest.stats().peak_bytes);
    run.sliced += earliest.stats().run.slices > 1;
  }
  UNSCOPED_INFO("boxes " << run.all_boxes << " against " << run.earliest_boxes << "; earliest times at 0: "
                         << run.at_zero << ", later: " << run.later);
  return run;
}

}  // namespace

// Report::earliest_toi lets the conservative refinement give up the queries that can no
// longer hold an object's earliest time (refine.cl): where a contact found for each of
// its objects is earlier than the query's answer can be (bodies colliding at different
// times), or where its objects already touch at time 0 (a cloth with a vertex on one
// of its faces at the start). The cubic test skips the pairs whose features stay apart
// until then (narrow_phase_pairs.cl). The times must stay the full list's, object by
// object.
TEST_CASE("earliest times alone equal the full list's, object by object, with less refinement", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 24, 40);
  const Scene funnel = cstreams::test::cloth_funnel();
  // The funnel starting with one vertex on a vertex of its last face: a contact at 0.
  SceneDescription touching_start = describe(funnel, 0);
  {
    std::vector<Vec3>& x = touching_start.objects[0].positions;
    const auto& face = touching_start.objects[0].faces.back();
    std::uint32_t moved = 0;
    while (moved == face[0] || moved == face[1] || moved == face[2]) ++moved;
    x[moved] = x[face[0]];
  }
  for (auto solver : {Solver::conservative, Solver::cubic})
    for (auto precision : {Precision::single, Precision::double_}) {
      INFO(to_string(solver) << ", " << to_string(precision));
      if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
      DetectorOptions options;
      options.solver.solver = solver;
      options.solver.precision = precision;
      const EarliestRun apart = compare_earliest(bodies, bodies.frame_count() - 1, options);
      CHECK(apart.later > 0);
      if (solver == Solver::cubic) {
        // Which pairs skip depends on which contacts the device found first (pocl: the
        // bodies' 42,612 contacts over their steps settle 26,495), so only the times are
        // checked; the skip itself is tested in test_narrow_phase.
        const EarliestRun touching = compare_earliest(funnel, 1, options, cstreams::test::device(), touching_start);
        CHECK(touching.at_zero == 1);
        CHECK(apart.earliest_contacts <= apart.all_contacts);
        continue;
      }
      // In double the bodies' queries start from the times they can be coplanar at, and
      // settle in a few rounds, before contacts found elsewhere give any of them up.
      if (precision == Precision::single) CHECK(apart.earliest_boxes < apart.all_boxes);
      else CHECK(apart.earliest_boxes <= apart.all_boxes);
      if (precision == Precision::single) {
        const EarliestRun touching = compare_earliest(funnel, 1, options, cstreams::test::device(), touching_start);
        CHECK(touching.at_zero == 1);
        // A vertex on a vertex is a contact no float enclosure proves (proof.h): with
        // escalation, only proven contacts give queries up, and this one gives none.
        DetectorOptions in_float = options;
        in_float.solver.escalate = false;
        const EarliestRun float_only =
            compare_earliest(funnel, 1, in_float, cstreams::test::device(), touching_start);
        CHECK(float_only.at_zero == 1);
        CHECK(float_only.earliest_boxes < float_only.all_boxes / 4);
      }
    }
}

namespace {

// One step of `scene` from frame 0, every position moved by `shift`.
std::vector<Contact> step_contacts(const Scene& scene, const Vec3& shift, Precision precision)
{
  DetectorOptions options;
  options.solver.precision = precision;
  options.solver.escalate = false;
  SceneDescription start = describe(scene, 0);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) start.objects[o].positions = shifted(scene, o, 0, shift);
  Detector detector(cstreams::test::device(), start, options);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) detector.set_positions(o, shifted(scene, o, 1, shift));
  detector.detect();
  return detector.contacts();
}

double earliest(const std::vector<Contact>& contacts)
{
  double t = 1;
  for (const Contact& c : contacts) t = std::min(t, c.toi);
  return t;
}

}  // namespace

// Positions that are floats are the input itself: single precision bounds them exactly
// (round_to_float, CcdStreams::exact_floats) rather than within half an ulp. The
// funnel's frames are floats: in single precision it must then report every pair that
// double precision does, no later, and few more. The same floats taken as rounded (the
// positions moved by 2^-40, under half an ulp) report more than twice as many where no
// contact goes to double (escalation off: test_escalation.cpp has it on).
TEST_CASE("single precision takes positions that are floats as the input itself", "[detector][quick]")
{
  const Scene funnel = cstreams::test::cloth_funnel();
  const std::vector<Contact> floats = step_contacts(funnel, Vec3::Zero(), Precision::single);
  const std::vector<Contact> rounded = step_contacts(funnel, {0x1p-40, 0, 0}, Precision::single);
  INFO(floats.size() << " contacts from floats, " << rounded.size() << " from the same floats rounded");
  CHECK(earliest(floats) > 0);
  CHECK(2 * floats.size() < rounded.size());
  if (!cstreams::test::device().device().fp64) return;
  const std::vector<Contact> exact = step_contacts(funnel, Vec3::Zero(), Precision::double_);
  INFO(exact.size() << " in double");
  REQUIRE(!exact.empty());
  for (const Contact& e : exact) {
    const auto found = std::find_if(floats.begin(), floats.end(), [&](const Contact& c) { return c.same_features(e); });
    REQUIRE(found != floats.end());
    // No later than the first contact, which is no later than double's time moved
    // forward by the tolerance (by which it may have been moved back, rounded down).
    CHECK(found->toi <= e.toi + 1.001 * SolverOptions().tolerance);
  }
  CHECK(10 * floats.size() <= 11 * exact.size());
}

// A first step sizes the refinement's work lists from its queries, and the funnel's
// late rounds outgrow them: the round that overflows runs again once they have grown
// (a replay), and the step must refine exactly as one whose lists were large enough
// from the start, the same step run again: the same boxes, rounds and contacts. A
// quiet step after them needs far smaller lists, and holds no more.
TEST_CASE("a refinement whose work list overflows goes on as one that never did", "[detector][quick]")
{
  const Scene funnel = cstreams::test::cloth_funnel();
  // Double precision settles the funnel in rounds that fit its first lists; in single
  // precision, positions that are not floats (moved by 2^-40) refine many more boxes.
  const Vec3 shift(0x1p-40, 0, 0);
  DetectorOptions options;
  options.solver.precision = Precision::single;
  Detector detector(cstreams::test::device(), describe(funnel, 0), options);
  std::vector<std::vector<Contact>> contacts;
  std::vector<runtime::PassStats> refined;
  for (int run = 0; run < 2; ++run) {
    for (std::uint32_t o = 0; o < funnel.objects.size(); ++o)
      if (funnel.objects[o].kind != ObjectKind::static_)
        detector.set_step(o, shifted(funnel, o, 0, shift), shifted(funnel, o, 1, shift));
    detector.detect();
    contacts.push_back(detector.contacts());
    refined.push_back(refinement(detector.stats()));
    REQUIRE(refined.back().name == "refine open queries");
  }
  CHECK(refined[0].reruns > 0);
  CHECK(refined[1].reruns == 0);
  CHECK(refined[0].list_items == refined[1].list_items);
  CHECK(refined[0].rounds == refined[1].rounds);
  CHECK(!contacts[0].empty());
  CHECK(same({contacts[0]}, {contacts[1]}));
  // A step at rest refines little: the lists grown for the funnel go back.
  for (std::uint32_t o = 0; o < funnel.objects.size(); ++o)
    if (funnel.objects[o].kind != ObjectKind::static_)
      detector.set_step(o, funnel.positions(o, 0), funnel.positions(o, 0));
  detector.detect();
  const runtime::PassStats at_rest = refinement(detector.stats());
  REQUIRE(at_rest.name == "refine open queries");
  INFO(refined[1].scratch_bytes << " bytes of work lists and state after the funnel's step, " << at_rest.scratch_bytes
                                << " after one at rest");
  CHECK(4 * at_rest.scratch_bytes < refined[1].scratch_bytes);
}

// Short of memory, a step runs the passes from the one that does not fit onwards in
// slices of its input, each refining its own queries: a slice's contacts give up only
// queries of the same slice, and the times must still be the full list's.
TEST_CASE("earliest times alone stay the full list's when a memory budget runs steps in slices", "[detector][quick]")
{
  const Scene bodies = cstreams::test::generated_scene("n-body", 24, 40);
  const std::size_t steps = bodies.frame_count() - 1;
  const DetectorOptions options;
  runtime::Context unlimited(filter_from_environment());
  const std::size_t peak = compare_earliest(bodies, steps, options, unlimited).earliest_peak;
  unsigned sliced = 0;
  for (const double share : {0.8, 0.75, 0.7, 0.6, 0.5}) {
    runtime::Context limited(filter_from_environment());
    limited.set_memory_limit(std::size_t(share * double(peak)));
    INFO("budget " << share << " of the unbudgeted peak, " << peak << " bytes");
    try {
      sliced += compare_earliest(bodies, steps, options, limited).sliced;
    } catch (const runtime::DeviceMemoryExhausted&) {
      CHECK(share < 0.8);
    }
  }
  CHECK(sliced > 0);
}

// Split into their connected components (n-body's balls, the armadillo and its
// rollers), the real steps have many objects and contacts at many times.
TEST_CASE("earliest times alone equal the full list's on real steps split into their bodies", "[detector][slow]")
{
  for (const auto& s : {cstreams::test::real_steps[3], cstreams::test::real_steps[2]}) {
    const std::string dir = cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/frames/");
    const Scene scene = scene_from_frames({dir + s.frame0, dir + s.frame1}, true);
    INFO("scene " << s.scene << ", " << scene.objects.size() << " objects");
    REQUIRE(scene.objects.size() > 1);
    for (auto precision : {Precision::single, Precision::double_}) {
      if (precision == Precision::double_ && !cstreams::test::device().device().fp64) continue;
      INFO(to_string(precision));
      DetectorOptions options;
      options.solver.precision = precision;
      const EarliestRun run = compare_earliest(scene, 1, options);
      CHECK(run.at_zero + run.later > 1);
      // In double, armadillo-rollers' queries start from the times they can be coplanar
      // at and settle in two rounds, before contacts found elsewhere give any of them up.
      if (precision == Precision::single) CHECK(run.earliest_contacts < run.all_contacts);
      else CHECK(run.earliest_contacts <= run.all_contacts);
    }
  }
}
