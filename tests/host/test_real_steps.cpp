// The host reference against the exact ground truth of the five real simulation steps.
#include "../support/benchmark_data.hpp"
#include "../support/test_device.hpp"

#include <cstreams/datasets/datasets.hpp>
#include <cstreams/detector.hpp>

#include <cstreams/io/query_io.hpp>
#include <cstreams/reference/reference_ccd.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sys/stat.h>

using namespace cstreams;
using cstreams::test::RealStep;

namespace {

Scene load_real(const RealStep& s)
{
  const std::string dir = cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/frames/");
  return scene_from_frames({dir + s.frame0, dir + s.frame1});
}

std::vector<std::array<std::uint64_t, 2>> boxes(const RealStep& s, const char* kind)
{
  std::ifstream in(cstreams::test::real_step_file(s, "boxes", std::string(kind) + ".json"));
  return nlohmann::json::parse(in).get<std::vector<std::array<std::uint64_t, 2>>>();
}

// The ground truth's pairs as the contacts the reference must report, using the id
// convention of scenes/benchmarks/README.md: [vertices | edges | faces] in one index space.
struct GroundTruth {
  std::vector<Contact> vf, ee;  // every pair marked true
  std::vector<VertexFace> vf_pairs;
  std::vector<EdgeEdge> ee_pairs;
  std::vector<bool> vf_truth, ee_truth;
};

GroundTruth ground_truth(const RealStep& s, const Step& step)
{
  const Topology& t = step.scene->objects[0].topology;
  const std::uint64_t nv = t.vertex_count, ne = t.edges.size();
  GroundTruth g;
  g.vf_truth = read_bool_array(cstreams::test::real_step_file(s, "mma_bool", "vf_mma_bool.json"));
  g.ee_truth = read_bool_array(cstreams::test::real_step_file(s, "mma_bool", "ee_mma_bool.json"));
  const auto vf = boxes(s, "vf"), ee = boxes(s, "ee");
  REQUIRE(vf.size() == g.vf_truth.size());
  REQUIRE(ee.size() == g.ee_truth.size());
  for (std::size_t i = 0; i < vf.size(); ++i) {
    REQUIRE(vf[i][0] < nv);
    REQUIRE(vf[i][1] >= nv + ne);
    const VertexFace p{std::uint32_t(vf[i][0]), std::uint32_t(vf[i][1] - nv - ne)};
    g.vf_pairs.push_back(p);
    if (g.vf_truth[i]) g.vf.push_back(make_contact(step, 0, 0, p, 0));
  }
  for (std::size_t i = 0; i < ee.size(); ++i) {
    REQUIRE(ee[i][0] >= nv);
    REQUIRE(ee[i][1] < nv + ne);
    const EdgeEdge p{std::uint32_t(ee[i][0] - nv), std::uint32_t(ee[i][1] - nv)};
    g.ee_pairs.push_back(p);
    if (g.ee_truth[i]) g.ee.push_back(make_contact(step, 0, 0, p, 0));
  }
  return g;
}

bool file_exists(const std::string& path)
{
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

// Every pair the ground truth marks true is among `contacts`.
void check_recall(const RealStep& s, const Step& step, ContactSpan contacts)
{
  const GroundTruth truth = ground_truth(s, step);
  auto key = [](const Contact& c) { return std::make_tuple(c.kind, c.v); };
  std::set<decltype(key(contacts[0]))> reported;
  for (const auto& c : contacts) reported.insert(key(c));
  std::size_t missed = 0;
  for (const auto* list : {&truth.vf, &truth.ee})
    for (const auto& c : *list)
      if (!reported.count(key(c))) {
        ++missed;
        UNSCOPED_INFO("missed " << (c.kind == ContactKind::vertex_face ? "vf" : "ee") << " " << c.v[0] << " "
                                << c.v[1] << " " << c.v[2] << " " << c.v[3]);
      }
  CHECK(truth.vf.size() + truth.ee.size() > 0);
  CHECK(missed == 0);
}

void check_recall(const RealStep& s)
{
  INFO("scene " << s.scene);
  const Scene scene = load_real(s);
  const Step step = load_step(scene, 0);
  check_recall(s, step, reference_ccd(step));
}

// The device pipeline with the default (conservative, single precision) solver, in
// front modes none and exact; both must report the same contacts. Then in double
// precision, where a float screen goes first, on devices that have it.
void check_device_recall(const RealStep& s)
{
  INFO("scene " << s.scene);
  const Scene scene = load_real(s);
  const Step step = load_step(scene, 0);
  std::vector<Contact> first;
  for (FrontMode front : {FrontMode::none, FrontMode::exact}) {
    DetectorOptions options;
    options.front = front;
    Detector detector(cstreams::test::device(), describe(scene, 0), options);
    detector.set_positions(0, step.x1[0]);
    detector.detect();
    check_recall(s, step, detector.contacts());
    if (front == FrontMode::none) {
      first = detector.contacts();
      continue;
    }
    REQUIRE(detector.contacts().size() == first.size());
    for (std::size_t i = 0; i < first.size(); ++i) CHECK(detector.contacts()[i].same_features(first[i]));
  }
  if (!cstreams::test::device().device().fp64) return;
  DetectorOptions options;
  options.solver.precision = Precision::double_;
  Detector detector(cstreams::test::device(), describe(scene, 0), options);
  detector.set_positions(0, step.x1[0]);
  detector.detect();
  INFO("double precision");
  check_recall(s, step, detector.contacts());
}

}  // namespace

TEST_CASE("real steps load with the published vertex, face and edge counts", "[host][io][quick]")
{
  const Scene cloth = load_real(cstreams::test::real_steps[4]);
  CHECK(cloth.objects[0].topology.vertex_count == 46598);
  CHECK(cloth.objects[0].topology.faces.size() == 92230);
  CHECK(cloth.objects[0].topology.edges.size() == 138825);
  const Scene nbody = load_real(cstreams::test::real_steps[3]);
  CHECK(nbody.objects[0].topology.vertex_count == 73960);
  CHECK(nbody.objects[0].topology.faces.size() == 146480);
  CHECK(nbody.objects[0].topology.edges.size() == 219840);
}

TEST_CASE("queries rebuilt from frames and boxes equal every upstream query CSV", "[host][io][quick]")
{
  for (const auto& s : cstreams::test::real_steps) {
    const Scene scene = load_real(s);
    const Step step = load_step(scene, 0);
    const GroundTruth truth = ground_truth(s, step);
    for (const char* kind : {"vf", "ee"}) {
      const std::string csv = std::string(CSTREAMS_BENCHMARK_DIR) + "/scalable-ccd-sample/" + s.scene +
                              "/queries/" + s.step + kind + ".csv";
      if (!file_exists(csv)) continue;  // absent upstream: cloth-ball, n-body ee, armadillo ee
      INFO(csv);
      const auto upstream = read_queries(csv);
      const bool vf = kind[0] == 'v';
      REQUIRE(upstream.size() == (vf ? truth.vf_pairs.size() : truth.ee_pairs.size()));
      std::size_t different = 0;
      for (std::size_t i = 0; i < upstream.size(); ++i) {
        const Query q = vf ? vertex_face_query(step, 0, 0, truth.vf_pairs[i]) : edge_edge_query(step, 0, 0, truth.ee_pairs[i]);
        if (q != upstream[i].points) ++different;
      }
      CHECK(different == 0);
    }
  }
}

TEST_CASE("the host reference reports every true pair of cloth-funnel", "[host][reference][quick]")
{
  check_recall(cstreams::test::real_steps[0]);
}

TEST_CASE("the host reference reports every true pair of rod-twist and armadillo-rollers", "[host][reference][slow]")
{
  check_recall(cstreams::test::real_steps[1]);
  check_recall(cstreams::test::real_steps[2]);
}

TEST_CASE("the host reference reports every true pair of n-body and cloth-ball", "[host][reference][slow]")
{
  check_recall(cstreams::test::real_steps[3]);
  check_recall(cstreams::test::real_steps[4]);
}

TEST_CASE("the device pipeline reports every true pair of cloth-funnel", "[detector][quick]")
{
  check_device_recall(cstreams::test::real_steps[0]);
}

TEST_CASE("the device pipeline reports every true pair of rod-twist and armadillo-rollers", "[detector][slow]")
{
  check_device_recall(cstreams::test::real_steps[1]);
  check_device_recall(cstreams::test::real_steps[2]);
}

TEST_CASE("the device pipeline reports every true pair of n-body and cloth-ball", "[detector][slow]")
{
  check_device_recall(cstreams::test::real_steps[3]);
  check_device_recall(cstreams::test::real_steps[4]);
}

TEST_CASE("the host reference misses none of the hand-made degenerate queries", "[host][reference][slow]")
{
  const char* scenes[] = {"erleben-cube-cliff-edges", "erleben-cube-internal-edges", "erleben-sliding-spike",
                          "erleben-sliding-wedge",    "erleben-spike-crack",         "erleben-spike-hole",
                          "erleben-spike-wedge",      "erleben-spikes",              "erleben-wedge-crack",
                          "erleben-wedges",           "unit-tests"};
  std::size_t queries = 0, positives = 0, false_negatives = 0, false_positives = 0;
  for (const char* scene : scenes)
    for (const char* kind : {"vertex-face", "edge-edge"})
      for (const char* file : {"data_0_0.csv", "data_0_1.csv"}) {
        const std::string path = std::string("sample-queries/") + scene + "/" + kind + "/" + file;
        if (!file_exists(std::string(CSTREAMS_BENCHMARK_DIR) + "/" + path)) continue;
        for (const auto& q : read_queries(cstreams::test::benchmark_path(path))) {
          const CcdResult r = kind[0] == 'v' ? vertex_face_reference(q.points) : edge_edge_reference(q.points);
          ++queries;
          positives += q.collides;
          if (q.collides && !r.collides) {
            ++false_negatives;
            UNSCOPED_INFO("false negative in " << path);
          }
          false_positives += !q.collides && r.collides;
        }
      }
  INFO("queries " << queries << ", positives " << positives << ", false positives " << false_positives);
  CHECK(queries == 7279);
  CHECK(positives == 435);
  CHECK(false_negatives == 0);
}

TEST_CASE("a real step's ground truth answers for every candidate pair as contacts name it", "[host][io][quick]")
{
  const RealStep& s = cstreams::test::real_steps[0];
  const std::string dir = cstreams::test::benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/frames/");
  const auto truth = StepTruth::for_frames({dir + s.frame0, dir + s.frame1});
  REQUIRE(truth);
  const Scene scene = load_real(s);
  const Step step = load_step(scene, 0);
  const GroundTruth g = ground_truth(s, step);
  std::size_t positives = 0;
  for (std::size_t i = 0; i < g.vf_pairs.size(); ++i) {
    const auto answer = truth->of(make_contact(step, 0, 0, g.vf_pairs[i], 0));
    REQUIRE(answer);
    CHECK(answer->collides == g.vf_truth[i]);
    positives += answer->collides;
  }
  for (std::size_t i = 0; i < g.ee_pairs.size(); ++i) {
    const auto answer = truth->of(make_contact(step, 0, 0, g.ee_pairs[i], 0));
    REQUIRE(answer);
    CHECK(answer->collides == g.ee_truth[i]);
    positives += answer->collides;
  }
  CHECK(positives == g.vf.size() + g.ee.size());
  CHECK(positives > 0);

  const StepTruth::Answer none{false, std::nanl("")}, contact{true, 0.25L};
  CHECK(std::string(none.verdict(std::nullopt)) == "right");
  CHECK(std::string(none.verdict(0.5)) == "false positive");
  CHECK(std::string(contact.verdict(std::nullopt)) == "misses it");
  CHECK(std::string(contact.verdict(0.25)) == "right");
  CHECK(std::string(contact.verdict(0.2)) == "right");
  CHECK(std::string(contact.verdict(0.3)) == "later than exact");
  CHECK(std::string(StepTruth::Answer{true, std::nanl("")}.verdict(0.9)) == "right");

  // A vertex against its own face is never a candidate; another object has no truth.
  const Face& f = scene.objects[0].topology.faces[0];
  CHECK_FALSE(truth->of(Contact{ContactKind::vertex_face, 0, 0, {f[0], f[0], f[1], f[2]}, 0.5}));
  Contact elsewhere = make_contact(step, 0, 0, g.vf_pairs[0], 0);
  elsewhere.object_b = 1;
  CHECK_FALSE(truth->of(elsewhere));
  // Frames that are not the two of one step folder have none.
  CHECK_FALSE(StepTruth::for_frames({dir + s.frame0}));
  CHECK_FALSE(StepTruth::for_frames({dir + s.frame0, cstreams::test::benchmark_path("scalable-ccd-sample/rod-twist/frames/3036.ply")}));
}
