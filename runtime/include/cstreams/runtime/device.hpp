#pragma once
#include <cstreams/runtime/opencl.hpp>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace cstreams::runtime {

enum class DeviceKind { cpu, gpu, accelerator, other };

// What a program needs to know about one OpenCL device, read once at discovery.
struct DeviceInfo {
  cl_platform_id platform = nullptr;
  cl_device_id id = nullptr;
  std::size_t platform_index = 0;
  std::size_t device_index = 0;
  std::string platform_name;
  std::string platform_vendor;
  std::string platform_version;
  std::string name;
  std::string vendor;
  std::string driver_version;
  std::string device_version;
  std::string opencl_c_version;
  DeviceKind kind = DeviceKind::other;
  unsigned compute_units = 0;
  unsigned max_clock_mhz = 0;
  std::size_t global_memory = 0;
  std::size_t local_memory = 0;
  std::size_t max_allocation = 0;
  std::size_t base_address_align = 1;  // bytes: where a sub-buffer (Buffer::slice) may start
  std::size_t max_work_group_size = 0;
  bool fp64 = false;
  std::string fp64_extension;  // cl_khr_fp64, or cl_amd_fp64 where only that is offered
  bool int64_atomics = false;  // cl_khr_int64_base_atomics
  bool register_caps = false;  // cl_nv_compiler_options: a build option caps a kernel's registers
  std::string profile;         // the device profile it runs under (apply_profile), or empty
  bool correctly_rounded_divide_sqrt = false;
  bool profiling_timer = true;  // profiling events time kernels (learnt by a Context)

  bool is_pocl() const;
  bool is_nvidia() const;
  bool is_amd() const;
  // "platform:device" indices, the stable way to name a device on one machine.
  std::string address() const;
};

const char* to_string(DeviceKind kind) noexcept;

// The build option that caps the registers of each work-item of a program's kernels at
// `registers`, where the device's compiler takes one (register_caps); empty elsewhere.
std::string register_cap_option(const DeviceInfo& device, unsigned registers);

// Every device of every platform, in platform then device order. A machine without
// any OpenCL platform gives an empty list, not an error.
std::vector<DeviceInfo> list_devices();

// A filter is a comma-separated list of terms that must all match (case-insensitive):
//   pocl | nvidia | amd | intel   vendor or implementation
//   gpu | cpu | accelerator       device type
//   P:D                           platform and device index
//   anything else                 a substring of the device or platform name
// An empty filter matches every device.
bool matches(const DeviceInfo& device, std::string_view filter);

// The filter a user gave through CSTREAMS_DEVICE, or empty.
std::string filter_from_environment();

// A device profile keeps the runtime within what a smaller device offers, on any device
// that offers at least as much: "hd5870" (AMD Radeon HD 5870 class) lowers global memory
// to 1 GiB, an allocation to 256 MiB, local memory to 32 KiB and work-groups to 256
// work-items, and takes away 64-bit atomics (programs see CS_HAS_INT64_ATOMICS=0);
// double precision stays only where the device has it. An empty name changes nothing;
// an unknown one throws Error naming the profiles there are.
DeviceInfo apply_profile(DeviceInfo device, std::string_view profile);

// The profile a user gave through CSTREAMS_DEVICE_PROFILE, or empty.
std::string profile_from_environment();

// The device a filter selects: the first match, preferring a GPU when the filter is
// empty, under the profile of CSTREAMS_DEVICE_PROFILE. Throws DeviceNotFound listing
// every device when nothing matches.
DeviceInfo select_device(std::string_view filter);
DeviceInfo select_device(const std::vector<DeviceInfo>& devices, std::string_view filter);

}  // namespace cstreams::runtime
