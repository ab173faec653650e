// The device pipeline through the public API, against the host reference: candidates in
// every front mode, contacts, bad input.
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

void check_candidates(const Scene& scene, std::size_t frame, const DetectorOptions& options)
{
  INFO("scene " << scene.name << ", frame " << frame << ", front " << to_string(options.front) << ", "
                << runtime::to_string(options.registration) << ", separation " << options.solver.min_separation);
  const Step step = load_step(scene, frame);
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  host.solver.min_separation = options.solver.min_separation;
  const Candidates expected = reference_broad_phase(step, host);
  Detector detector(cstreams::test::device(), describe(scene, frame), options);
  run_step(detector, step);
  const Candidates got = detector.candidates();
  CHECK(got.vf_count() == expected.vf_count());
  CHECK(got.ee_count() == expected.ee_count());
  CHECK(got == expected);
  CHECK(got.vf_count() > 0);
  // The same step again, the front now tracked from the last: the same pairs; and in
  // the steady state (a third time) nothing grows.
  run_step(detector, step);
  CHECK(detector.candidates() == expected);
  run_step(detector, step);
  for (const auto& p : detector.stats().run.passes) CHECK(p.reruns == 0);
}

}  // namespace

TEST_CASE("device candidates equal the host's in float boxes, in every front mode", "[detector][quick]")
{
  const Scene f = cstreams::test::cloth_funnel();
  DetectorOptions options;
  for (auto front : {FrontMode::none, FrontMode::exact, FrontMode::deferred}) {
    options.front = front;
    options.solver.min_separation = 0;
    check_candidates(f, 0, options);
  }
  // With a minimum separation the broad phase widens every box; the candidates do not
  // depend on the solver, and the conservative one would spend its time (seconds on two
  // CPU cores) on thousands of pairs that hover at that distance.
  options.front = FrontMode::exact;
  options.solver.min_separation = 1e-3;
  options.solver.solver = Solver::cubic;
  check_candidates(f, 0, options);
  options.solver.solver = Solver::conservative;

  // Multi-object scenes: cloth against a static sphere, and tumbling rigid bodies.
  options.solver.min_separation = 0;
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 40);
  check_candidates(cloth, 33, options);
  Scene bart = cstreams::test::generated_scene("bart", 12, 0);
  bart.ignored_pairs.emplace_back(0, 1);
  bart.ignored_pairs.emplace_back(2, 5);
  options.registration = runtime::Registration::lock_free;
  check_candidates(bart, 8, options);
}

// Two triangles in one plane move along x. Passing the same place a step apart, their
// swept boxes overlap while their features never come near: the decomposition leaves
// every feature pair out. Moving into each other, it keeps what meets.
TEST_CASE("the decomposition leaves out features that pass the same place at different times", "[detector][quick]")
{
  const std::vector<Vec3> a0{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, b0{{3, 0, 0}, {4, 0, 0}, {3, 1, 0}};
  const auto moved = [](std::vector<Vec3> x, double dx) {
    for (auto& p : x) p.x() += dx;
    return x;
  };
  SceneDescription scene;
  const std::uint32_t a = scene.add({"a", {{0, 1, 2}}, a0}), b = scene.add({"b", {{0, 1, 2}}, b0});
  Detector detector(cstreams::test::device(), scene);
  // a's tip reaches x = 3.5 at the end; b starts at x = 3 and moves on by 2.
  detector.set_step(a, a0, moved(a0, 2.5));
  detector.set_step(b, b0, moved(b0, 2));
  detector.detect();
  CHECK(detector.stats().triangle_pairs == 1);
  CHECK(detector.stats().vf_candidates == 0);
  CHECK(detector.stats().ee_candidates == 0);
  CHECK(detector.contacts().empty());

  detector.set_step(a, a0, moved(a0, 2.5));
  detector.set_step(b, b0, moved(b0, -2.5));
  detector.detect();
  CHECK(detector.stats().vf_candidates > 0);
  CHECK(detector.stats().ee_candidates > 0);
  CHECK(!detector.contacts().empty());
}


TEST_CASE("front modes, registrations and tiny capacities report identical contacts over many frames",
          "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  DetectorOptions options;
  options.front = FrontMode::none;
  const auto expected = run_frames(cloth, options, 10, 29);
  std::size_t total = 0;
  for (const auto& c : expected) total += c.size();
  CHECK(total > 100);

  DetectorStats exact_stats, deferred_stats;
  options.front = FrontMode::exact;
  CHECK(same(run_frames(cloth, options, 10, 29, &exact_stats), expected));
  options.front = FrontMode::deferred;
  // A budget far below the exact front's: it must be kept at coarser levels.
  options.front_budget_mb = double(exact_stats.front_pairs * 8 * 2) / 4 / (1024 * 1024);
  CHECK(same(run_frames(cloth, options, 10, 29, &deferred_stats), expected));
  CHECK(deferred_stats.front_pairs < exact_stats.front_pairs);
  CHECK(deferred_stats.front_level_cap < 2 * 20);

  options.front = FrontMode::exact;
  options.registration = runtime::Registration::lock_free;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
  options.registration = runtime::Registration::global_atomic;
  options.initial_capacity = 1;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
  options.registration = runtime::Registration::segmented_lock;
  options.front = FrontMode::deferred;
  CHECK(same(run_frames(cloth, options, 10, 29), expected));
}

// An exact front tracked over many steps climbs wherever boxes have moved apart, so that
// with no floor it is the very cut a search from the roots finds for the same step in
// the same trees (both detectors build their BVHs from the same first frame); a front
// that failed to climb would still find every contact, but grow step after step. Under
// the default floor (DetectorOptions::front_climb_levels) pairs that came apart in this
// sequence stop below it, so the tracked front holds more pairs, and the same contacts.
TEST_CASE("an exact front tracked over many steps is the one a search from the roots finds", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  constexpr std::size_t first = 10, last = 29;
  for (const bool floor : {false, true}) {
    INFO((floor ? "default floor" : "no floor"));
    DetectorOptions options;
    options.front = FrontMode::exact;
    if (!floor) options.front_climb_levels = std::numeric_limits<std::uint32_t>::max();
    Detector tracked(cstreams::test::device(), describe(cloth, first), options);
    for (std::size_t frame = first; frame < last; ++frame) run_step(tracked, load_step(cloth, frame));
    Detector searched(cstreams::test::device(), describe(cloth, first), options);
    run_step(searched, load_step(cloth, last - 1));
    CHECK(tracked.stats().front_pairs > 0);
    if (floor) CHECK(tracked.stats().front_pairs > searched.stats().front_pairs);
    else CHECK(tracked.stats().front_pairs == searched.stats().front_pairs);
    CHECK(searched.stats().triangle_pairs == tracked.stats().triangle_pairs);
    CHECK(same({searched.contacts()}, {tracked.contacts()}));
  }
}

TEST_CASE("a device that ends loops early reports the same contacts, searching from finer fronts",
          "[detector][quick]")
{
  // Mesa's llvmpipe ends a work-item's loops after 65535 trips in all. A context asked
  // for a far lower limit makes any device work as if it did: a search that runs out of
  // trips stops the step, which runs again from a front four times finer, and the
  // refinement's rounds go over exactly their items.
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  runtime::Context limited(filter_from_environment(), 0, 1024);
  REQUIRE(limited.loop_trip_limit() == 1024);
  DetectorOptions options;
  // Searches of 32 trips (a first exact front is already eight levels finer where boxes
  // overlap, and searches of 64 trips no longer ran out) need a front finer than the
  // default budget holds; a deferred front that cannot get fine enough within its
  // budget is an error (below).
  options.front_budget_mb = 64;
  for (auto front : {FrontMode::none, FrontMode::exact, FrontMode::deferred}) {
    INFO(to_string(front));
    options.front = front;
    unsigned retries = 0;
    CHECK(same(run_frames(cloth, options, 10, 16, nullptr, limited, &retries), run_frames(cloth, options, 10, 16)));
    CHECK(retries > 0);
  }
  options.front_budget_mb = 0.125;
  CHECK_THROWS_WITH(run_frames(cloth, options, 10, 11, nullptr, limited),
                    Catch::Contains("runs out of the device's loop trips") && Catch::Contains("within the front's budget"));
}


TEST_CASE("device contacts equal the solver's on the host's candidates, in both precisions", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 40);
  const Step step = load_step(cloth, 33);
  ReferenceOptions host;
  host.bounds = BoundsPrecision::single;
  const Candidates candidates = reference_broad_phase(step, host);
  for (auto precision : {Precision::single, Precision::double_}) {
    INFO(to_string(precision));
    DetectorOptions options;
    options.solver.precision = precision;
    const auto& device = cstreams::test::device().device();
    if (precision == Precision::double_ && !device.fp64) {
      CHECK_THROWS_WITH(Detector(cstreams::test::device(), describe(cloth, 33), options),
                        Catch::Contains("neither cl_khr_fp64 nor cl_amd_fp64"));
      continue;
    }
    Detector detector(cstreams::test::device(), describe(cloth, 33), options);
    run_step(detector, step);
    std::vector<Contact> expected;
    DeviceSolver elementary(cstreams::test::device(), options.solver);
    for (const auto& block : candidates.blocks) {
      std::vector<Query> vf, ee;
      for (const auto& p : block.vf) vf.push_back(vertex_face_query(step, block.object_a, block.object_b, p));
      for (const auto& p : block.ee) ee.push_back(edge_edge_query(step, block.object_a, block.object_b, p));
      const auto rv = elementary.solve(ContactKind::vertex_face, vf), re = elementary.solve(ContactKind::edge_edge, ee);
      for (std::size_t i = 0; i < vf.size(); ++i)
        if (rv[i].collides()) expected.push_back(make_contact(step, block.object_a, block.object_b, block.vf[i], rv[i].toi));
      for (std::size_t i = 0; i < ee.size(); ++i)
        if (re[i].collides()) expected.push_back(make_contact(step, block.object_a, block.object_b, block.ee[i], re[i].toi));
    }
    sort_canonical(expected);
    const auto& got = detector.contacts();
    REQUIRE(got.size() == expected.size());
    bool inter_object = false;
    for (std::size_t i = 0; i < got.size(); ++i) {
      CHECK(got[i].same_features(expected[i]));
      CHECK(got[i].toi == expected[i].toi);
      inter_object |= got[i].object_a != got[i].object_b;
    }
    CHECK(inter_object);

    // Earliest times per object, without the list: the list's minimum, rounded down.
    const auto earliest = detector.earliest_toi();
    for (std::uint32_t o = 0; o < cloth.objects.size(); ++o) {
      double first = 1;
      for (const auto& c : got)
        if (c.object_a == o || c.object_b == o) first = std::min(first, c.toi);
      CHECK(earliest[o] <= first);
      CHECK(earliest[o] >= double(std::nextafter(float(first), 0.0f)));
    }
    detector.detect(Report::earliest_toi);
    CHECK_THROWS_WITH(detector.contacts(), Catch::Contains("earliest"));
  }
}

// The sort's last pass on records made by hand, merged as one run (so in the order
// given): the host reads its output as Contacts, so every field must land where
// Contact keeps it, whatever bits the scene gives ids (fields that straddle words too),
// and a float time must widen to the very double the float is (subnormals too, which
// the kernel widens bit by bit).
TEST_CASE("contacts come back laid out as the host's Contact, times widened exactly", "[detector][quick]")
{
  runtime::Context& context = cstreams::test::device();
  context.programs().add_sources(ccd_kernel_sources());
  constexpr cl_uint block = 8;
  const float floats[] = {0.0f,
                          std::numeric_limits<float>::denorm_min(),
                          3e-40f,
                          std::nextafter(std::numeric_limits<float>::min(), 0.0f),
                          std::numeric_limits<float>::min(),
                          1e-7f,
                          0.7f,
                          1.0f};
  const double doubles[] = {0.0, std::numeric_limits<double>::denorm_min(), 1e-310, 0.3, 1.0 - 1e-16, 1.0};
  // (object bits, vertex bits): the widest ids, and fields that end mid-word.
  for (const auto& [object_bits, vertex_bits] : {std::pair<cl_uint, cl_uint>{31, 32}, {3, 13}, {0, 7}})
    for (const bool double_time : {false, true}) {
      INFO((double_time ? "double" : "single") << " times, " << object_bits << " object bits, " << vertex_bits
                                                << " vertex bits");
      const cl_uint time_bits = double_time ? 64 : 32;
      const cl_uint words = (1 + 2 * object_bits + 4 * vertex_bits + time_bits + 31) / 32;
      const auto below = [](cl_uint bits, std::uint64_t x) {
        return bits == 0 ? 0 : x & ((std::uint64_t(1) << bits) - 1);
      };
      std::vector<std::uint32_t> records;
      std::vector<Contact> expected;
      const std::size_t n = double_time ? std::size(doubles) : std::size(floats);
      REQUIRE(n <= block);  // one block: one run, merged with nothing
      for (std::size_t i = 0; i < n; ++i) {
        Contact c;
        c.kind = i % 2 ? ContactKind::edge_edge : ContactKind::vertex_face;
        c.object_a = std::uint32_t(below(object_bits, 0x7fffffffu - i));
        c.object_b = std::uint32_t(below(object_bits, 7 * i));
        c.v = {std::uint32_t(below(vertex_bits, 11 + i)), std::uint32_t(below(vertex_bits, 4000000000u - i)),
               std::uint32_t(below(vertex_bits, 13)), std::uint32_t(below(vertex_bits, 3000000000u + 5 * i))};
        std::uint64_t time_field;
        if (double_time) {
          std::memcpy(&time_field, &doubles[i], sizeof time_field);
          c.toi = doubles[i];
        } else {
          std::uint32_t bits;
          std::memcpy(&bits, &floats[i], sizeof bits);
          time_field = bits;
          c.toi = double(floats[i]);
        }
        expected.push_back(c);
        // Fields most significant first, bit by bit.
        std::vector<std::uint32_t> record(words, 0);
        std::size_t at = 0;
        const auto put = [&](std::uint64_t value, cl_uint bits) {
          for (cl_uint b = bits; b-- > 0; ++at)
            if (value >> b & 1) record[at / 32] |= 0x80000000u >> (at % 32);
        };
        put(i % 2, 1);
        put(c.object_a, object_bits);
        put(c.object_b, object_bits);
        for (const std::uint32_t v : c.v) put(v, vertex_bits);
        put(time_field, time_bits);
        records.insert(records.end(), record.begin(), record.end());
      }
      const runtime::Kernel merge_last = context.programs().kernel("ccd/contacts.cl", "cs_contacts_merged",
                                                                   "-DCS_SORT_WORDS=" + std::to_string(words));
      runtime::Buffer in(context, records.size() * sizeof(std::uint32_t), "records");
      runtime::Buffer out(context, n * sizeof(Contact), "contacts");
      context.write(in, records.data(), records.size() * sizeof(std::uint32_t));
      merge_last.set_args(in, cl_uint(n), block, block, cl_uint(double_time), object_bits, vertex_bits, out);
      merge_last.set_local(8, block * words * sizeof(cl_uint));
      context.launch(merge_last, context.work_group_size(), context.work_group_size());
      std::vector<Contact> got(n);
      context.read(out, got.data(), n * sizeof(Contact));
      for (std::size_t i = 0; i < n; ++i) {
        INFO("contact " << i);
        CHECK(got[i].kind == expected[i].kind);
        CHECK(got[i].object_a == expected[i].object_a);
        CHECK(got[i].object_b == expected[i].object_b);
        CHECK(got[i].v == expected[i].v);
        CHECK(got[i].toi == expected[i].toi);
      }
    }
}

TEST_CASE("bad input at the API is a clear error and the detector stays usable", "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 36, 30);
  Detector detector(cstreams::test::device(), describe(cloth, 30));
  const Step step = load_step(cloth, 30);
  run_step(detector, step);
  const std::vector<Contact> before = detector.contacts();
  REQUIRE(!before.empty());

  const std::uint32_t sheet = detector.object("cloth"), sphere = detector.object("sphere");
  CHECK_THROWS_WITH(detector.object("table"), Catch::Contains("no object named 'table'"));
  CHECK_THROWS_WITH(detector.set_positions(7, step.x1[0]), Catch::Contains("no object 7"));
  CHECK_THROWS_WITH(detector.set_positions(sphere, step.x1[sphere]), Catch::Contains("'sphere' is static"));
  auto fewer = step.x1[sheet];
  fewer.pop_back();
  CHECK_THROWS_WITH(detector.set_positions(sheet, fewer), Catch::Contains("vertices, not " + std::to_string(fewer.size())));
  // The step's start, where the cloth is not now, but for one coordinate.
  auto nan = step.x0[sheet];
  nan[17].y() = std::nan("");
  CHECK_THROWS_AS(detector.set_step(sheet, step.x0[sheet], nan), InputError);
  CHECK_THROWS_WITH(detector.set_step(sheet, step.x0[sheet], nan), Catch::Contains("'cloth': vertex 17"));
  CHECK_THROWS_WITH(detector.set_step(sheet, nan, step.x0[sheet]), Catch::Contains("'cloth': vertex 17"));
  CHECK_THROWS_WITH(detector.set_positions(sheet, nan), Catch::Contains("'cloth': vertex 17"));
  // Refused whole: the next step is the one a detector given none of them runs (the
  // cloth stays where the last step left it, touching the sphere).
  Detector clean(cstreams::test::device(), describe(cloth, 30));
  run_step(clean, step);
  clean.detect();
  detector.detect();
  REQUIRE(!clean.contacts().empty());
  check_same_contacts(detector.contacts(), clean.contacts());

  run_step(detector, step);
  REQUIRE(detector.contacts().size() == before.size());
  for (std::size_t i = 0; i < before.size(); ++i) CHECK(detector.contacts()[i].same_features(before[i]));

  SceneDescription broken;
  broken.add({"tri", {{0, 1, 1}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}});
  CHECK_THROWS_WITH(Detector(cstreams::test::device(), broken), Catch::Contains("object 'tri': face 0 repeats a vertex"));
  broken.objects[0].faces = {{0, 1, 3}};
  CHECK_THROWS_WITH(Detector(cstreams::test::device(), broken), Catch::Contains("face 0 uses vertex 3 of 3"));
}

// The front update's work-group searches from a list of eight pairs a work-item in local
// memory; children that find it full are searched on the work-item's own stack. Groups
// of four work-items fill their lists of 32 pairs at every search from seeds.
TEST_CASE("a front update whose groups' lists fill reports the contacts of one whose lists never do",
          "[detector][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 30, 30);
  runtime::Context tiny(filter_from_environment(), 4);
  REQUIRE(tiny.work_group_size() == 4);
  for (auto front : {FrontMode::none, FrontMode::exact}) {
    INFO(to_string(front));
    DetectorOptions options;
    options.front = front;
    CHECK(same(run_frames(cloth, options, 10, 14, nullptr, tiny), run_frames(cloth, options, 10, 14)));
  }
}

TEST_CASE("contacts do not depend on the work-group size a device runs", "[detector][quick]")
{
  // Devices differ in how many work-items a group may hold (rusticl on llvmpipe: 32);
  // the conservative refinement keeps 256 box positions a group whatever that number.
  const Scene scene = cstreams::test::cloth_funnel();
  const Step step = load_step(scene, 0);
  runtime::Context small(filter_from_environment(), 32);
  REQUIRE(small.work_group_size() == 32);
  for (Precision precision : {Precision::single, Precision::double_}) {
    if (precision == Precision::double_ && !small.device().fp64) continue;
    DetectorOptions options;
    options.solver.precision = precision;
    Detector a(cstreams::test::device(), describe(scene, 0), options), b(small, describe(scene, 0), options);
    run_step(a, step);
    run_step(b, step);
    check_same_contacts(a.contacts(), b.contacts());
  }
}
