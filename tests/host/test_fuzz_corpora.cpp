// Every input the fuzzers kept (their seeds, the merged corpora, and each finding once
// fixed) replayed through the same checks as the fuzz targets, in every build.
#include <inputs.hpp>

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace {

template <class Check> std::size_t replay(const std::string& target, Check check)
{
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(CSTREAMS_FUZZ_CORPUS) + "/" + target)) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    INFO(entry.path().string());
    CHECK_NOTHROW(check(bytes));
    ++files;
  }
  return files;
}

}  // namespace

TEST_CASE("the fuzz corpora parse or fail with InputError", "[io][fuzz][quick]")
{
  CHECK(replay("mesh_readers", cstreams::fuzz::mesh_readers) > 100);
  CHECK(replay("scene_manifest", [](const std::string& b) { cstreams::fuzz::scene_manifest(b, CSTREAMS_FUZZ_MESHES); }) >= 4);
  CHECK(replay("query_csv", cstreams::fuzz::query_csv) >= 6);
}
