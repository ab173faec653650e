#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace cstreams::scenes {

// Procedural, kinematic scenes for benchmarks and front-tracking tests. Each writes a
// binary PLY per frame and a manifest (scene.json) into its folder and returns the
// manifest's path. The same name, seed and sizes always give the same files.
//
//   cloth-sphere  a cloth dropped on a static sphere; its hanging skirt pleats and
//                 folds through itself (deformable, self-collision + sphere);
//                 resolution 100 gives 20,000 cloth triangles
//   n-body        hundreds of spheres flying through a box and through each other
//                 (rigid objects, one per component)
//   bart          ~4K triangles of small rigid bodies tumbling on random paths
//   large-sheet   a sheet folding onto itself; resolution 870 gives 1.51M triangles
struct GeneratorOptions {
  std::string name;          // one of the four above
  std::string folder;        // created if missing
  std::uint32_t seed = 1;
  int frames = 0;            // 0: the scene's default
  int resolution = 0;        // 0: the scene's default; meaning depends on the scene
};

std::vector<std::string> generator_names();
std::string generate_scene(const GeneratorOptions& options);

}  // namespace cstreams::scenes
