#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/scenes/generators.hpp>
#include <cstreams/scenes/shapes.hpp>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

namespace cstreams::scenes {

namespace {

constexpr double pi = 3.14159265358979323846;

std::string frame_name(const std::string& stem, int frame)
{
  char name[64];
  std::snprintf(name, sizeof name, "%s_%03d.ply", stem.c_str(), frame);
  return name;
}

nlohmann::json frames_entry(const std::string& stem, int frames)
{
  return {{"pattern", stem + "_%03d.ply"}, {"first", 0}, {"count", frames}};
}

std::string write_manifest(const std::string& folder, const nlohmann::json& manifest)
{
  const std::string path = folder + "/scene.json";
  write_file_atomically(path, [&](std::ostream& out) { out << manifest.dump(2) << "\n"; });
  return path;
}

// A cloth of n x n quads, 2.4 R wide, dropped on a sphere of radius R. Inside the
// sphere's silhouette it drapes over the cap; outside, the skirt swings down past
// vertical and pleats with a seeded angular wave, so pleats fold over and opposite
// sides pass through each other (and through the sphere): self-contacts every frame
// once the skirt has swung in.
std::string cloth_sphere(const GeneratorOptions& o)
{
  const int n = o.resolution ? o.resolution : 100, frames = o.frames ? o.frames : 40;
  const double R = 1.0;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> phase(0, 2 * pi);
  const double wave_phase = phase(rng), lobes = 5 + double(rng() % 4);
  Mesh cloth = sheet(n, n, 2.4 * R * 2, 2.4 * R * 2);
  const std::vector<Vec3> flat = cloth.positions;
  write_ply(o.folder + "/sphere.ply", icosphere(4, R));
  for (int f = 0; f < frames; ++f) {
    const double s = frames > 1 ? double(f) / (frames - 1) : 0.0;
    const double drop = 1.6 * R * std::min(1.0, 2.2 * s);     // reaches the cap at s ~ 0.45
    const double swing = std::max(0.0, (s - 0.2) / 0.8);       // skirt swings down after
    for (std::size_t i = 0; i < flat.size(); ++i) {
      const Vec3 q = flat[i] - Vec3(2.4 * R, 2.4 * R, 0);
      const double r = std::hypot(q.x(), q.y()), theta = std::atan2(q.y(), q.x());
      const double top = 0.6 * R + R - drop;                   // height of the falling sheet
      Vec3 p;
      if (r <= R) {
        const double cap = std::sqrt(std::max(0.0, R * R - r * r)) + 0.01 * R;
        p = Vec3(q.x(), q.y(), std::max(top, cap));
      } else {
        const double rim_z = std::max(top, 0.01 * R);
        // The skirt's angle below horizontal goes to 160 degrees: past vertical and
        // inward, so the long corners of opposite sides cross under the sphere.
        const double alpha = swing * 160.0 * pi / 180.0 * (0.85 + 0.15 * std::sin(lobes * theta + wave_phase));
        const double L = r - R;
        const double pleat = 1 + 0.35 * swing * std::sin(2 * lobes * theta + wave_phase) * std::min(1.0, L / R);
        const double radial = (R + L * std::cos(alpha)) * pleat;
        // Sideways pleats steeper than the cloth's own spacing (0.3 * lobes > 1) make
        // the skirt fold over itself: the map from cloth to space stops being one-to-one.
        const double folded = theta + 0.3 * swing * std::min(1.0, L / R) * std::sin(lobes * theta + wave_phase);
        p = Vec3(radial * std::cos(folded), radial * std::sin(folded), rim_z - L * std::sin(alpha));
      }
      cloth.positions[i] = p;
    }
    write_ply(o.folder + "/" + frame_name("cloth", f), cloth);
  }
  nlohmann::json manifest{{"name", "cloth-sphere"},
                          {"objects",
                           {{{"name", "cloth"}, {"kind", "deformable"}, {"self_collision", true},
                             {"frames", frames_entry("cloth", frames)}},
                            {{"name", "sphere"}, {"kind", "static"}, {"frames", "sphere.ply"}}}}};
  return write_manifest(o.folder, manifest);
}

// Rigid bodies moving on straight lines and rotating, reflected at the walls of a
// cube; they pass through each other freely, so contacts come and go every frame.
std::string rigid_bodies(const GeneratorOptions& o, const char* name, int bodies, const Mesh& body, double box,
                         double speed, int frames)
{
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> u(-1, 1);
  struct Motion {
    Vec3 start, velocity, axis;
    double spin;
  };
  std::vector<Motion> motions;
  for (int b = 0; b < bodies; ++b) {
    Vec3 axis(u(rng), u(rng), u(rng));
    motions.push_back({Vec3(u(rng), u(rng), u(rng)) * box, Vec3(u(rng), u(rng), u(rng)) * speed,
                       axis.norm() > 1e-3 ? axis.normalized() : Vec3::UnitZ(), u(rng) * 0.2});
  }
  auto reflect = [box](double x) {
    // Folds an unbounded coordinate into [-box, box] as a ball bouncing between walls.
    const double period = 4 * box;
    double m = std::fmod(x + box, period);
    if (m < 0) m += period;
    return m < 2 * box ? m - box : 3 * box - m;
  };
  for (int f = 0; f < frames; ++f) {
    Mesh all;
    for (const auto& m : motions) {
      Mesh b = body;
      const Eigen::AngleAxisd rotation(m.spin * f, m.axis);
      const Vec3 c = m.start + m.velocity * f;
      const Vec3 centre(reflect(c.x()), reflect(c.y()), reflect(c.z()));
      for (auto& p : b.positions) p = centre + rotation * p;
      append(all, b);
    }
    write_ply(o.folder + "/" + frame_name(name, f), all);
  }
  nlohmann::json manifest{{"name", name},
                          {"objects",
                           {{{"name", "body"}, {"kind", "rigid"}, {"self_collision", false},
                             {"split_components", true}, {"frames", frames_entry(name, frames)}}}}};
  return write_manifest(o.folder, manifest);
}

// A sheet of n x n quads folding about its middle line: one half rotates up and over
// by 200 degrees, sweeping through the other half, with a seeded ripple so that the
// contact front moves across the sheet from frame to frame.
std::string large_sheet(const GeneratorOptions& o)
{
  const int n = o.resolution ? o.resolution : 870, frames = o.frames ? o.frames : 6;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> phase(0, 2 * pi);
  const double ripple_phase = phase(rng);
  Mesh m = sheet(n, n, 2.0, 2.0);
  const std::vector<Vec3> flat = m.positions;
  for (int f = 0; f < frames; ++f) {
    const double s = frames > 1 ? double(f) / (frames - 1) : 0.0;
    const double angle = s * 200.0 * pi / 180.0;
    for (std::size_t i = 0; i < flat.size(); ++i) {
      const double x = flat[i].x() - 1.0, y = flat[i].y();
      const double ripple = 0.02 * std::sin(9 * y + ripple_phase + 4 * s);
      if (x <= 0) {
        m.positions[i] = Vec3(x, y, ripple);
      } else {
        m.positions[i] = Vec3(x * std::cos(angle), y, x * std::sin(angle) + ripple);
      }
    }
    write_ply(o.folder + "/" + frame_name("sheet", f), m);
  }
  nlohmann::json manifest{{"name", "large-sheet"},
                          {"objects",
                           {{{"name", "sheet"}, {"kind", "deformable"}, {"self_collision", true},
                             {"frames", frames_entry("sheet", frames)}}}}};
  return write_manifest(o.folder, manifest);
}

}  // namespace

std::vector<std::string> generator_names() { return {"cloth-sphere", "n-body", "bart", "large-sheet"}; }

std::string generate_scene(const GeneratorOptions& o)
{
  std::error_code ec;
  std::filesystem::create_directories(o.folder, ec);
  if (ec) throw InputError(o.folder + ": cannot create folder: " + ec.message());
  if (o.name == "cloth-sphere") return cloth_sphere(o);
  if (o.name == "n-body") {
    const int bodies = o.resolution ? o.resolution : 300;
    return rigid_bodies(o, "nbody", bodies, icosphere(2, 0.5), 0.6 * std::cbrt(double(bodies)), 0.05,
                        o.frames ? o.frames : 30);
  }
  if (o.name == "bart") {
    const int bodies = o.resolution ? o.resolution : 50;
    return rigid_bodies(o, "bart", bodies, icosphere(1, 0.3), 0.5 * std::cbrt(double(bodies)), 0.04,
                        o.frames ? o.frames : 40);
  }
  if (o.name == "large-sheet") return large_sheet(o);
  std::string names;
  for (const auto& n : generator_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError("unknown scene generator '" + o.name + "' (" + names + ")");
}

}  // namespace cstreams::scenes
