// Single precision's escalation (SolverOptions::escalate, refine.cl's CS_ESCALATE): a
// contact the float enclosure cannot prove an exact zero for runs again in double, that
// query alone. It must remove the contacts float's rounding invents and the times of 0
// it gives where the exact one is positive, and never lose a contact or report one late.
#include "narrow_phase_cases.hpp"

#include <cstreams/detector.hpp>
#include <cstreams/scene/scene.hpp>

#include <fstream>

using namespace cstreams;
using namespace cstreams::test;

namespace {

bool has_fp64() { return cstreams::test::device().device().fp64; }

SolverOptions without_escalation()
{
  SolverOptions o = conservative(Precision::single);
  o.escalate = false;
  return o;
}

// The earliest exact time of impact of a real step's queries of both kinds
// (toi-ground-truth/, 40 digits a time).
long double exact_earliest(const std::string& scene, const std::string& step)
{
  long double earliest = 2;
  for (const char* kind : {"vf", "ee"}) {
    const std::string path = benchmark_path("toi-ground-truth/" + scene + "_" + step + kind + "_toi.csv");
    std::ifstream in(path);
    REQUIRE(in);
    std::string line;
    std::getline(in, line);  // the header
    while (std::getline(in, line)) earliest = std::min(earliest, std::stold(line.substr(line.rfind(',') + 1)));
  }
  return earliest;
}

// One step of a real scene's two frames, as `cstreams run A.ply B.ply` makes it: the
// earliest time of its contacts, or of its objects with Report::earliest_toi.
double step_earliest(const RealStep& s, const SolverOptions& solver, Report report)
{
  const std::string dir = benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/frames/");
  const Scene scene = scene_from_frames({dir + s.frame0, dir + s.frame1}, false);
  DetectorOptions options;
  options.solver = solver;
  Detector detector(cstreams::test::device(), describe(scene, 0), options);
  detector.set_positions(0, scene.positions(0, 1));
  detector.detect(report);
  if (report == Report::earliest_toi) return detector.earliest_toi()[0];
  double t = 1;
  for (const Contact& c : detector.contacts()) t = std::min(t, c.toi);
  return t;
}

}  // namespace

// A vertex that slides a hair (2^-40) above a face far from the origin: its float
// coordinates' one-ulp intervals reach the face, so the float enclosure answers a
// contact; in double it is apart. A vertex that passes through the same face collides,
// no later than it does.
TEST_CASE("in single precision, a near miss under float's rounding is decided in double", "[narrow][quick]")
{
  const Vec3 far(1024, 1024, 1024), in(0.25, 0.25, 0), above(0, 0, 0x1p-13 + 0x1p-40);
  const Query slides = query({far + in + above, far + A, far + B, far + C},
                             {far + in + above + Vec3(0.125, 0, 0), far + A, far + B, far + C});
  // Through the face at t = 1/3 exactly: from 1/3 above it to 2/3 below.
  const Query passes = query({far + in + Vec3(0, 0, 1.0 / 3), far + A, far + B, far + C},
                             {far + in - Vec3(0, 0, 2.0 / 3), far + A, far + B, far + C});
  DeviceSolver in_float(cstreams::test::device(), without_escalation());
  DeviceSolver escalating(cstreams::test::device(), conservative(Precision::single));
  CHECK(in_float.solve(ContactKind::vertex_face, {slides})[0].collides());
  const auto through = escalating.solve(ContactKind::vertex_face, {passes});
  REQUIRE(through[0].collides());
  CHECK(through[0].toi <= 1.0 / 3);
  // Within the tolerance, relative to the largest coordinate, at a unit speed.
  CHECK(through[0].toi > 1.0 / 3 - 2 * SolverOptions{}.tolerance * 1025);
  // Without double the option changes nothing, and the contact stays.
  CHECK(escalating.solve(ContactKind::vertex_face, {slides})[0].collides() == !has_fp64());
}

// Over the 7,279 hand-made degenerate queries, float alone reports 336 false contacts
// (pocl, the H200), double 78 and Tight Inclusion in double 222. Escalated, single
// precision must miss nothing and report no false contact that double does not.
TEST_CASE("hand-made queries: single precision misses nothing and cries wolf no more than double", "[narrow][quick]")
{
  const auto sets = handmade();
  DeviceSolver single(cstreams::test::device(), conservative(Precision::single));
  const Tally s = run(single, sets);
  CHECK(s.false_negatives == 0);
  CHECK(s.late == 0);
  if (!has_fp64()) return;
  DeviceSolver in_double(cstreams::test::device(), conservative(Precision::double_));
  DeviceSolver in_float(cstreams::test::device(), without_escalation());
  const Tally d = run(in_double, sets), f = run(in_float, sets);
  INFO(s.false_positives << " false positives escalated, " << f.false_positives << " in float alone, "
                         << d.false_positives << " in double");
  CHECK(s.false_positives <= d.false_positives);
  CHECK(s.false_positives < f.false_positives / 2);
}

// The real steps' candidate queries, against mma_bool: float alone reported 137 false
// contacts over the five steps.
TEST_CASE("real steps: single precision reports no contact that does not happen", "[narrow][quick]")
{
  std::vector<Dataset> sets;
  for (const auto& step : real_steps)
    for (auto kind : {ContactKind::vertex_face, ContactKind::edge_edge})
      sets.push_back(real_step_dataset(benchmark_path(std::string("scalable-ccd-sample/") + step.scene), kind));
  DeviceSolver single(cstreams::test::device(), conservative(Precision::single));
  const Tally total = run(single, sets);
  CHECK(total.false_negatives == 0);
  CHECK(total.late == 0);
  if (has_fp64()) CHECK(total.false_positives == 0);
}

// Rod-twist's edges come within 3 to 5 float ulps of each other at the start of its
// step: float alone cannot separate them and answers 0, where the exact earliest time
// is 5.9e-5. Escalated, the step's earliest time (of its contacts, and alone) lies in
// [0.5, 1] times the exact one; so does cloth-funnel's.
TEST_CASE("single precision's earliest time of a real step is no 0 where the exact one is positive", "[detector][quick]")
{
  if (!has_fp64()) return;
  for (const RealStep& s : {real_steps[1], real_steps[0]}) {
    const long double exact = exact_earliest(s.scene, s.step);
    for (Report report : {Report::contacts, Report::earliest_toi}) {
      const double t = step_earliest(s, conservative(Precision::single), report);
      INFO(s.scene << (report == Report::contacts ? ", contacts" : ", earliest times alone") << ": " << t
                   << " against the exact " << double(exact));
      CHECK((long double)t <= exact);
      CHECK((long double)t >= 0.5L * exact);
    }
  }
}
