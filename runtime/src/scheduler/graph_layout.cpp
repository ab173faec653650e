#include "graph_layout.hpp"

#include "registrar.hpp"

#include <cstreams/runtime/context.hpp>

#include <algorithm>

namespace cstreams::runtime {

std::size_t work_group_of(const PassSpec& spec, const Context& context)
{
  const std::size_t wg = context.work_group_size();
  return spec.group ? std::min(spec.group, wg) : wg;
}

namespace {

PassState make_pass(Context& context, const PassSpec& spec, Registration preferred, std::uint32_t& slots)
{
  PassState p;
  p.spec = &spec;
  const Registration registration = registration_of(spec, preferred);
  p.kernel = build_pass_kernel(context, spec, registration, spec.kernel.kernel);
  if (!spec.variant_kernel.empty()) p.variant = build_pass_kernel(context, spec, registration, spec.variant_kernel);
  if (registration == Registration::global_atomic) {
    p.atomic_kernel = p.kernel;
    p.atomic_variant = p.variant;
  }
  if (const auto& w = spec.worklist) {
    auto& l = p.list.emplace();
    l.seed = build_pass_kernel(context, spec, registration, w->seed);
    l.round = build_pass_kernel(context, spec, registration, w->round);
  }
  for (StreamId e : spec.emits) {
    EmitterState es;
    es.stream = e;
    es.expected = spec.expected_items(e);
    es.group = work_group_of(spec, context);
    for (const auto& [input, output] : spec.handovers)
      if (output == e) es.handed_from = input;
    es.overflow_slot = slots++;
    p.emitters.push_back(std::move(es));
  }
  p.inputs = pass_inputs(spec);
  p.stats.name = spec.name;
  return p;
}

}  // namespace

// The streams' buffers and counter slots, and the passes in execution order with their
// kernels; returns the counter words they take.
std::uint32_t lay_out(Context& context, const StreamGraph& graph, Registration registration, StreamBuffers& buffers,
                      std::vector<PassState>& passes)
{
  std::vector<StreamState>& streams = buffers.all();
  const auto order = graph.schedule();
  std::uint32_t slots = 0;
  streams.resize(graph.streams().size());
  std::vector<bool> handed_over(streams.size(), false);  // takes an input's buffer from its first run
  for (const auto& pass : graph.passes())
    for (const auto& handover : pass.handovers) handed_over[handover.second.index] = true;
  for (std::size_t i = 0; i < streams.size(); ++i) {
    const auto& spec = graph.streams()[i];
    buffers.allocate(StreamId{std::uint32_t(i)}, handed_over[i] ? 0 : spec.size);
    if (spec.variable) streams[i].slot = slots++;
    else streams[i].count = spec.size;
  }
  for (const auto& pass : graph.passes()) {
    for (StreamId e : pass.emits) streams[e.index].transient = true;
    if (pass.culls()) streams[pass.cull_target.index].transient = true;
  }
  for (const auto& pass : graph.passes())
    for (const auto& [input, output] : pass.handovers) streams[input.index].transient = streams[output.index].transient = false;
  for (std::size_t i = 0; i < streams.size(); ++i)
    if (graph.streams()[i].gathered) streams[i].transient = false;
  for (std::size_t index : order) passes.push_back(make_pass(context, graph.passes()[index], registration, slots));
  // A work list held to a budget runs in slices without memory running short, through
  // the global counter from there on: those kernels are built now, not in the step
  // that first needs them (the 1.5M-triangle sheet's surge step waited 50-100 ms on
  // NVIDIA's compiler for one where the driver's cache lacked it).
  const auto budgeted = std::find_if(passes.begin(), passes.end(), [](const PassState& p) {
    return p.spec->worklist && p.spec->worklist->most_bytes > 0;
  });
  for (auto p = budgeted; p != passes.end(); ++p) build_fallback(context, *p);
  return slots;
}

}  // namespace cstreams::runtime
