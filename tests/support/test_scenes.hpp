#pragma once
// Scenes the host tests share: generated ones (written once per parameters into the
// temporary folder) and steps of the benchmark data.
#include <cstreams/scene/scene.hpp>

#include <string>

namespace cstreams::test {

Scene generated_scene(const std::string& generator, int frames, int resolution);
// scalable-ccd-sample/cloth-funnel, frames 227 and 228: one step of one mesh.
Scene cloth_funnel();
// scalable-ccd-sample/cloth-ball, frames 92 and 93: the paper's cloth on a ball.
Scene cloth_ball();

}  // namespace cstreams::test
