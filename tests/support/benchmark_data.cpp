#include "benchmark_data.hpp"

#include <stdexcept>
#include <sys/stat.h>

namespace cstreams::test {

std::string benchmark_path(const std::string& relative)
{
  const std::string path = std::string(CSTREAMS_BENCHMARK_DIR) + "/" + relative;
  struct stat st;
  if (stat(path.c_str(), &st) != 0)
    throw std::runtime_error("benchmark data not found: " + path +
                             " (configure with -DCSTREAMS_BENCHMARK_DIR=<folder>)");
  return path;
}

const RealStep real_steps[5] = {
    {"cloth-funnel", "227.ply", "228.ply", "227"},
    {"rod-twist", "3036.ply", "3037.ply", "3036"},
    {"armadillo-rollers", "326.ply", "327.ply", "326"},
    {"n-body-simulation", "balls16_18.ply", "balls16_19.ply", "18"},
    {"cloth-ball", "cloth_ball92.ply", "cloth_ball93.ply", "92"},
};

std::string real_step_file(const RealStep& s, const std::string& sub, const std::string& suffix)
{
  return benchmark_path(std::string("scalable-ccd-sample/") + s.scene + "/" + sub + "/" + s.step + suffix);
}

}  // namespace cstreams::test
