#include "commands.hpp"

#include <cstreams/geometry/bvh.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/scene/scene.hpp>
#include <cstreams/scenes/generators.hpp>

#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string_view>

namespace cstreams::cli {

Scene open_scene(const std::vector<std::string>& paths, bool split)
{
  if (paths.size() == 1 && !split) return load_scene(paths[0]);
  return scene_from_frames(paths, split);
}

StepRange parse_step_range(const std::string& text)
{
  StepRange range;
  if (text.empty()) return range;
  const auto number = [&](std::string_view digits, std::size_t& value) {
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    return !digits.empty() && error == std::errc() && end == digits.data() + digits.size();
  };
  const std::string_view all(text);
  const auto colon = all.find(':');
  range.all = false;
  const bool ok = colon == std::string_view::npos
                      ? number(all, range.first) && range.first < SIZE_MAX
                      : number(all.substr(0, colon), range.first) && number(all.substr(colon + 1), range.last);
  if (!ok) throw InputError("--frames '" + text + "': must be A (one step) or A:B (frames A to B), whole numbers");
  if (colon == std::string_view::npos) range.last = range.first + 1;
  if (range.first >= range.last) throw InputError("--frames " + text + ": A:B needs A < B");
  return range;
}

std::pair<std::size_t, std::size_t> resolve(const StepRange& range, std::size_t frame_count)
{
  const std::size_t steps = frame_count > 1 ? frame_count - 1 : 1;
  if (range.all) return {0, steps};
  if (range.last > steps)
    throw InputError("--frames " + std::to_string(range.first) + ":" + std::to_string(range.last) +
                     " is outside the scene's steps 0:" + std::to_string(steps));
  return {range.first, range.last};
}

namespace {

struct InfoOptions {
  std::vector<std::string> paths;
  bool split = false;
  bool json = false;
};

void info(const InfoOptions& o)
{
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = open_scene(o.paths, o.split);
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  nlohmann::json out{{"scene", scene.name}, {"frames", scene.frame_count()}, {"objects", nlohmann::json::array()}};
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::size_t orphan_vf = 0, orphan_ee = 0;
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& obj = scene.objects[i];
    const auto x = scene.positions(i, 0);
    for (const auto& p : x) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Bvh bvh = build_bvh(swept_bounds(obj.topology, x, x, 0).faces);
    nlohmann::json j{{"name", obj.name},
                     {"kind", to_string(obj.kind)},
                     {"self_collision", scene.may_collide(i, i)},
                     {"vertices", obj.topology.vertex_count},
                     {"edges", obj.topology.edges.size()},
                     {"faces", obj.topology.faces.size()},
                     {"bvh_nodes", bvh.nodes.size()},
                     {"bvh_depth", bvh.depth()}};
    if (scene.may_collide(i, i)) {
      const OrphanSet orphans = build_orphans(obj.topology);
      j["orphan_vf"] = orphans.vf.size();
      j["orphan_ee"] = orphans.ee.size();
      orphan_vf += orphans.vf.size();
      orphan_ee += orphans.ee.size();
    }
    out["objects"].push_back(j);
  }
  std::size_t edges = 0, nodes = 0;
  for (const auto& j : out["objects"]) {
    edges += j["edges"].get<std::size_t>();
    nodes += j["bvh_nodes"].get<std::size_t>();
  }
  out["totals"] = {{"vertices", scene.vertex_count()}, {"edges", edges}, {"faces", scene.face_count()},
                   {"orphan_vf", orphan_vf}, {"orphan_ee", orphan_ee}, {"bvh_nodes", nodes}};
  out["bounding_box"] = {{"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}};
  out["load_seconds"] = load_s;

  if (o.json) {
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::printf("scene %s: %zu objects, %zu frames, loaded in %.3f s\n", scene.name.c_str(), scene.objects.size(),
              scene.frame_count(), load_s);
  std::printf("%-16s %-10s %4s %10s %10s %10s %10s %10s %9s %5s\n", "object", "kind", "self", "vertices", "edges",
              "faces", "orphan vf", "orphan ee", "bvh nodes", "depth");
  for (const auto& j : out["objects"])
    std::printf("%-16s %-10s %4s %10zu %10zu %10zu %10zu %10zu %9zu %5zu\n", j["name"].get<std::string>().c_str(),
                j["kind"].get<std::string>().c_str(), j["self_collision"].get<bool>() ? "yes" : "no",
                j["vertices"].get<std::size_t>(), j["edges"].get<std::size_t>(), j["faces"].get<std::size_t>(),
                j.value("orphan_vf", std::size_t(0)), j.value("orphan_ee", std::size_t(0)),
                j["bvh_nodes"].get<std::size_t>(), j["bvh_depth"].get<std::size_t>());
  std::printf("%-16s %-10s %4s %10zu %10zu %10zu %10zu %10zu %9zu\n", "total", "", "", scene.vertex_count(), edges,
              scene.face_count(), orphan_vf, orphan_ee, nodes);
  std::printf("bounding box (frame 0): [%g, %g, %g] - [%g, %g, %g]\n", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
}

struct ReferenceCommandOptions {
  std::vector<std::string> paths;
  bool split = false;
  std::string frames;
  std::string out;
  bool brute_force = false;
  ReferenceSolverOptions solver;
};

void check(const ReferenceCommandOptions& o)
{
  check_option("--tolerance", o.solver.tolerance, option_ranges::tolerance);
  check_option("--min-separation", o.solver.min_separation, option_ranges::min_separation);
  parse_step_range(o.frames);
  if (!o.out.empty()) check_output_path("--out", o.out);
}

void reference(const ReferenceCommandOptions& o)
{
  const Scene scene = open_scene(o.paths, o.split);
  const auto [first, last] = resolve(parse_step_range(o.frames), scene.frame_count());
  ReferenceOptions options;
  options.solver = o.solver;
  options.tolerance = o.solver.tolerance;
  options.broad_phase = o.brute_force ? BroadPhase::brute_force : BroadPhase::bvh;
  std::vector<Contact> all;
  for (std::size_t f = first; f < last; ++f) {
    const auto start = std::chrono::steady_clock::now();
    const Step step = load_step(scene, f);
    const Candidates candidates = reference_broad_phase(step, options);
    const auto contacts = reference_narrow_phase(step, candidates, options.solver);
    std::fprintf(stderr, "step %zu: %zu vf + %zu ee candidates, %zu contacts, %.2f s\n", f, candidates.vf_count(),
                 candidates.ee_count(), contacts.size(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    all.insert(all.end(), contacts.begin(), contacts.end());
  }
  if (o.out.empty()) write_contacts_csv(std::cout, all);
  else write_contacts_csv(o.out, all);
}

}  // namespace

void add_reference_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<ReferenceCommandOptions>();
  auto* cmd = app.add_subcommand("reference",
                                 "Run the host reference CCD (double precision, never misses) and write contacts as CSV");
  cmd->add_option("scene", o->paths, "A scene manifest (.json), a mesh file, or the frame files of one mesh")
      ->required();
  cmd->add_flag("--split", o->split, "Treat each connected component of the mesh as an object");
  cmd->add_option("--frames", o->frames, "Steps A:B (from frame A to B), or one step A; default: all");
  cmd->add_option("--out", o->out, "CSV file (default: standard output)");
  cmd->add_flag("--brute-force", o->brute_force, "Test every triangle pair instead of traversing BVHs");
  cmd->add_option("--tolerance", o->solver.tolerance, "Co-domain tolerance, relative to the query's coordinates");
  cmd->add_option("--min-separation", o->solver.min_separation, "Distance below which primitives count as colliding");
  cmd->callback([o, &command] {
    check(*o);
    command = [o] { reference(*o); };
  });
}

void add_info_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<InfoOptions>();
  auto* cmd = app.add_subcommand("info", "Describe a scene: objects, topology, orphan pairs, BVH, bounding box");
  cmd->add_option("scene", o->paths, "A scene manifest (.json), a mesh file, or the frame files of one mesh")
      ->required();
  cmd->add_flag("--split", o->split, "Treat each connected component of the mesh as an object");
  cmd->add_flag("--json", o->json, "Print JSON instead of a table");
  cmd->callback([o, &command] { command = [o] { info(*o); }; });
}

void add_generate_command(CLI::App& app, Command& command)
{
  auto o = std::make_shared<scenes::GeneratorOptions>();
  auto* cmd = app.add_subcommand("generate", "Write a procedural scene (PLY frames and scene.json) into a folder");
  cmd->add_option("name", o->name, "cloth-sphere, n-body, bart or large-sheet")->required();
  cmd->add_option("--out", o->folder, "Folder to write into")->required();
  cmd->add_option("--seed", o->seed, "Random seed (same seed, same files)");
  cmd->add_option("--frames", o->frames, "Number of frames (default: the scene's)");
  cmd->add_option("--resolution", o->resolution, "Size parameter (default: the scene's; see docs/command-line.md)");
  cmd->callback([o, &command] {
    // Bounds that keep a typo from asking for terabytes of frames.
    check_option("--frames", o->frames, {0, 100000});
    check_option("--resolution", o->resolution, {0, 4096});
    command = [o] { std::printf("%s\n", scenes::generate_scene(*o).c_str()); };
  });
}

}  // namespace cstreams::cli
