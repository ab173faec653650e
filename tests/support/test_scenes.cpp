#include "test_scenes.hpp"

#include "benchmark_data.hpp"
#include "scratch.hpp"

#include <cstreams/scenes/generators.hpp>

#include <filesystem>

namespace cstreams::test {

Scene generated_scene(const std::string& generator, int frames, int resolution)
{
  // The generator makes the folder itself.
  const auto folder =
      fresh_scratch("test-" + generator + "-" + std::to_string(frames) + "-" + std::to_string(resolution));
  std::filesystem::remove(folder);
  return load_scene(scenes::generate_scene({generator, folder.string(), 1, frames, resolution}));
}

Scene cloth_funnel()
{
  const std::string dir = benchmark_path("scalable-ccd-sample/cloth-funnel/frames/");
  return scene_from_frames({dir + "227.ply", dir + "228.ply"});
}

Scene cloth_ball()
{
  const std::string dir = benchmark_path("scalable-ccd-sample/cloth-ball/frames/");
  return scene_from_frames({dir + "cloth_ball92.ply", dir + "cloth_ball93.ply"});
}

}  // namespace cstreams::test
