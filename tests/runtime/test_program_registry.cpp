#include "../support/test_device.hpp"

#include <cstreams/runtime/error.hpp>

#include <catch2/catch.hpp>

#include <algorithm>

using namespace cstreams::runtime;

TEST_CASE("includes expand between #line markers that name the real files", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  const std::string source = registry.expanded_source("kernels/stream_test.cl");
  CHECK_THAT(source, Catch::StartsWith("#line 1 \"kernels/stream_test.cl\"\n"));
  CHECK_THAT(source, Catch::Contains("#line 1 \"runtime/registration.h\""));
  CHECK_THAT(source, Catch::Contains("#line 1 \"runtime/common.h\""));
  // After the include the next line of stream_test.cl (line 4) resumes with its number.
  CHECK_THAT(source, Catch::Contains("#line 4 \"kernels/stream_test.cl\""));
  // Every expanded line knows where it came from, for compilers that ignore #line.
  const auto origins = registry.line_origins("kernels/stream_test.cl");
  CHECK(std::count(source.begin(), source.end(), '\n') == long(origins.size()));
  CHECK(origins.back().rfind("kernels/stream_test.cl:", 0) == 0);
  // common.h is included by registration.h only once although two files ask for it.
  const auto first = source.find("#line 1 \"runtime/common.h\"");
  CHECK(source.find("#line 1 \"runtime/common.h\"", first + 1) == std::string::npos);
}

TEST_CASE("a kernel that fails to build raises an error carrying the build log", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  try {
    registry.kernel("kernels/broken.cl", "broken");
    FAIL("the broken kernel built");
  } catch (const BuildError& e) {
    INFO("build log:\n" << e.log());
    CHECK(e.program() == "kernels/broken.cl");
    CHECK_THAT(e.log(), Catch::Contains("undeclared_identifier"));
    CHECK_THAT(e.log(), Catch::Contains("broken.cl:6"));
    CHECK_THAT(std::string(e.what()), Catch::Contains("kernels/broken.cl"));
  }
}

TEST_CASE("build logs that ignore #line are mapped back to files and lines", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  // NVIDIA's compiler numbers the expanded source; broken.cl's line 6 is its line 21
  // after common.h (and its #line markers) is expanded in.
  const auto origins = registry.line_origins("kernels/broken.cl");
  const auto at = std::find(origins.begin(), origins.end(), "kernels/broken.cl:6");
  REQUIRE(at != origins.end());
  const std::string raw = "<kernel>:" + std::to_string(at - origins.begin() + 1) + ":27: error: use of undeclared identifier";
  CHECK(registry.locate(raw, "kernels/broken.cl") == "kernels/broken.cl:6:27: error: use of undeclared identifier");
  CHECK(registry.locate("<kernel>:99999:1: error", "kernels/broken.cl") == "<kernel>:99999:1: error");
}

TEST_CASE("an include that is not embedded is reported with file and line", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  static const char text[] = "#include \"runtime/common.h\"\n#include \"nowhere.h\"\n";
  registry.add_sources({{"kernels/missing_include.cl", text}});
  CHECK_THROWS_WITH(registry.expanded_source("kernels/missing_include.cl"),
                    Catch::Contains("kernels/missing_include.cl:2") && Catch::Contains("nowhere.h"));
}

TEST_CASE("kernels are created once per program and options", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  const std::string lock_free = "-DCS_REGISTRATION=2";
  const Kernel a = registry.kernel("kernels/stream_test.cl", "test_square", lock_free);
  const std::size_t built = registry.programs_built();
  const Kernel b = registry.kernel("kernels/stream_test.cl", "test_square", lock_free);
  CHECK(a.get() == b.get());
  CHECK(registry.programs_built() == built);
  const Kernel c = registry.kernel("kernels/stream_test.cl", "test_square", lock_free + " -DOTHER_OPTION=1");
  CHECK(c.get() != a.get());
  CHECK(registry.programs_built() == built + 1);
  CHECK(registry.cache_key("kernels/stream_test.cl", "") != registry.cache_key("kernels/stream_test.cl", "-DX=1"));
  CHECK_THAT(registry.device_options(), Catch::Contains("-DCS_WG_SIZE="));
}

TEST_CASE("emitting kernels built without a registration mode fail to compile clearly", "[runtime][registry][quick]")
{
  auto& registry = cstreams::test::device().programs();
  try {
    registry.kernel("kernels/stream_test.cl", "test_expand");
    FAIL("built without CS_REGISTRATION");
  } catch (const BuildError& e) {
    INFO("build log:\n" << e.log());
    CHECK_THAT(e.log(), Catch::Contains("cs_registration_mode_is_set_by_the_scheduler"));
    CHECK_THAT(std::string(e.what()), Catch::Contains("cs_registration_mode_is_set_by_the_scheduler"));
  }
}

TEST_CASE("under the HD 5870 profile, kernels are built without 64-bit atomics and within 32 KiB of local memory",
          "[runtime][registry][quick]")
{
  Context hd(apply_profile(select_device(filter_from_environment()), "hd5870"));
  REQUIRE(hd.device().local_memory <= 32 * 1024);
  CHECK_THAT(hd.programs().device_options(), Catch::Contains("-DCS_HAS_INT64_ATOMICS=0"));
  static const char local[] = "__kernel void k(__global uint* x) {\n"
                              "  __local uint tile[9000];\n"
                              "  tile[get_local_id(0)] = x[get_global_id(0)];\n"
                              "  barrier(CLK_LOCAL_MEM_FENCE);\n"
                              "  x[get_global_id(0)] = tile[8999 - get_local_id(0)];\n"
                              "}\n";
  hd.programs().add_sources({{"kernels/local_memory.cl", local}});
  CHECK_THROWS_WITH(hd.programs().kernel("kernels/local_memory.cl", "k"),
                    Catch::Contains("bytes of local memory, more than the 32768") && Catch::Contains("hd5870 profile"));
}
