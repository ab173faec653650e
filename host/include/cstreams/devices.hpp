#pragma once
// Device discovery and selection as the collision library offers it. The filter
// grammar is the runtime's (see cstreams/runtime/device.hpp): pocl, nvidia, amd,
// gpu, cpu, "P:D" indices or a name substring, comma-separated terms all matching.
#include <cstreams/runtime/device.hpp>
#include <cstreams/runtime/error.hpp>

namespace cstreams {

using runtime::DeviceInfo;
using runtime::DeviceKind;
using runtime::filter_from_environment;
using runtime::list_devices;
using runtime::select_device;

}  // namespace cstreams
