#pragma once
// Steps through a Detector that several of the detector's test files take.
#include "../support/test_device.hpp"

#include <cstreams/detector.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/scene/scene.hpp>

#include <catch2/catch.hpp>

#include <vector>

namespace cstreams::test {

// Runs one step of `scene` from `frame` through a detector built at that frame.
inline void run_step(Detector& detector, const Step& step)
{
  for (std::uint32_t o = 0; o < step.x0.size(); ++o)
    if (step.scene->objects[o].kind != ObjectKind::static_) detector.set_step(o, step.x0[o], step.x1[o]);
  detector.detect();
}

// The same contacts, feature by feature and time by time.
inline void check_same_contacts(const ContactSpan& a, const ContactSpan& b)
{
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].same_features(b[i]));
    CHECK(a[i].toi == b[i].toi);
  }
}

// Contacts of every step of `scene` through one detector fed frame by frame; `retries`
// adds up the steps' repeated runs.
inline std::vector<std::vector<Contact>> run_frames(const Scene& scene, const DetectorOptions& options,
                                                    std::size_t first, std::size_t last,
                                                    DetectorStats* deepest = nullptr,
                                                    runtime::Context& context = cstreams::test::device(),
                                                    unsigned* retries = nullptr)
{
  Detector detector(context, describe(scene, first), options);
  std::vector<std::vector<Contact>> out;
  for (std::size_t frame = first; frame < last; ++frame) {
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].kind != ObjectKind::static_) detector.set_positions(o, scene.positions(o, frame + 1));
    detector.detect();
    out.push_back(detector.contacts());
    if (deepest && detector.stats().front_pairs >= deepest->front_pairs) *deepest = detector.stats();
    if (retries) *retries += detector.stats().front_retries;
  }
  return out;
}

// Whether two runs gave the same contacts, step by step, feature by feature and time by time.
inline bool same(const std::vector<std::vector<Contact>>& a, const std::vector<std::vector<Contact>>& b)
{
  if (a.size() != b.size()) return false;
  for (std::size_t f = 0; f < a.size(); ++f) {
    if (a[f].size() != b[f].size()) return false;
    for (std::size_t i = 0; i < a[f].size(); ++i)
      if (!a[f][i].same_features(b[f][i]) || a[f][i].toi != b[f][i].toi) return false;
  }
  return true;
}

}  // namespace cstreams::test
