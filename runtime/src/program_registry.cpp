#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/program_registry.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

namespace cstreams::runtime {

namespace {

// FNV-1a: stable across runs and compilers, unlike std::hash, so keys can name files.
std::uint64_t fnv1a(const std::string& text)
{
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string hex(std::uint64_t v)
{
  std::ostringstream out;
  out << std::hex << v;
  return out.str();
}

std::string folder_of(const std::string& name)
{
  auto slash = name.rfind('/');
  return slash == std::string::npos ? std::string() : name.substr(0, slash + 1);
}

std::string build_log(cl_program program, cl_device_id device)
{
  std::size_t size = 0;
  if (clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size) != CL_SUCCESS) return {};
  std::string log(size, '\0');
  clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

// Rewrites "<kernel>:21:" (a line of the expanded source) as "file.cl:6:".
std::string map_log_locations(const std::string& log, const std::vector<std::string>& origins)
{
  static const std::regex location(R"re(<(kernel|source|stdin)>:([0-9]+):)re");
  std::string out;
  auto begin = std::sregex_iterator(log.begin(), log.end(), location);
  std::size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    const auto& m = *it;
    const std::size_t line = std::stoul(m[2].str());
    out += log.substr(last, std::size_t(m.position()) - last);
    out += line >= 1 && line <= origins.size() ? origins[line - 1] + ":" : m.str();
    last = std::size_t(m.position() + m.length());
  }
  return out + log.substr(last);
}

std::string derive_device_options(const DeviceInfo& device, std::size_t work_group_size, std::uint32_t loop_trips)
{
  std::string options = "-cl-std=CL1.2 -DCS_WG_SIZE=" + std::to_string(work_group_size) +
                        " -DCS_LOOP_TRIPS=" + std::to_string(loop_trips) + "u";
  options += device.fp64 ? " -DCS_HAS_FP64=1" : " -DCS_HAS_FP64=0";
  if (device.fp64_extension == "cl_amd_fp64") options += " -DCS_FP64_AMD=1";
  // Kernels enable 64-bit atomics only under this (a device profile may take them away).
  options += device.int64_atomics ? " -DCS_HAS_INT64_ATOMICS=1" : " -DCS_HAS_INT64_ATOMICS=0";
  // Where a test may stop early: a CPU runs a work-item's loads one after another
  // anyway and gains from skipping them, a GPU from issuing them together.
  options += device.kind == DeviceKind::cpu ? " -DCS_CPU=1" : " -DCS_CPU=0";
  options += device.is_pocl()     ? " -DCS_VENDOR_POCL=1"
             : device.is_nvidia() ? " -DCS_VENDOR_NVIDIA=1"
             : device.is_amd()    ? " -DCS_VENDOR_AMD=1"
                                  : " -DCS_VENDOR_OTHER=1";
  // Division and square root default to a few ulp on GPUs but are exact on pocl; asking
  // for correct rounding where the device offers it makes float results agree.
  if (device.correctly_rounded_divide_sqrt) options += " -cl-fp32-correctly-rounded-divide-sqrt";
  return options;
}

}  // namespace

ProgramRegistry::ProgramRegistry(Context& context)
    : context_(context), device_options_(derive_device_options(context.device(), context.work_group_size(), context.loop_trip_limit()))
{
}

void ProgramRegistry::add_sources(const SourceSet& sources)
{
  for (const auto& s : sources) sources_[s.name] = s.text;
}

bool ProgramRegistry::has_source(const std::string& name) const { return sources_.count(name) != 0; }

std::string ProgramRegistry::text_of(const std::string& name) const
{
  if (const char* dir = std::getenv("CSTREAMS_KERNEL_DIR"); dir && *dir) {
    std::ifstream file(std::string(dir) + "/" + name, std::ios::binary);
    if (file) return std::string(std::istreambuf_iterator<char>(file), {});
  }
  auto it = sources_.find(name);
  if (it == sources_.end()) throw Error("OpenCL source " + name + " is not embedded in this program");
  return it->second;
}

void ProgramRegistry::expand(const std::string& name, Expansion& out) const
{
  if (std::find(out.stack.begin(), out.stack.end(), name) != out.stack.end())
    throw Error("OpenCL source " + name + " includes itself");
  if (std::find(out.included.begin(), out.included.end(), name) != out.included.end()) return;
  out.included.push_back(name);
  out.stack.push_back(name);

  static const std::regex include_line(R"re(^\s*#\s*include\s*"([^"]+)"\s*$)re");
  std::istringstream in(text_of(name));
  std::string line;
  std::size_t number = 0;
  auto emit = [&](const std::string& text, std::size_t origin) {
    out.text += text;
    out.text += '\n';
    out.origins.push_back(name + ":" + std::to_string(origin));
  };
  emit("#line 1 \"" + name + "\"", 1);
  while (std::getline(in, line)) {
    ++number;
    std::smatch m;
    if (!std::regex_match(line, m, include_line)) {
      emit(line, number);
      continue;
    }
    const std::string relative = folder_of(name) + m[1].str();
    const std::string target = has_source(relative) ? relative : m[1].str();
    if (!has_source(target))
      throw Error(name + ":" + std::to_string(number) + ": included file \"" + m[1].str() + "\" is not embedded");
    expand(target, out);
    emit("#line " + std::to_string(number + 1) + " \"" + name + "\"", number);
  }
  out.stack.pop_back();
}

std::string ProgramRegistry::expanded_source(const std::string& program) const
{
  Expansion e;
  expand(program, e);
  return e.text;
}

std::vector<std::string> ProgramRegistry::line_origins(const std::string& program) const
{
  Expansion e;
  expand(program, e);
  return e.origins;
}

std::string ProgramRegistry::locate(const std::string& log, const std::string& program) const
{
  return map_log_locations(log, line_origins(program));
}

std::string ProgramRegistry::cache_key(const std::string& program, const std::string& options) const
{
  const auto& d = context_.device();
  return hex(fnv1a(expanded_source(program))) + "-" +
         hex(fnv1a(device_options_ + " " + options + "|" + d.platform_name + "|" + d.name + "|" + d.driver_version));
}

ProgramRegistry::Program& ProgramRegistry::program(const std::string& name, const std::string& options)
{
  const std::string key = name + "|" + options;
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;

  Expansion expansion;
  expand(name, expansion);
  const char* text = expansion.text.c_str();
  cl_int status = CL_SUCCESS;
  Handle<cl_program> built(clCreateProgramWithSource(context_.get(), 1, &text, nullptr, &status));
  check(status, "clCreateProgramWithSource", "loading " + name);

  // For profiling: extra options (-cl-nv-verbose reports registers and spills) and a
  // file that collects every build log.
  const char* extra = std::getenv("CSTREAMS_BUILD_OPTIONS");
  const std::string all_options =
      device_options_ + (options.empty() ? "" : " " + options) + (extra && *extra ? " " + std::string(extra) : "");
  cl_device_id device = context_.device().id;
  status = clBuildProgram(built.get(), 1, &device, all_options.c_str(), nullptr, nullptr);
  if (status == CL_BUILD_PROGRAM_FAILURE || status == CL_INVALID_BUILD_OPTIONS || status == CL_COMPILER_NOT_AVAILABLE)
    throw BuildError(name, context_.device().name, all_options,
                     map_log_locations(build_log(built.get(), device), expansion.origins));
  check(status, "clBuildProgram", "building " + name);
  if (const char* log = std::getenv("CSTREAMS_BUILD_LOG"); log && *log)
    std::ofstream(log, std::ios::app) << "== " << name << " " << all_options << "\n"
                                      << map_log_locations(build_log(built.get(), device), expansion.origins) << "\n";
  return programs_.emplace(key, Program{std::move(built), {}}).first->second;
}

void ProgramRegistry::build(const std::string& name, const std::string& options) { program(name, options); }

Kernel ProgramRegistry::kernel(const std::string& name, const std::string& kernel_name, const std::string& options)
{
  Program& p = program(name, options);
  if (auto it = p.kernels.find(kernel_name); it != p.kernels.end()) return it->second;

  cl_int status = CL_SUCCESS;
  Handle<cl_kernel> k(clCreateKernel(p.program.get(), kernel_name.c_str(), &status));
  check(status, "clCreateKernel", "creating kernel " + kernel_name + " of " + name);
  std::size_t max_wg = 0;
  check(clGetKernelWorkGroupInfo(k.get(), context_.device().id, CL_KERNEL_WORK_GROUP_SIZE, sizeof(max_wg), &max_wg,
                                 nullptr),
        "clGetKernelWorkGroupInfo", "querying kernel " + kernel_name);
  // Kernels are written for CS_WG_SIZE work-items per group; a device that cannot
  // run that many of this kernel at once must say so now, not at the first launch.
  if (max_wg < context_.work_group_size())
    throw Error("kernel " + kernel_name + " of " + name + " runs at most " + std::to_string(max_wg) +
                " work-items per group on " + context_.device().name + ", fewer than CS_WG_SIZE=" +
                std::to_string(context_.work_group_size()));
  cl_ulong local_bytes = 0;
  check(clGetKernelWorkGroupInfo(k.get(), context_.device().id, CL_KERNEL_LOCAL_MEM_SIZE, sizeof(local_bytes),
                                 &local_bytes, nullptr),
        "clGetKernelWorkGroupInfo", "querying kernel " + kernel_name);
  if (local_bytes > context_.device().local_memory)
    throw Error("kernel " + kernel_name + " of " + name + " needs " + std::to_string(local_bytes) +
                " bytes of local memory, more than the " + std::to_string(context_.device().local_memory) + " of " +
                context_.device().name + (context_.device().profile.empty() ? "" : " (" + context_.device().profile + " profile)"));
  return p.kernels.emplace(kernel_name, Kernel(std::move(k), kernel_name, max_wg)).first->second;
}

}  // namespace cstreams::runtime
