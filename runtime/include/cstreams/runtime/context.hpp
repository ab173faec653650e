#pragma once
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/device.hpp>
#include <cstreams/runtime/handle.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/program_registry.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace cstreams::runtime {

// A device with its OpenCL context, one in-order profiling queue and its program
// registry. Everything the runtime enqueues goes through this queue, so passes need
// no events to order themselves; only uploads ahead (write_ahead) take a second
// queue, ordered against the first through events.
//
// Threads: a context, and everything built on it, is used by one thread at a time.
// Its kernels are shared objects whose arguments are set before each launch, so two
// threads on one context would race; ThreadGuard turns that into an error. Threads
// that detect at the same time each open their own context (any number per device).
class Context {
public:
  // Held while a detector or solver works on the context; re-entrant within a thread.
  // Throws Error when another thread holds the context.
  class ThreadGuard {
  public:
    explicit ThreadGuard(Context& context);
    ~ThreadGuard();
    ThreadGuard(const ThreadGuard&) = delete;
    ThreadGuard& operator=(const ThreadGuard&) = delete;

  private:
    Context& context_;
    bool owner_ = false;
  };

  // max_work_group_size (a power of two; 0: none) keeps the runtime's groups smaller
  // than the device allows, as a smaller device would run them. loop_trip_limit (0:
  // none) makes the kernels keep their loops within that many trips a work-item, as on
  // a device that ends loops there (see loop_trip_limit()).
  explicit Context(const DeviceInfo& device, std::size_t max_work_group_size = 0, std::uint32_t loop_trip_limit = 0);
  // Opens the device that `filter` selects (see select_device()).
  explicit Context(std::string_view filter, std::size_t max_work_group_size = 0, std::uint32_t loop_trip_limit = 0);
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context();

  const DeviceInfo& device() const noexcept { return device_; }
  cl_context get() const noexcept { return context_.get(); }
  cl_command_queue queue() const noexcept { return queue_.get(); }
  ProgramRegistry& programs() noexcept { return *programs_; }

  // Work-group size of every kernel the runtime launches with a fixed local size: the
  // largest power of two up to 256 that the device and its kernels allow.
  std::size_t work_group_size() const noexcept { return work_group_size_; }

  // The loop trips a work-item may make in all before the device ends its loops (Mesa's
  // llvmpipe ends them after 65535), or the lower limit asked for; 0: no limit. Kernels
  // see it as CS_LOOP_TRIPS and keep within it (cl_kernels/runtime/loop_trips.h).
  std::uint32_t loop_trip_limit() const noexcept { return loop_trip_limit_; }

  // Launches a 1-D range of `global` work-items (rounded up to `local`; 0 lets the
  // driver choose local size). A launch of 0 items enqueues nothing.
  void launch(const Kernel& kernel, std::size_t global, std::size_t local, Timeline* timeline = nullptr,
              std::string_view label = {});

  void write(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset = 0,
             Timeline* timeline = nullptr);
  // A write queued behind the work on queue() that returns at once: it reads `data`
  // until its event, returned, completes.
  Handle<cl_event> write_queued(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset);
  void read(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset = 0,
            Timeline* timeline = nullptr);
  // A read queued behind the work on queue() that returns at once: `data` holds the
  // bytes once a blocking command queued after it has returned (the queue is in order).
  void read_queued(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset = 0);
  // The same, with its event: `data` holds the bytes once read_landed() returns on it.
  Handle<cl_event> read_started(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset = 0,
                                Timeline* timeline = nullptr);
  // Returns once a read_started() read has landed: a blocking read (blocking_reads()).
  void read_landed(const Handle<cl_event>& read);
  void copy(const Buffer& source, const Buffer& destination, std::size_t bytes, std::size_t source_offset = 0,
            std::size_t destination_offset = 0, Timeline* timeline = nullptr);
  void fill_u32(const Buffer& buffer, std::uint32_t value, std::size_t first, std::size_t count,
                Timeline* timeline = nullptr);
  void finish();

  // Uploads ahead of the work on queue(), on a second in-order queue (opened at the
  // first), so that they overlap it: the write starts once `after` completes (an event
  // of queue(); none: at once) and reads `data` until its own event, returned,
  // completes. Commands that read the buffer on queue() must wait_for() that event.
  Handle<cl_event> write_ahead(const Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset,
                               const Handle<cl_event>& after);
  // Commands queued on queue() from now on start once these events complete.
  void wait_for(const std::vector<Handle<cl_event>>& events);
  // Returns once these events complete.
  void block_until(const std::vector<Handle<cl_event>>& events);
  // An event that completes once everything queued on queue() so far has.
  Handle<cl_event> marker();

  // Every kernel launch and every blocking read this context has issued: a step's cost
  // beyond its kernels' time is mostly these (a launch ~5 us, a read ~16 us on the H200).
  std::uint64_t kernel_launches() const noexcept { return kernel_launches_; }
  std::uint64_t blocking_reads() const noexcept { return blocking_reads_; }

  // Device memory: what this context's live buffers hold, and the most they may (the
  // device's global memory unless lowered). Buffer refuses allocations past the limit.
  std::size_t memory_in_use() const noexcept { return memory_->in_use; }
  std::size_t memory_limit() const noexcept { return memory_limit_; }
  void set_memory_limit(std::size_t bytes);
  // The most the live buffers have held since the last reset (which starts it at what
  // they hold then).
  std::size_t memory_high_water() const noexcept { return memory_->high_water; }
  void reset_memory_high_water() noexcept { memory_->high_water = memory_->in_use.load(); }
  const std::shared_ptr<MemoryAccount>& memory_account() const noexcept { return memory_; }

private:
  // Queues a read without blocking; its event goes to `event` where that is not null.
  void enqueue_read(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset, cl_event* event);

  DeviceInfo device_;
  Handle<cl_context> context_;
  Handle<cl_command_queue> queue_;
  Handle<cl_command_queue> ahead_;  // write_ahead()'s
  std::size_t work_group_size_ = 0;
  std::uint32_t loop_trip_limit_ = 0;
  std::size_t memory_limit_ = 0;
  std::uint64_t kernel_launches_ = 0, blocking_reads_ = 0;
  std::shared_ptr<MemoryAccount> memory_;
  std::atomic<std::thread::id> user_{};
  std::unique_ptr<ProgramRegistry> programs_;
};

inline std::size_t round_up(std::size_t n, std::size_t multiple) { return (n + multiple - 1) / multiple * multiple; }

}  // namespace cstreams::runtime
