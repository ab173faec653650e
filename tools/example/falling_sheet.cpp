// A cloth sheet falls onto a static floor at constant speed; cstreams reports when it
// lands. The floor is at z = 0 and the sheet starts at z = 0.35, falling 0.1 a step,
// so it touches the floor halfway through step 3 (time of impact 0.5).
//
//   falling_sheet [device filter]      (default: CSTREAMS_DEVICE, else the first GPU)
//
// Exits with status 1 if the contact is not found where it must be.
#include <cstreams/detector.hpp>
#include <cstreams/devices.hpp>
#include <cstreams/runtime/context.hpp>

#include <cmath>
#include <cstdio>
#include <exception>

namespace {

// An n x n grid of quads over [-half, half]^2 at height z, two triangles a quad.
cstreams::ObjectDescription grid(const char* name, int n, double half, double z, cstreams::ObjectKind kind)
{
  cstreams::ObjectDescription o;
  o.name = name;
  o.kind = kind;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) o.positions.emplace_back(-half + 2 * half * i / n, -half + 2 * half * j / n, z);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + std::uint32_t(n + 1), d = c + 1;
      o.faces.push_back({a, b, d});
      o.faces.push_back({a, d, c});
    }
  return o;
}

}  // namespace

int main(int argc, char** argv)
try {
  cstreams::runtime::Context device(argc > 1 ? argv[1] : cstreams::filter_from_environment());

  cstreams::SceneDescription scene;
  const std::uint32_t sheet = scene.add(grid("sheet", 32, 1.0, 0.35, cstreams::ObjectKind::deformable));
  scene.add(grid("floor", 1, 2.0, 0.0, cstreams::ObjectKind::static_));

  cstreams::DetectorOptions options;  // conservative solver: never misses a contact
  options.front = cstreams::FrontMode::exact;
  cstreams::Detector detector(device, scene, options);
  std::printf("device: %s\n", device.device().name.c_str());

  std::vector<cstreams::Vec3> x = scene.objects[sheet].positions;
  int landed = -1;
  double landing_time = 1;
  for (int step = 0; step < 5; ++step) {
    for (auto& p : x) p.z() -= 0.1;
    detector.set_positions(sheet, x);
    detector.detect();
    const auto& contacts = detector.contacts();
    const double first = detector.earliest_toi()[sheet];
    std::printf("step %d: %zu contacts, earliest time of impact %.6f, %.3f ms\n", step, contacts.size(), first,
                detector.stats().host_ms);
    if (landed < 0 && !contacts.empty()) {
      landed = step;
      landing_time = first;
    }
  }
  const bool ok = landed == 3 && std::fabs(landing_time - 0.5) < 1e-3;
  std::printf("%s: the sheet lands in step %d at time %.6f (expected step 3 at 0.5)\n", ok ? "ok" : "WRONG", landed,
              landing_time);
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "falling_sheet: %s\n", e.what());
  return 1;
}
