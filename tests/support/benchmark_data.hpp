#pragma once
// Paths into the benchmark data, scenes/benchmarks in the repository (CMake option
// CSTREAMS_BENCHMARK_DIR). Tests that need it fail with this message when it is missing.
#include <string>

namespace cstreams::test {

std::string benchmark_path(const std::string& relative);

// The five real steps of scalable-ccd-sample.
struct RealStep {
  const char* scene;   // folder name
  const char* frame0;  // file names under frames/
  const char* frame1;
  const char* step;    // prefix of boxes/, mma_bool/, queries/ files
};
extern const RealStep real_steps[5];
std::string real_step_file(const RealStep& s, const std::string& sub, const std::string& suffix);

}  // namespace cstreams::test
