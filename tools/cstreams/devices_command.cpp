#include "commands.hpp"

#include <cstreams/devices.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

namespace cstreams::cli {

namespace {

struct DevicesOptions {
  bool json = false;
  std::string filter;
};

std::string mebibytes(std::size_t bytes)
{
  char text[32];
  if (bytes >= (std::size_t(1) << 30)) std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / double(1 << 30));
  else std::snprintf(text, sizeof text, "%.0f KiB", double(bytes) / 1024.0);
  return text;
}

nlohmann::json to_json(const DeviceInfo& d, bool selected)
{
  return {{"address", d.address()},
          {"selected", selected},
          {"name", d.name},
          {"platform", d.platform_name},
          {"platform_version", d.platform_version},
          {"vendor", d.vendor},
          {"driver", d.driver_version},
          {"device_version", d.device_version},
          {"opencl_c", d.opencl_c_version},
          {"type", runtime::to_string(d.kind)},
          {"compute_units", d.compute_units},
          {"max_clock_mhz", d.max_clock_mhz},
          {"global_memory_bytes", d.global_memory},
          {"local_memory_bytes", d.local_memory},
          {"max_allocation_bytes", d.max_allocation},
          {"max_work_group_size", d.max_work_group_size},
          {"fp64", d.fp64},
          {"int64_atomics", d.int64_atomics},
          {"register_caps", d.register_caps}};
}

void print_text(const DeviceInfo& d, bool selected)
{
  std::printf("[%s]%s %s\n", d.address().c_str(), selected ? " (selected)" : "", d.name.c_str());
  std::printf("    platform       %s (%s)\n", d.platform_name.c_str(), d.platform_version.c_str());
  std::printf("    vendor         %s\n", d.vendor.c_str());
  std::printf("    driver         %s\n", d.driver_version.c_str());
  std::printf("    OpenCL C       %s\n", d.opencl_c_version.c_str());
  std::printf("    type           %s, %u compute units, %u MHz\n", runtime::to_string(d.kind), d.compute_units,
              d.max_clock_mhz);
  std::printf("    memory         %s global, %s local, %s per allocation\n", mebibytes(d.global_memory).c_str(),
              mebibytes(d.local_memory).c_str(), mebibytes(d.max_allocation).c_str());
  std::printf("    work-group     %zu work-items at most\n", d.max_work_group_size);
  std::printf("    fp64           %s\n", d.fp64 ? "yes" : "no");
  std::printf("    64-bit atomics %s\n", d.int64_atomics ? "yes" : "no");
  std::printf("    register caps  %s\n", d.register_caps ? "yes" : "no");
}

void run(const DevicesOptions& options)
{
  const auto devices = list_devices();
  const std::string filter = options.filter.empty() ? filter_from_environment() : options.filter;
  std::string selected;
  std::string problem;
  try {
    selected = select_device(devices, filter).address();
  } catch (const runtime::DeviceNotFound& e) {
    problem = e.what();
  }

  if (options.json) {
    nlohmann::json out{{"filter", filter}, {"selected", selected.empty() ? nlohmann::json() : nlohmann::json(selected)}};
    out["devices"] = nlohmann::json::array();
    for (const auto& d : devices) out["devices"].push_back(to_json(d, d.address() == selected));
    std::cout << out.dump(2) << "\n";
  } else {
    for (const auto& d : devices) print_text(d, d.address() == selected);
    if (!selected.empty())
      std::printf("\nfilter '%s' selects [%s]\n", filter.c_str(), selected.c_str());
  }
  if (!problem.empty()) throw runtime::DeviceNotFound(problem);
}

}  // namespace

void add_devices_command(CLI::App& app, Command& command)
{
  auto options = std::make_shared<DevicesOptions>();
  auto* cmd = app.add_subcommand("devices", "List every OpenCL platform and device and the one a filter selects");
  cmd->add_flag("--json", options->json, "Print JSON instead of text");
  cmd->add_option("--device", options->filter,
                  "Device filter (default: CSTREAMS_DEVICE): pocl, nvidia, amd, gpu, cpu, P:D or a name substring");
  cmd->callback([options, &command] { command = [options] { run(*options); }; });
}

}  // namespace cstreams::cli
