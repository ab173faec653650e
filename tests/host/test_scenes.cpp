#include "../support/scratch.hpp"

#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/scenes/generators.hpp>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace cstreams;
namespace fs = std::filesystem;

namespace {

// The generator makes the folder itself.
std::string fresh_folder(const std::string& name)
{
  const fs::path p = cstreams::test::fresh_scratch("scenes-" + name);
  fs::remove(p);
  return p.string();
}

std::string bytes_of(const fs::path& p)
{
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace

TEST_CASE("generated scenes are deterministic in their seed", "[host][scenes][quick]")
{
  const fs::path a = fresh_folder("a"), b = fresh_folder("b"), c = fresh_folder("c");
  scenes::GeneratorOptions o{"bart", a.string(), 3, 4, 0};
  scenes::generate_scene(o);
  o.folder = b.string();
  scenes::generate_scene(o);
  o.folder = c.string();
  o.seed = 4;
  scenes::generate_scene(o);
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(a)) {
    const auto name = entry.path().filename();
    CHECK(bytes_of(entry.path()) == bytes_of(b / name));  // same seed, same bytes
    // Another seed moves every body; only the manifest stays the same.
    CHECK((bytes_of(entry.path()) == bytes_of(c / name)) == (name == "scene.json"));
    ++files;
  }
  CHECK(files == 5);  // four frames and the manifest
}

TEST_CASE("a step reads each frame file once for all the objects split from it", "[host][scenes][quick]")
{
  const Scene nbody = load_scene(scenes::generate_scene({"n-body", fresh_folder("reads"), 1, 3, 0}));
  REQUIRE(nbody.objects.size() == 300);
  const std::size_t before = nbody.files_read();
  const Step first = load_step(nbody, 0);
  CHECK(nbody.files_read() - before == 2);
  const Step second = load_step(nbody, 1);
  CHECK(nbody.files_read() - before <= 4);
  // The second step starts where the first ended, body by body.
  for (std::uint32_t o = 0; o < nbody.objects.size(); ++o) CHECK(second.x0[o] == first.x1[o]);
}

TEST_CASE("generated scenes have the documented sizes and collide", "[host][scenes][quick]")
{
  const Scene cloth = load_scene(scenes::generate_scene({"cloth-sphere", fresh_folder("cloth"), 1, 3, 0}));
  CHECK(cloth.objects.size() == 2);
  CHECK(cloth.objects[0].topology.faces.size() == 20000);
  CHECK(cloth.objects[1].kind == ObjectKind::static_);
  CHECK(cloth.frame_count() == 3);

  const Scene bart = load_scene(scenes::generate_scene({"bart", fresh_folder("bart"), 1, 3, 0}));
  CHECK(bart.objects.size() == 50);
  CHECK(bart.face_count() == 4000);
  CHECK_FALSE(bart.may_collide(0, 0));
  CHECK(bart.may_collide(0, 1));

  const Scene nbody = load_scene(scenes::generate_scene({"n-body", fresh_folder("nbody"), 1, 2, 0}));
  CHECK(nbody.objects.size() == 300);

  const Scene sheet = load_scene(scenes::generate_scene({"large-sheet", fresh_folder("sheet"), 1, 3, 20}));
  CHECK(sheet.face_count() == 2 * 20 * 20);  // resolution 870 gives 1,513,800

  // Brute force pairs every two objects' faces: 40 bodies keep it quick.
  const Scene few = load_scene(scenes::generate_scene({"n-body", fresh_folder("few"), 2, 2, 40}));
  for (const Scene* s : {&bart, &few}) {
    const Step step = load_step(*s, 0);
    const Candidates bvh = reference_broad_phase(step);
    ReferenceOptions brute;
    brute.broad_phase = BroadPhase::brute_force;
    CHECK(bvh == reference_broad_phase(step, brute));
    CHECK_FALSE(reference_narrow_phase(step, bvh).empty());
  }
}
