#include <cstreams/runtime/device.hpp>
#include <cstreams/runtime/error.hpp>

#include <catch2/catch.hpp>

using namespace cstreams::runtime;

namespace {
DeviceInfo make(std::size_t p, std::size_t d, std::string platform, std::string name, std::string vendor, DeviceKind kind)
{
  DeviceInfo info;
  info.platform_index = p;
  info.device_index = d;
  info.platform_name = std::move(platform);
  info.name = std::move(name);
  info.vendor = std::move(vendor);
  info.kind = kind;
  return info;
}

// The two platforms of the H200 machine, in the order its loader lists them.
std::vector<DeviceInfo> h200_machine()
{
  return {make(0, 0, "Portable Computing Language", "cpu-x86-64-AMD EPYC", "AuthenticAMD", DeviceKind::cpu),
          make(1, 0, "NVIDIA CUDA", "NVIDIA H200", "NVIDIA Corporation", DeviceKind::gpu)};
}
}  // namespace

TEST_CASE("device filters select by vendor, type, index and name", "[runtime][device][quick]")
{
  const auto devices = h200_machine();
  CHECK(select_device(devices, "pocl").name == "cpu-x86-64-AMD EPYC");
  CHECK(select_device(devices, "nvidia").name == "NVIDIA H200");
  CHECK(select_device(devices, "gpu").name == "NVIDIA H200");
  CHECK(select_device(devices, "cpu").name == "cpu-x86-64-AMD EPYC");
  CHECK(select_device(devices, "1:0").name == "NVIDIA H200");
  CHECK(select_device(devices, "h200").name == "NVIDIA H200");
  CHECK(select_device(devices, "gpu, NVIDIA").name == "NVIDIA H200");
  // pocl on an AMD processor reports vendor AuthenticAMD but is not an AMD OpenCL device.
  CHECK_THROWS_AS(select_device(devices, "amd"), DeviceNotFound);
}

TEST_CASE("an empty filter prefers a GPU, else the first device", "[runtime][device][quick]")
{
  CHECK(select_device(h200_machine(), "").name == "NVIDIA H200");
  CHECK(select_device({h200_machine()[0]}, "  ").name == "cpu-x86-64-AMD EPYC");
}

TEST_CASE("a filter that matches nothing lists the devices", "[runtime][device][quick]")
{
  try {
    select_device(h200_machine(), "gpu,pocl");
    FAIL("expected DeviceNotFound");
  } catch (const DeviceNotFound& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains("gpu,pocl"));
    CHECK_THAT(what, Catch::Contains("[0:0] cpu-x86-64-AMD EPYC"));
    CHECK_THAT(what, Catch::Contains("[1:0] NVIDIA H200"));
  }
  CHECK_THROWS_WITH(select_device({}, "pocl"), Catch::Contains("no OpenCL platform"));
}

TEST_CASE("the installed devices are discovered with their properties", "[runtime][device][quick]")
{
  const auto devices = list_devices();
  REQUIRE_FALSE(devices.empty());
  const DeviceInfo chosen = select_device(filter_from_environment());
  CHECK_FALSE(chosen.name.empty());
  CHECK(chosen.compute_units > 0);
  CHECK(chosen.global_memory > 0);
  CHECK(chosen.max_work_group_size > 0);
  CHECK_THAT(chosen.opencl_c_version, Catch::StartsWith("OpenCL C"));
}

TEST_CASE("the HD 5870 profile lowers what a device offers to that card's, and no further", "[runtime][device][quick]")
{
  DeviceInfo big = make(1, 0, "NVIDIA CUDA", "NVIDIA H200", "NVIDIA Corporation", DeviceKind::gpu);
  big.global_memory = std::size_t(140) << 30;
  big.max_allocation = std::size_t(35) << 30;
  big.local_memory = 48 << 10;
  big.max_work_group_size = 1024;
  big.fp64 = big.int64_atomics = big.register_caps = true;
  big.fp64_extension = "cl_khr_fp64";
  const DeviceInfo hd = apply_profile(big, "HD5870");
  CHECK(hd.global_memory == std::size_t(1) << 30);
  CHECK(hd.max_allocation == std::size_t(256) << 20);
  CHECK(hd.local_memory == 32 << 10);
  CHECK(hd.max_work_group_size == 256);
  CHECK(!hd.int64_atomics);
  // The card's compiler takes no register cap: its programs build with none.
  CHECK(register_cap_option(big, 32) == " -cl-nv-maxrregcount=32");
  CHECK(register_cap_option(hd, 32).empty());
  CHECK(hd.fp64);
  CHECK(hd.profile == "hd5870");

  DeviceInfo small = big;
  small.max_allocation = std::size_t(128) << 20;
  small.max_work_group_size = 32;
  small.fp64 = false;
  small.fp64_extension.clear();
  const DeviceInfo still_small = apply_profile(small, "hd5870");
  CHECK(still_small.max_allocation == std::size_t(128) << 20);
  CHECK(still_small.max_work_group_size == 32);
  CHECK(!still_small.fp64);

  CHECK(apply_profile(big, "").profile.empty());
  CHECK_THROWS_WITH(apply_profile(big, "hd4870"), Catch::Contains("unknown device profile 'hd4870'") &&
                                                      Catch::Contains("hd5870"));
}
