#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include "scheduler/run_loop.hpp"

#include <algorithm>
#include <string>

namespace cstreams::runtime {

Scheduler::Scheduler(Context& context, StreamGraph graph, SchedulerOptions options)
    : state_(std::make_unique<State>(context, std::move(graph), options))
{
}

Scheduler::~Scheduler() = default;

void Scheduler::run() { state_->run(); }
bool Scheduler::release_idle_scratch()
{
  state_->settle_stats();
  return state_->scratch.release_idle();
}
std::vector<Buffer> Scheduler::borrow_idle_scratch(const std::vector<std::size_t>& sizes) const
{
  return state_->scratch.borrow_idle(sizes);
}

void Scheduler::upload(StreamId stream, const void* items, std::size_t count)
{
  auto& s = *state_;
  s.settle_stats();
  auto& st = s.state(stream);
  // What the stream held is replaced, so it goes first; short of memory, idle scratch
  // goes too.
  if (count > st.capacity || !s.spec(stream).variable) s.scratch.with_memory([&] { s.buffers.grow(stream, count, false); });
  s.context.write(st.buffer, items, count * s.spec(stream).element_bytes);
  st.count = count;
  st.known = true;
  st.partial = false;
  st.handed_to.clear();
}

void Scheduler::on_counter_read(std::function<void()> work) { state_->flush.on_counter_read(std::move(work)); }

void Scheduler::read_after_run(StreamId stream, void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  if (spec.variable || count > s.state(stream).count)
    throw Error("cannot read " + std::to_string(count) + " items of stream " + spec.name + " after a run" +
                (spec.variable ? ": it is variable-length" : ", which holds " + std::to_string(s.state(stream).count)));
  s.run_reads.add(stream, items, count * spec.element_bytes);
}

void Scheduler::download(StreamId stream, void* items, std::size_t count) const
{
  auto& s = *state_;
  auto& st = s.state(stream);
  if (st.spent && count > 0)
    throw Error("cannot read stream " + s.spec(stream).name + ": it lives within a run, and went back once read");
  if (count > st.count)
    throw Error("cannot read " + std::to_string(count) + " items of stream " + s.spec(stream).name + ", which holds " +
                std::to_string(st.count));
  if (st.partial)
    throw Error("cannot read stream " + s.spec(stream).name + ": the last run went in " +
                std::to_string(s.stats.slices) + " slices to fit the device's memory, and the stream kept only the "
                "last one's items (StreamGraph::gather keeps them all)");
  s.context.read(st.buffer, items, count * s.spec(stream).element_bytes);
}

namespace {

void check_write(const StreamSpec& spec, std::size_t held, std::size_t first, std::size_t count)
{
  if (spec.variable || first + count > held)
    throw Error("cannot write items [" + std::to_string(first) + ", " + std::to_string(first + count) +
                ") of stream " + spec.name +
                (spec.variable ? ", which is variable-length" : ", which holds " + std::to_string(held)));
}

}  // namespace

void Scheduler::write(StreamId stream, std::size_t first, const void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  check_write(spec, s.state(stream).count, first, count);
  s.context.write(s.state(stream).buffer, items, count * spec.element_bytes, first * spec.element_bytes);
}

Handle<cl_event> Scheduler::write_queued(StreamId stream, std::size_t first, const void* items, std::size_t count)
{
  auto& s = *state_;
  const auto& spec = s.spec(stream);
  check_write(spec, s.state(stream).count, first, count);
  return s.context.write_queued(s.state(stream).buffer, items, count * spec.element_bytes, first * spec.element_bytes);
}

void Scheduler::copy(StreamId source, std::size_t source_first, StreamId destination, std::size_t destination_first,
                     std::size_t count)
{
  auto& s = *state_;
  const auto &from = s.spec(source), &to = s.spec(destination);
  if (from.element_bytes != to.element_bytes || source_first + count > s.state(source).count ||
      destination_first + count > s.state(destination).count || to.variable)
    throw Error("cannot copy " + std::to_string(count) + " items from stream " + from.name + " to " + to.name);
  s.context.copy(s.state(source).buffer, s.state(destination).buffer, count * from.element_bytes,
                 source_first * from.element_bytes, destination_first * to.element_bytes);
}

std::size_t Scheduler::count(StreamId stream) const { return state_->state(stream).count; }
std::size_t Scheduler::capacity(StreamId stream) const { return state_->state(stream).capacity; }

void Scheduler::set_capacity(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (!s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is fixed-length; resize it instead");
  s.settle_stats();
  auto& st = s.state(stream);
  const std::size_t kept = std::min(st.count, items);
  const Buffer old = st.buffer;  // held until its first items are copied over
  s.scratch.with_memory([&] { s.buffers.allocate(stream, items); });
  if (kept > 0) s.context.copy(old, st.buffer, kept * s.spec(stream).element_bytes);
  st.count = kept;
  st.handed_to.clear();
}

void Scheduler::set_limit(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (!s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is fixed-length and never grows");
  s.state(stream).limit = items;
  if (s.state(stream).capacity > items) set_capacity(stream, items);
}

void Scheduler::resize(StreamId stream, std::size_t items)
{
  auto& s = *state_;
  if (s.spec(stream).variable) throw Error("stream " + s.spec(stream).name + " is variable-length; its passes size it");
  s.settle_stats();
  if (items != s.state(stream).capacity) s.buffers.allocate(stream, items);
  s.state(stream).count = items;
}

void Scheduler::swap(StreamId a, StreamId b)
{
  auto& s = *state_;
  const auto &sa = s.spec(a), &sb = s.spec(b);
  if (sa.element_bytes != sb.element_bytes || sa.variable != sb.variable)
    throw Error("streams " + sa.name + " and " + sb.name + " differ in element size or kind and cannot swap");
  s.settle_stats();
  auto &x = s.state(a), &y = s.state(b);
  std::swap(x.buffer, y.buffer);
  std::swap(x.count, y.count);
  std::swap(x.capacity, y.capacity);
  std::swap(x.known, y.known);
  std::swap(x.partial, y.partial);
  std::swap(x.handed_to, y.handed_to);
  std::swap(x.arena_at, y.arena_at);
}

const Buffer& Scheduler::buffer(StreamId stream) const { return state_->state(stream).buffer; }

void Scheduler::set(ParamId param, const void* bytes, std::size_t size)
{
  auto& s = *state_;
  const auto& spec = s.graph.params().at(param.index);
  if (size != spec.bytes)
    throw Error("parameter " + spec.name + " takes " + std::to_string(spec.bytes) + " bytes, not " + std::to_string(size));
  auto& v = s.params[param.index];
  v.assign(static_cast<const unsigned char*>(bytes), static_cast<const unsigned char*>(bytes) + size);
}

const StreamGraph& Scheduler::graph() const { return state_->graph; }

std::vector<std::string> Scheduler::execution_order() const
{
  std::vector<std::string> names;
  for (const auto& p : state_->passes) names.push_back(p.spec->name);
  return names;
}

const RunStats& Scheduler::stats() const
{
  state_->settle_stats();
  return state_->stats;
}
Registration Scheduler::registration() const { return state_->options.registration; }

}  // namespace cstreams::runtime
