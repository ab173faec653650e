#include <cstreams/runtime/device.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <sstream>

namespace cstreams::runtime {

namespace {

std::string lower(std::string_view s)
{
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return out;
}

bool contains(std::string_view haystack, std::string_view needle)
{
  return lower(haystack).find(lower(needle)) != std::string::npos;
}

std::string trim(std::string s)
{
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && std::isspace(static_cast<unsigned char>(s[start]))) ++start;
  return s.substr(start);
}

std::string platform_string(cl_platform_id platform, cl_platform_info what)
{
  std::size_t size = 0;
  check(clGetPlatformInfo(platform, what, 0, nullptr, &size), "clGetPlatformInfo");
  std::string value(size, '\0');
  check(clGetPlatformInfo(platform, what, size, value.data(), nullptr), "clGetPlatformInfo");
  return trim(value);
}

std::string device_string(cl_device_id device, cl_device_info what)
{
  std::size_t size = 0;
  check(clGetDeviceInfo(device, what, 0, nullptr, &size), "clGetDeviceInfo");
  std::string value(size, '\0');
  check(clGetDeviceInfo(device, what, size, value.data(), nullptr), "clGetDeviceInfo");
  return trim(value);
}

template <class T> T device_value(cl_device_id device, cl_device_info what)
{
  T value{};
  check(clGetDeviceInfo(device, what, sizeof(T), &value, nullptr), "clGetDeviceInfo");
  return value;
}

DeviceInfo describe(cl_platform_id platform, cl_device_id id, std::size_t p, std::size_t d)
{
  DeviceInfo info;
  info.platform = platform;
  info.id = id;
  info.platform_index = p;
  info.device_index = d;
  info.platform_name = platform_string(platform, CL_PLATFORM_NAME);
  info.platform_vendor = platform_string(platform, CL_PLATFORM_VENDOR);
  info.platform_version = platform_string(platform, CL_PLATFORM_VERSION);
  info.name = device_string(id, CL_DEVICE_NAME);
  info.vendor = device_string(id, CL_DEVICE_VENDOR);
  info.driver_version = device_string(id, CL_DRIVER_VERSION);
  info.device_version = device_string(id, CL_DEVICE_VERSION);
  info.opencl_c_version = device_string(id, CL_DEVICE_OPENCL_C_VERSION);
  auto type = device_value<cl_device_type>(id, CL_DEVICE_TYPE);
  info.kind = (type & CL_DEVICE_TYPE_GPU)           ? DeviceKind::gpu
              : (type & CL_DEVICE_TYPE_CPU)         ? DeviceKind::cpu
              : (type & CL_DEVICE_TYPE_ACCELERATOR) ? DeviceKind::accelerator
                                                    : DeviceKind::other;
  info.compute_units = device_value<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS);
  info.max_clock_mhz = device_value<cl_uint>(id, CL_DEVICE_MAX_CLOCK_FREQUENCY);
  info.global_memory = device_value<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE);
  info.local_memory = device_value<cl_ulong>(id, CL_DEVICE_LOCAL_MEM_SIZE);
  info.max_allocation = device_value<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
  info.base_address_align = std::max<std::size_t>(1, device_value<cl_uint>(id, CL_DEVICE_MEM_BASE_ADDR_ALIGN) / 8);
  info.max_work_group_size = device_value<std::size_t>(id, CL_DEVICE_MAX_WORK_GROUP_SIZE);
  const std::string extensions = device_string(id, CL_DEVICE_EXTENSIONS);
  auto has = [&](const char* extension) { return extensions.find(extension) != std::string::npos; };
  // AMD's older GPUs (the HD 5870 among them) offer double precision as cl_amd_fp64 only.
  if (has("cl_khr_fp64") || device_value<cl_device_fp_config>(id, CL_DEVICE_DOUBLE_FP_CONFIG) != 0)
    info.fp64_extension = "cl_khr_fp64";
  else if (has("cl_amd_fp64"))
    info.fp64_extension = "cl_amd_fp64";
  info.fp64 = !info.fp64_extension.empty();
  info.int64_atomics = has("cl_khr_int64_base_atomics");
  info.register_caps = has("cl_nv_compiler_options");
  info.correctly_rounded_divide_sqrt =
      (device_value<cl_device_fp_config>(id, CL_DEVICE_SINGLE_FP_CONFIG) & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
  return info;
}

bool parse_index(std::string_view s, std::size_t& value)
{
  if (s.empty() || s.size() > 6) return false;
  value = 0;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    value = value * 10 + std::size_t(c - '0');
  }
  return true;
}

bool term_matches(const DeviceInfo& d, std::string_view term)
{
  const std::string t = lower(term);
  if (t == "pocl") return d.is_pocl();
  if (t == "nvidia") return d.is_nvidia();
  if (t == "amd") return d.is_amd();
  if (t == "intel") return contains(d.vendor, "intel") && !d.is_pocl();
  if (t == "gpu") return d.kind == DeviceKind::gpu;
  if (t == "cpu") return d.kind == DeviceKind::cpu;
  if (t == "accelerator") return d.kind == DeviceKind::accelerator;
  if (auto colon = t.find(':'); colon != std::string::npos) {
    std::size_t p = 0, i = 0;
    if (parse_index(std::string_view(t).substr(0, colon), p) &&
        parse_index(std::string_view(t).substr(colon + 1), i))
      return d.platform_index == p && d.device_index == i;
  }
  return contains(d.name, t) || contains(d.platform_name, t);
}

std::string listing(const std::vector<DeviceInfo>& devices)
{
  if (devices.empty()) return "no OpenCL platform or device is installed (is an ICD such as pocl-opencl-icd present?)";
  std::ostringstream out;
  out << "devices:";
  for (const auto& d : devices)
    out << " [" << d.address() << "] " << d.name << " (" << d.platform_name << ", " << to_string(d.kind) << ");";
  std::string text = out.str();
  text.pop_back();
  return text;
}

}  // namespace

bool DeviceInfo::is_pocl() const
{
  return contains(platform_name, "portable computing language") || contains(platform_version, "pocl");
}
bool DeviceInfo::is_nvidia() const { return contains(vendor, "nvidia") || contains(platform_name, "nvidia"); }
bool DeviceInfo::is_amd() const
{
  return !is_pocl() && (contains(vendor, "advanced micro devices") || contains(vendor, "amd") ||
                        contains(platform_name, "amd accelerated parallel processing"));
}
std::string DeviceInfo::address() const
{
  return std::to_string(platform_index) + ":" + std::to_string(device_index);
}

const char* to_string(DeviceKind kind) noexcept
{
  switch (kind) {
    case DeviceKind::cpu: return "cpu";
    case DeviceKind::gpu: return "gpu";
    case DeviceKind::accelerator: return "accelerator";
    case DeviceKind::other: break;
  }
  return "other";
}

std::vector<DeviceInfo> list_devices()
{
  cl_uint platform_count = 0;
  cl_int status = clGetPlatformIDs(0, nullptr, &platform_count);
  if (status == -1001 /* CL_PLATFORM_NOT_FOUND_KHR: the ICD loader found no platform */ || platform_count == 0)
    return {};
  check(status, "clGetPlatformIDs");
  std::vector<cl_platform_id> platforms(platform_count);
  check(clGetPlatformIDs(platform_count, platforms.data(), nullptr), "clGetPlatformIDs");

  std::vector<DeviceInfo> devices;
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    cl_uint count = 0;
    status = clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &count);
    if (status == CL_DEVICE_NOT_FOUND || count == 0) continue;
    check(status, "clGetDeviceIDs", "listing the devices of platform " + std::to_string(p));
    std::vector<cl_device_id> ids(count);
    check(clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, count, ids.data(), nullptr), "clGetDeviceIDs");
    for (std::size_t d = 0; d < ids.size(); ++d) devices.push_back(describe(platforms[p], ids[d], p, d));
  }
  return devices;
}

bool matches(const DeviceInfo& device, std::string_view filter)
{
  std::size_t start = 0;
  while (start <= filter.size()) {
    std::size_t end = filter.find(',', start);
    if (end == std::string_view::npos) end = filter.size();
    std::string term = trim(std::string(filter.substr(start, end - start)));
    if (!term.empty() && !term_matches(device, term)) return false;
    start = end + 1;
  }
  return true;
}

std::string filter_from_environment()
{
  const char* value = std::getenv("CSTREAMS_DEVICE");
  return value ? trim(value) : std::string();
}

DeviceInfo select_device(const std::vector<DeviceInfo>& devices, std::string_view filter)
{
  if (trim(std::string(filter)).empty()) {
    for (const auto& d : devices)
      if (d.kind == DeviceKind::gpu) return d;
    if (!devices.empty()) return devices.front();
  }
  for (const auto& d : devices)
    if (matches(d, filter)) return d;
  throw DeviceNotFound("no OpenCL device matches the filter '" + std::string(filter) + "'; " + listing(devices));
}

DeviceInfo apply_profile(DeviceInfo device, std::string_view profile)
{
  const std::string name = lower(trim(std::string(profile)));
  if (name.empty()) return device;
  if (name != "hd5870") throw Error("unknown device profile '" + std::string(profile) + "' (profiles: hd5870)");
  constexpr std::size_t mib = std::size_t(1) << 20;
  device.global_memory = std::min(device.global_memory, 1024 * mib);
  device.max_allocation = std::min(device.max_allocation, 256 * mib);
  device.local_memory = std::min<std::size_t>(device.local_memory, 32 * 1024);
  device.max_work_group_size = std::min<std::size_t>(device.max_work_group_size, 256);
  device.int64_atomics = false;
  device.register_caps = false;
  device.profile = name;
  return device;
}

std::string register_cap_option(const DeviceInfo& device, unsigned registers)
{
  return device.register_caps ? " -cl-nv-maxrregcount=" + std::to_string(registers) : std::string();
}

std::string profile_from_environment()
{
  const char* value = std::getenv("CSTREAMS_DEVICE_PROFILE");
  return value ? trim(value) : std::string();
}

DeviceInfo select_device(std::string_view filter)
{
  return apply_profile(select_device(list_devices(), filter), profile_from_environment());
}

}  // namespace cstreams::runtime
