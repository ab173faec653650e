#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <string>

namespace cstreams::runtime {

namespace {
// 256 work-items fill an NVIDIA or AMD multiprocessor several times over and keep
// the scan's local tile (8 items each) within 8 KiB; pocl runs it as a loop.
constexpr std::size_t preferred_work_group_size = 256;

struct Probed {
  std::size_t work_group_size = 0;
  std::uint32_t loop_trip_limit = 0;
  bool profiling_timer = true;
};

// What the device does with kernels of the kind the runtime builds (see
// cl_kernels/runtime/probe.cl), learnt once when a context opens: the work-items a
// kernel with local memory and barriers may run per group, after how many loop trips
// in all a work-item's loops end (0: never), and whether profiling events time kernels.
// Throws for a device that ends loops early in a way the kernels' canary
// (loop_trips.h) would not notice.
Probed probe_device(const DeviceInfo& device, cl_context context, cl_command_queue queue)
{
  const SourceSet& sources = runtime_kernel_sources();
  auto text_of = [&](const std::string& name) {
    const auto source =
        std::find_if(sources.begin(), sources.end(), [&](const SourceFile& s) { return name == s.name; });
    if (source == sources.end()) throw Error(name + " is not embedded in this program");
    return source->text;
  };
  cl_int status = CL_SUCCESS;
  const char* texts[] = {text_of("runtime/loop_trips.h"), text_of("runtime/probe.cl")};
  Handle<cl_program> program(clCreateProgramWithSource(context, 2, texts, nullptr, &status));
  check(status, "clCreateProgramWithSource", "runtime/probe.cl");
  check(clBuildProgram(program.get(), 1, &device.id, "-cl-std=CL1.2", nullptr, nullptr), "clBuildProgram",
        "runtime/probe.cl on " + device.name);
  Probed probed;
  std::size_t& work_group_size = probed.work_group_size;
  Handle<cl_kernel> group(clCreateKernel(program.get(), "cs_probe_work_group", &status));
  check(status, "clCreateKernel", "cs_probe_work_group");
  check(clGetKernelWorkGroupInfo(group.get(), device.id, CL_KERNEL_WORK_GROUP_SIZE, sizeof work_group_size,
                                 &work_group_size, nullptr),
        "clGetKernelWorkGroupInfo", "cs_probe_work_group on " + device.name);

  Handle<cl_kernel> loop(clCreateKernel(program.get(), "cs_probe_loop_trips", &status));
  check(status, "clCreateKernel", "cs_probe_loop_trips");
  std::uint32_t counts[4] = {0, 1, 1, 0};
  Handle<cl_mem> buffer(clCreateBuffer(context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof counts, counts, &status));
  check(status, "clCreateBuffer", "probing " + device.name);
  cl_mem raw = buffer.get();
  check(clSetKernelArg(loop.get(), 0, sizeof raw, &raw), "clSetKernelArg", "cs_probe_loop_trips");
  // Runs `kernel` over one work-item with `trips` as its second argument; returns its
  // time as the profiling events say (0 where they say nothing).
  auto run_one = [&](cl_kernel kernel, const char* name, std::uint32_t trips) {
    check(clSetKernelArg(kernel, 1, sizeof trips, &trips), "clSetKernelArg", name);
    const std::size_t one = 1;
    cl_event raw_event = nullptr;
    check(clEnqueueNDRangeKernel(queue, kernel, 1, nullptr, &one, &one, 0, nullptr, &raw_event),
          "clEnqueueNDRangeKernel", std::string(name) + " on " + device.name);
    Handle<cl_event> event(raw_event);
    check(clEnqueueReadBuffer(queue, raw, CL_TRUE, 0, sizeof counts, counts, 0, nullptr, nullptr),
          "clEnqueueReadBuffer", std::string(name) + " on " + device.name);
    cl_ulong start = 0, end = 0;
    const bool timed =
        clGetEventProfilingInfo(raw_event, CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr) == CL_SUCCESS &&
        clGetEventProfilingInfo(raw_event, CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr) == CL_SUCCESS;
    return timed && end > start ? end - start : cl_ulong(0);
  };
  // A timer that times kernels sees twenty thousand volatile loads take over 10 us more
  // than one (rusticl's report a few nanoseconds, whatever the kernel does).
  Handle<cl_kernel> timer(clCreateKernel(program.get(), "cs_probe_timer", &status));
  check(status, "clCreateKernel", "cs_probe_timer");
  // counts[1] holds 1; the sum goes to counts[0], which the loop probe below rewrites.
  check(clSetKernelArg(timer.get(), 0, sizeof raw, &raw), "clSetKernelArg", "cs_probe_timer");
  check(clSetKernelArg(timer.get(), 2, sizeof raw, &raw), "clSetKernelArg", "cs_probe_timer");
  // The least of three runs each: on a busy CPU device one short run can take longer
  // than a long one (a pocl run beside a test suite reported no timer, and the
  // command's device times were all unknown), while a run is never faster than its work.
  const auto least_of_three = [&](std::uint32_t trips) {
    cl_ulong least = run_one(timer.get(), "cs_probe_timer", trips);
    for (int k = 0; k < 2; ++k) least = std::min(least, run_one(timer.get(), "cs_probe_timer", trips));
    return least;
  };
  const cl_ulong short_ns = least_of_three(1);
  const cl_ulong long_ns = least_of_three(20000);
  probed.profiling_timer = long_ns > short_ns + 10000;
  const std::uint32_t asked = 1u << 17;
  run_one(loop.get(), "cs_probe_loop_trips", asked);
  if (counts[0] == asked) return probed;
  // The kernels whose loops run as long as their input asks bound their trips by this
  // limit and check the canary; a device that cut loops short without the canary
  // noticing would lose contacts without a word.
  if (counts[0] == 0 || counts[3] != 1)
    throw Error("device " + device.name + " (" + device.platform_name + ") ends a kernel's loops after " +
                std::to_string(counts[0]) + " trips, silently, in a way cstreams cannot detect; its results "
                "could miss contacts: use another device");
  probed.loop_trip_limit = counts[0];
  return probed;
}

// The largest power of two within what the device and its kernels allow, at most the
// preferred size.
std::size_t pick_work_group_size(const DeviceInfo& device, std::size_t kernel_limit)
{
  const std::size_t limit = std::min({preferred_work_group_size, device.max_work_group_size, kernel_limit});
  std::size_t size = 1;
  while (size * 2 <= limit) size *= 2;
  return size;
}

Handle<cl_event> out_event(Timeline* timeline, cl_event& raw)
{
  return timeline ? Handle<cl_event>(raw) : Handle<cl_event>();
}
}  // namespace

Context::Context(std::string_view filter, std::size_t max_work_group_size, std::uint32_t loop_trip_limit)
    : Context(select_device(filter), max_work_group_size, loop_trip_limit)
{
}

Context::Context(const DeviceInfo& device, std::size_t max_work_group_size, std::uint32_t loop_trip_limit)
    : device_(device), memory_limit_(device.global_memory),
      memory_(std::make_shared<MemoryAccount>())
{
  cl_int status = CL_SUCCESS;
  cl_context_properties properties[] = {CL_CONTEXT_PLATFORM, cl_context_properties(device.platform), 0};
  context_ = Handle<cl_context>(clCreateContext(properties, 1, &device_.id, nullptr, nullptr, &status));
  check(status, "clCreateContext", "opening " + device_.name);
  queue_ = Handle<cl_command_queue>(clCreateCommandQueue(context_.get(), device_.id, CL_QUEUE_PROFILING_ENABLE, &status));
  check(status, "clCreateCommandQueue", "opening " + device_.name);
  const Probed probed = probe_device(device_, context_.get(), queue_.get());
  std::size_t limit = probed.work_group_size;
  if (max_work_group_size) limit = std::min(limit, max_work_group_size);
  loop_trip_limit_ = probed.loop_trip_limit;
  device_.profiling_timer = probed.profiling_timer;
  if (loop_trip_limit && (!loop_trip_limit_ || loop_trip_limit < loop_trip_limit_)) loop_trip_limit_ = loop_trip_limit;
  work_group_size_ = pick_work_group_size(device_, limit);
  programs_ = std::make_unique<ProgramRegistry>(*this);
  programs_->add_sources(runtime_kernel_sources());
}

Context::~Context()
{
  if (ahead_) clFinish(ahead_.get());
  if (queue_) clFinish(queue_.get());
}

void Context::launch(const Kernel& kernel, std::size_t global, std::size_t local, Timeline* timeline,
                     std::string_view label)
{
  if (global == 0) return;
  if (local) global = round_up(global, local);
  cl_event event = nullptr;
  check_with(clEnqueueNDRangeKernel(queue_.get(), kernel.get(), 1, nullptr, &global, local ? &local : nullptr, 0,
                                    nullptr, timeline ? &event : nullptr),
             "clEnqueueNDRangeKernel",
             [&] { return "launching " + kernel.name() + " over " + std::to_string(global) + " work-items"; });
  ++kernel_launches_;
  if (timeline) timeline->record(label.empty() ? kernel.name() : std::string(label), out_event(timeline, event));
}

void Context::write(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset, Timeline* timeline)
{
  if (bytes == 0) return;
  cl_event event = nullptr;
  check_with(clEnqueueWriteBuffer(queue_.get(), buffer.get(), CL_TRUE, offset, bytes, data, 0, nullptr,
                                  timeline ? &event : nullptr),
             "clEnqueueWriteBuffer", [&] { return "uploading " + std::to_string(bytes) + " bytes"; });
  if (timeline) timeline->record("upload", out_event(timeline, event));
}

Handle<cl_event> Context::write_queued(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset)
{
  if (bytes == 0) return {};
  cl_event event = nullptr;
  check_with(clEnqueueWriteBuffer(queue_.get(), buffer.get(), CL_FALSE, offset, bytes, data, 0, nullptr, &event),
             "clEnqueueWriteBuffer", [&] { return "queueing an upload of " + std::to_string(bytes) + " bytes"; });
  return Handle<cl_event>(event);
}

void Context::copy(const Buffer& source, const Buffer& destination, std::size_t bytes, std::size_t source_offset,
                   std::size_t destination_offset, Timeline* timeline)
{
  if (bytes == 0) return;
  cl_event event = nullptr;
  check_with(clEnqueueCopyBuffer(queue_.get(), source.get(), destination.get(), source_offset, destination_offset,
                                 bytes, 0, nullptr, timeline ? &event : nullptr),
             "clEnqueueCopyBuffer", [&] { return "copying " + std::to_string(bytes) + " bytes"; });
  if (timeline) timeline->record("copy", out_event(timeline, event));
}

void Context::read(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset, Timeline* timeline)
{
  if (bytes == 0) return;
  cl_event event = nullptr;
  check_with(clEnqueueReadBuffer(queue_.get(), buffer.get(), CL_TRUE, offset, bytes, data, 0, nullptr,
                                 timeline ? &event : nullptr),
             "clEnqueueReadBuffer", [&] { return "reading back " + std::to_string(bytes) + " bytes"; });
  ++blocking_reads_;
  if (timeline) timeline->record("readback", out_event(timeline, event));
}

void Context::enqueue_read(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset, cl_event* event)
{
  check_with(clEnqueueReadBuffer(queue_.get(), buffer.get(), CL_FALSE, offset, bytes, data, 0, nullptr, event),
             "clEnqueueReadBuffer", [&] { return "queueing a read of " + std::to_string(bytes) + " bytes"; });
}

// Without an event, which the driver would make and the caller free for reads that
// need none (a step's counts, read behind its kernels).
void Context::read_queued(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset)
{
  if (bytes > 0) enqueue_read(buffer, data, bytes, offset, nullptr);
}

Handle<cl_event> Context::read_started(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset,
                                       Timeline* timeline)
{
  if (bytes == 0) return {};
  cl_event event = nullptr;
  enqueue_read(buffer, data, bytes, offset, &event);
  Handle<cl_event> read(event);
  if (timeline) timeline->record("readback", read);
  return read;
}

void Context::read_landed(const Handle<cl_event>& read)
{
  block_until({read});
  ++blocking_reads_;
}

void Context::fill_u32(const Buffer& buffer, std::uint32_t value, std::size_t first, std::size_t count,
                       Timeline* timeline)
{
  if (count == 0) return;
  cl_event event = nullptr;
  check_with(clEnqueueFillBuffer(queue_.get(), buffer.get(), &value, sizeof(value), first * sizeof(value),
                                 count * sizeof(value), 0, nullptr, timeline ? &event : nullptr),
             "clEnqueueFillBuffer", [&] { return "clearing " + std::to_string(count) + " counters"; });
  if (timeline) timeline->record("fill", out_event(timeline, event));
}

void Context::finish() { check(clFinish(queue_.get()), "clFinish"); }

Handle<cl_event> Context::write_ahead(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset,
                                      const Handle<cl_event>& after)
{
  if (!ahead_) {
    cl_int status = CL_SUCCESS;
    ahead_ = Handle<cl_command_queue>(clCreateCommandQueue(context_.get(), device_.id, 0, &status));
    check(status, "clCreateCommandQueue", "opening a queue for uploads ahead on " + device_.name);
  }
  const cl_event wait = after.get();
  cl_event event = nullptr;
  check_with(clEnqueueWriteBuffer(ahead_.get(), buffer.get(), CL_FALSE, offset, bytes, data, wait ? 1 : 0,
                                  wait ? &wait : nullptr, &event),
             "clEnqueueWriteBuffer", [&] { return "uploading " + std::to_string(bytes) + " bytes ahead"; });
  Handle<cl_event> written(event);
  // Queued is not started: without a flush a driver may hold the write until the
  // queue's next blocking call, after the work it was to overlap.
  check(clFlush(ahead_.get()), "clFlush", "starting an upload ahead");
  return written;
}

namespace {

std::vector<cl_event> raw_events(const std::vector<Handle<cl_event>>& events)
{
  std::vector<cl_event> raw;
  for (const auto& e : events)
    if (e) raw.push_back(e.get());
  return raw;
}

}  // namespace

void Context::wait_for(const std::vector<Handle<cl_event>>& events)
{
  const std::vector<cl_event> raw = raw_events(events);
  if (raw.empty()) return;
  check(clEnqueueBarrierWithWaitList(queue_.get(), cl_uint(raw.size()), raw.data(), nullptr),
        "clEnqueueBarrierWithWaitList", "waiting for uploads ahead");
}

void Context::block_until(const std::vector<Handle<cl_event>>& events)
{
  const std::vector<cl_event> raw = raw_events(events);
  if (!raw.empty())
    check(clWaitForEvents(cl_uint(raw.size()), raw.data()), "clWaitForEvents", "waiting for queued transfers");
}

Handle<cl_event> Context::marker()
{
  cl_event event = nullptr;
  check(clEnqueueMarkerWithWaitList(queue_.get(), 0, nullptr, &event), "clEnqueueMarkerWithWaitList");
  return Handle<cl_event>(event);
}

Context::ThreadGuard::ThreadGuard(Context& context) : context_(context)
{
  const std::thread::id me = std::this_thread::get_id();
  std::thread::id none;
  if (context.user_.compare_exchange_strong(none, me)) {
    owner_ = true;
  } else if (none != me) {
    throw Error("the context of " + context.device_.name +
                " is in use by another thread; give each thread its own runtime::Context");
  }
}

Context::ThreadGuard::~ThreadGuard()
{
  if (owner_) context_.user_ = std::thread::id();
}

void Context::set_memory_limit(std::size_t bytes) { memory_limit_ = std::min(bytes, device_.global_memory); }

Buffer::Buffer(Context& context, std::size_t bytes, const char* label)
{
  // Drivers allocate lazily and report a shortage later, at some launch, without naming
  // the allocation; checked here, it is named and nothing is enqueued.
  const DeviceInfo& device = context.device();
  if (bytes > device.max_allocation)
    throw DeviceMemoryExhausted(label, bytes, device.name + " allocates at most " + mebibytes(device.max_allocation) +
                                              " at once");
  const std::size_t in_use = context.memory_in_use(), limit = context.memory_limit();
  // An empty buffer (one word, below) is not counted, so no limit refuses it.
  if (bytes > 0 && (bytes > limit || in_use > limit - bytes))
    throw DeviceMemoryExhausted(label, bytes, mebibytes(in_use) + " of the " + mebibytes(limit) + " of " + device.name +
                                              " are in use");
  cl_int status = CL_SUCCESS;
  // A zero-byte cl_mem is invalid; one word keeps empty streams bindable as arguments.
  Handle<cl_mem> mem(clCreateBuffer(context.get(), CL_MEM_READ_WRITE, std::max<std::size_t>(bytes, 4), nullptr, &status));
  check(status, "clCreateBuffer", std::string("allocating ") + std::to_string(bytes) + " bytes for " + label);
  allocation_ = std::make_shared<const Allocation>(std::move(mem), bytes, context.memory_account());
}

Buffer Buffer::slice(std::size_t offset, std::size_t bytes) const
{
  if (!allocation_ || bytes == 0 || offset > allocation_->bytes || bytes > allocation_->bytes - offset)
    throw Error("cannot slice bytes [" + std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                ") of a buffer of " + std::to_string(this->bytes()));
  const auto& whole = allocation_->whole ? allocation_->whole : allocation_;
  const cl_buffer_region region{allocation_->offset + offset, bytes};
  cl_int status = CL_SUCCESS;
  Handle<cl_mem> mem(
      clCreateSubBuffer(whole->mem.get(), CL_MEM_READ_WRITE, CL_BUFFER_CREATE_TYPE_REGION, &region, &status));
  check(status, "clCreateSubBuffer",
        "bytes " + std::to_string(region.origin) + " to " + std::to_string(region.origin + bytes));
  Buffer view;
  view.allocation_ = std::make_shared<const Allocation>(std::move(mem), bytes, whole, region.origin);
  return view;
}

void ensure_capacity(Context& context, Buffer& buffer, std::size_t bytes, const char* label)
{
  if (buffer.bytes() < bytes) buffer = Buffer(context, bytes, label);
}

void Kernel::set_raw(unsigned index, std::size_t size, const void* value) const
{
  check_with(clSetKernelArg(kernel_.get(), index, size, value), "clSetKernelArg",
             [&] { return "setting argument " + std::to_string(index) + " of " + name_; });
}

void Timeline::record(std::string label, Handle<cl_event> event)
{
  pending_.push_back({std::move(label), std::move(event), std::chrono::steady_clock::now()});
}

std::vector<Timeline::Entry> Timeline::resolve() const
{
  std::vector<Entry> entries;
  if (pending_.empty()) return entries;
  entries.reserve(pending_.size());
  // The queue runs in order, so once the last command is done every earlier one is:
  // one wait instead of one an event (a hundred a step).
  cl_event last = pending_.back().event.get();
  check(clWaitForEvents(1, &last), "clWaitForEvents", "profiling " + pending_.back().label);
  for (const auto& p : pending_) {
    cl_ulong queued = 0, start = 0, end = 0;
    const auto describe = [&] { return "profiling " + p.label; };
    check_with(clGetEventProfilingInfo(p.event.get(), CL_PROFILING_COMMAND_QUEUED, sizeof(queued), &queued, nullptr),
               "clGetEventProfilingInfo", describe);
    check_with(clGetEventProfilingInfo(p.event.get(), CL_PROFILING_COMMAND_START, sizeof(start), &start, nullptr),
               "clGetEventProfilingInfo", describe);
    check_with(clGetEventProfilingInfo(p.event.get(), CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr),
               "clGetEventProfilingInfo", describe);
    entries.push_back({p.label, end > start ? end - start : 0, queued, start, end, p.host_queued});
  }
  return entries;
}

}  // namespace cstreams::runtime
