#include "binding.hpp"

#include <cstreams/runtime/error.hpp>

#include <variant>

namespace cstreams::runtime {

unsigned bind_own_args(const Bindings& b, const PassSpec& spec, const Kernel& k)
{
  unsigned index = 0;
  for (const auto& a : spec.args) {
    if (auto buffer = std::get_if<BufferArg>(&a)) k.set_arg(index, b.streams.at(buffer->stream.index).buffer);
    else if (auto count = std::get_if<CountArg>(&a)) k.set_arg(index, cl_uint(b.streams.at(count->stream.index).count));
    else if (auto value = std::get_if<ValueArg>(&a)) k.set_raw(index, value->bytes.size(), value->bytes.data());
    else {
      const std::size_t param = std::get<ParamArg>(a).param.index;
      const auto& bytes = b.params.at(param);
      if (bytes.empty())
        throw Error("pass " + spec.name + " needs parameter " + b.graph.params()[param].name + ", which was never set");
      k.set_raw(index, bytes.size(), bytes.data());
    }
    ++index;
  }
  return index;
}

namespace {

// An emitter's nine arguments, as CS_EMITTER_PARAMS declares them: where its items go,
// their counts and the capacity of each, the counters and its overflow slot, the plan,
// the segments it covers and the spill pool (segmented lock), and its count slot.
void bind_emitter(const Bindings& b, Registration mode, const EmitterState& e, const Kernel& k, unsigned& index)
{
  const StreamState& dst = b.streams.at(e.stream.index);
  const bool atomic = mode == Registration::global_atomic, locked = mode == Registration::segmented_lock;
  const std::size_t capacity =
      atomic ? dst.capacity : locked ? b.planner.first_segment_capacity(e) : e.segment_capacity;
  k.set_arg(index++, atomic ? dst.buffer : e.items);
  k.set_arg(index++, atomic ? b.counters : e.counts);
  k.set_arg(index++, cl_uint(capacity));
  k.set_arg(index++, b.counters);
  k.set_arg(index++, cl_uint(atomic ? dst.slot : e.overflow_slot));
  k.set_arg(index++, atomic ? b.counters : locked ? plan_of(e, b.no_plan) : e.counts);
  k.set_arg(index++, cl_uint(locked ? e.planned : 0));
  k.set_arg(index++, cl_uint(locked ? e.pool : 0));
  k.set_arg(index++, cl_uint(dst.slot));
}

}  // namespace

void bind_args(const Bindings& b, const PassState& p, const Kernel& k)
{
  unsigned index = bind_own_args(b, *p.spec, k);
  if (p.list) k.set_arg(index++, p.list->state);
  for (const auto& e : p.emitters) bind_emitter(b, p.mode, e, k, index);
  if (p.spec->culls()) k.set_arg(index++, p.keep);
}

}  // namespace cstreams::runtime
