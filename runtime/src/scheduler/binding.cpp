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

// An emitter's nine arguments: where its items go, its counts and capacity, the
// counters, its overflow slot, its plan and pool (segmented lock), and its count slot.
void bind_emitter(const Bindings& b, Registration mode, const EmitterState& e, const Kernel& k, unsigned& index)
{
  const StreamState& dst = b.streams.at(e.stream.index);
  if (mode == Registration::global_atomic) {
    k.set_arg(index++, dst.buffer);
    k.set_arg(index++, b.counters);
    k.set_arg(index++, cl_uint(dst.capacity));
    k.set_arg(index++, b.counters);
    k.set_arg(index++, cl_uint(dst.slot));
    k.set_arg(index++, b.counters);
    k.set_arg(index++, cl_uint(0));
    k.set_arg(index++, cl_uint(0));
  } else if (mode == Registration::segmented_lock) {
    k.set_arg(index++, e.items);
    k.set_arg(index++, e.counts);
    k.set_arg(index++, cl_uint(b.planner.first_segment_capacity(e)));
    k.set_arg(index++, b.counters);
    k.set_arg(index++, cl_uint(e.overflow_slot));
    k.set_arg(index++, e.planned ? e.plan : b.no_plan);
    k.set_arg(index++, cl_uint(e.planned));
    k.set_arg(index++, cl_uint(e.pool));
  } else {
    k.set_arg(index++, e.items);
    k.set_arg(index++, e.counts);
    k.set_arg(index++, cl_uint(e.segment_capacity));
    k.set_arg(index++, b.counters);
    k.set_arg(index++, cl_uint(e.overflow_slot));
    k.set_arg(index++, e.counts);
    k.set_arg(index++, cl_uint(0));
    k.set_arg(index++, cl_uint(0));
  }
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
