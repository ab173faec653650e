// Detectors side by side (one context, one device, several threads) and over long runs:
// each reports what it reports alone, and memory stays flat.
#include "../support/test_device.hpp"
#include "../support/test_scenes.hpp"
#include "detector_steps.hpp"

#include <cstreams/detector.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/runtime/context.hpp>

#include <catch2/catch.hpp>

#include <fstream>
#include <thread>
#include <unistd.h>

using namespace cstreams;
using cstreams::test::same;

namespace {

using StepContacts = std::vector<std::vector<Contact>>;

// Runs `detector` over the steps [first, last) of `scene`, one step per call of next().
struct Run {
  const Scene& scene;
  Detector& detector;
  std::size_t frame;
  StepContacts contacts;

  void next()
  {
    const Step step = load_step(scene, frame++);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].kind != ObjectKind::static_) detector.set_positions(o, step.x1[o]);
    detector.detect();
    contacts.push_back(detector.contacts());
  }
};

StepContacts alone(const Scene& scene, std::size_t first, std::size_t steps)
{
  runtime::Context context(filter_from_environment());
  Detector detector(context, describe(scene, first));
  Run run{scene, detector, first, {}};
  for (std::size_t i = 0; i < steps; ++i) run.next();
  return run.contacts;
}

std::size_t contact_count(const StepContacts& c)
{
  std::size_t n = 0;
  for (const auto& s : c) n += s.size();
  return n;
}

std::size_t resident_bytes()
{
  std::ifstream statm("/proc/self/statm");
  std::size_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * std::size_t(::sysconf(_SC_PAGESIZE));
}

}  // namespace

TEST_CASE("two detectors interleaved on one context or one device report what each reports alone",
          "[detector][together][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 34, 24), bodies = cstreams::test::generated_scene("bart", 12, 30);
  const std::size_t steps = 5;
  const StepContacts cloth_alone = alone(cloth, 27, steps), bodies_alone = alone(bodies, 5, steps);
  REQUIRE(contact_count(cloth_alone) > 0);
  REQUIRE(contact_count(bodies_alone) > 0);

  SECTION("one context")
  {
    runtime::Context& context = cstreams::test::device();
    Detector a(context, describe(cloth, 27)), b(context, describe(bodies, 5));
    Run ra{cloth, a, 27, {}}, rb{bodies, b, 5, {}};
    for (std::size_t i = 0; i < steps; ++i) {
      ra.next();
      rb.next();
    }
    CHECK(same(ra.contacts, cloth_alone));
    CHECK(same(rb.contacts, bodies_alone));
  }
  SECTION("two contexts of one device")
  {
    runtime::Context first(filter_from_environment()), second(filter_from_environment());
    REQUIRE(first.device().id == second.device().id);
    Detector a(first, describe(cloth, 27)), b(second, describe(bodies, 5));
    Run ra{cloth, a, 27, {}}, rb{bodies, b, 5, {}};
    for (std::size_t i = 0; i < steps; ++i) {
      rb.next();
      ra.next();
    }
    CHECK(same(ra.contacts, cloth_alone));
    CHECK(same(rb.contacts, bodies_alone));
  }
}

TEST_CASE("detectors on two threads, each with its own context, report what they report alone",
          "[detector][together][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 34, 24), bodies = cstreams::test::generated_scene("bart", 12, 30);
  const std::size_t steps = 5;
  const StepContacts cloth_alone = alone(cloth, 27, steps), bodies_alone = alone(bodies, 5, steps);
  StepContacts cloth_threaded, bodies_threaded;
  std::thread other([&] { cloth_threaded = alone(cloth, 27, steps); });
  bodies_threaded = alone(bodies, 5, steps);
  other.join();
  CHECK(same(cloth_threaded, cloth_alone));
  CHECK(same(bodies_threaded, bodies_alone));
}

TEST_CASE("a context in use by one thread is refused to another with a clear error", "[detector][together][quick]")
{
  const Scene cloth = cstreams::test::generated_scene("cloth-sphere", 34, 24);
  runtime::Context context(filter_from_environment());
  Detector detector(context, describe(cloth, 27));
  std::string refused;
  {
    const runtime::Context::ThreadGuard busy(context);  // as if this thread were mid-step
    std::thread other([&] {
      try {
        detector.detect();
      } catch (const Error& e) {
        refused = e.what();
      }
    });
    other.join();
  }
  CHECK_THAT(refused, Catch::Contains("is in use by another thread") && Catch::Contains("its own runtime::Context"));
  // Refused, not broken: once the context is free the same detector works from any thread.
  std::thread later([&] { detector.detect(); });
  later.join();
  CHECK_NOTHROW(detector.contacts());
}

TEST_CASE("hundreds of steps: memory stays flat and contacts equal a fresh detector's", "[detector][soak][slow]")
{
  // The sequence twice through one detector: the second pass does the first's work
  // again, so it must report the same and end holding what the first did. Its device
  // peak may pass the first's by a little: work lists go back after a burst and come
  // back at the next, beside registration plans (a word a group) that the first pass's
  // later, larger steps sized.
  const std::size_t steps = 150;
  const Scene scene = cstreams::test::generated_scene("cloth-sphere", int(steps + 1), 16);
  runtime::Context context(filter_from_environment());
  Detector detector(context, describe(scene, 0));
  struct Pass {
    StepContacts contacts;
    std::size_t device_peak = 0, device_end = 0, host_peak = 0;
  } pass[2];
  for (Pass& p : pass) {
    for (std::size_t frame = 0; frame < steps; ++frame) {
      const Step step = load_step(scene, frame);
      for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
        if (scene.objects[o].kind != ObjectKind::static_) detector.set_step(o, step.x0[o], step.x1[o]);
      detector.detect();
      p.contacts.push_back(detector.contacts());
      p.device_peak = std::max(p.device_peak, context.memory_in_use());
      p.host_peak = std::max(p.host_peak, resident_bytes());
    }
    p.device_end = context.memory_in_use();
  }
  INFO("device peak " << pass[0].device_peak << " then " << pass[1].device_peak << " bytes; host resident peak "
                      << pass[0].host_peak << " then " << pass[1].host_peak);
  CHECK(contact_count(pass[0].contacts) > 1000);
  CHECK(same(pass[1].contacts, pass[0].contacts));
  CHECK(pass[1].device_peak <= pass[0].device_peak + pass[0].device_peak / 100);
  CHECK(pass[1].device_end == pass[0].device_end);
  CHECK(pass[1].host_peak <= pass[0].host_peak + (4 << 20));
  for (std::size_t step : {0, 75, 149}) {
    INFO("step " << step);
    CHECK(same(alone(scene, step, 1), StepContacts{pass[0].contacts[step]}));
  }
}
