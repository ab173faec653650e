#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <algorithm>

namespace cstreams::runtime {

StreamId StreamGraph::fixed(std::string name, std::size_t element_bytes, std::size_t count)
{
  if (element_bytes == 0 || element_bytes % 4 != 0)
    throw Error("stream " + name + ": element size " + std::to_string(element_bytes) + " is not a multiple of 4 bytes");
  streams_.push_back({std::move(name), element_bytes, false, count});
  return StreamId{std::uint32_t(streams_.size() - 1)};
}

StreamId StreamGraph::variable(std::string name, std::size_t element_bytes, std::size_t initial_capacity)
{
  StreamId id = fixed(std::move(name), element_bytes, initial_capacity);
  streams_.back().variable = true;
  return id;
}

void StreamGraph::gather(StreamId stream)
{
  StreamSpec& s = streams_.at(stream.index);
  if (!s.variable) throw Error("stream " + s.name + " is fixed-length: a run writes all of it, so there is nothing to gather");
  if (s.within_run) throw Error("stream " + s.name + " lives within a run, so there is nothing to gather for the caller");
  s.gathered = true;
}

void StreamGraph::within_run(StreamId stream)
{
  StreamSpec& s = streams_.at(stream.index);
  if (!s.variable) throw Error("stream " + s.name + " is fixed-length: it lives from run to run");
  if (s.gathered) throw Error("stream " + s.name + " is gathered for the caller, so it outlives its run");
  s.within_run = true;
}

ParamId StreamGraph::param(std::string name, std::size_t bytes)
{
  params_.push_back({std::move(name), bytes});
  return ParamId{std::uint32_t(params_.size() - 1)};
}

PassSpec& StreamGraph::pass(std::string name, KernelRef kernel)
{
  passes_.emplace_back();
  passes_.back().name = std::move(name);
  passes_.back().kernel = std::move(kernel);
  return passes_.back();
}

const StreamSpec& StreamGraph::stream(StreamId s) const
{
  if (s.index >= streams_.size()) throw Error("unknown stream id " + std::to_string(s.index));
  return streams_[s.index];
}

namespace {

bool in_place(const PassSpec& p, StreamId s)
{
  return std::find(p.updates.begin(), p.updates.end(), s) != p.updates.end() ||
         std::find(p.lowers.begin(), p.lowers.end(), s) != p.lowers.end();
}

}  // namespace

std::vector<StreamId> pass_outputs(const PassSpec& p)
{
  std::vector<StreamId> out = p.writes;
  out.insert(out.end(), p.emits.begin(), p.emits.end());
  if (p.culls()) out.push_back(p.cull_target);
  out.insert(out.end(), p.updates.begin(), p.updates.end());
  out.insert(out.end(), p.lowers.begin(), p.lowers.end());
  return out;
}

std::vector<StreamId> pass_inputs(const PassSpec& p)
{
  std::vector<StreamId> in = p.reads;
  if (p.launches_over_stream()) in.push_back(p.over);
  in.insert(in.end(), p.also_over.begin(), p.also_over.end());
  if (p.culls()) in.push_back(p.cull_source);
  const auto outputs = pass_outputs(p);
  for (const auto& a : p.args)
    if (auto b = std::get_if<BufferArg>(&a))
      if (std::find(outputs.begin(), outputs.end(), b->stream) == outputs.end()) in.push_back(b->stream);
  // A stream updated or lowered in place is the pass's output, ordered as such, not an input.
  in.erase(std::remove_if(in.begin(), in.end(), [&](StreamId s) { return in_place(p, s); }), in.end());
  return in;
}

std::vector<std::size_t> StreamGraph::schedule() const
{
  std::vector<long> writer(streams_.size(), -1);
  std::vector<std::vector<std::size_t>> updaters(streams_.size());  // declaration order
  for (std::size_t p = 0; p < passes_.size(); ++p) {
    const auto& pass = passes_[p];
    if (pass.launches_over_stream() && pass.over.index >= streams_.size())
      throw Error("pass " + pass.name + " is launched over an unknown stream");
    for (std::size_t q = 0; q < p; ++q)
      if (passes_[q].name == pass.name) throw Error("two passes are named " + pass.name);
    for (StreamId s : pass.also_over)
      if (s.index >= streams_.size()) throw Error("pass " + pass.name + " is launched over an unknown stream");
    if ((pass.culls() || pass.worklist) && !pass.also_over.empty())
      throw Error("pass " + pass.name + " culls or refines a work list, so it must be launched over one stream");
    if (pass.culls() && pass.cull_source != pass.over)
      throw Error("pass " + pass.name + " culls " + stream(pass.cull_source).name + " but is launched over " +
                  stream(pass.over).name);
    if (const auto& w = pass.worklist) {
      if (!pass.launches_over_stream() || w->seed.empty() || w->round.empty() || w->item_bytes == 0 ||
          w->item_bytes % 4 != 0 || w->state_bytes == 0 || w->state_bytes % 4 != 0 || w->round_items == 0 || !pass.updates.empty())
        throw Error("pass " + pass.name +
                    " refines a work list but lacks an input stream, a seed or round kernel, a round size or "
                    "item and state sizes in whole words, or updates a stream in place");
      if (w->extra_state_bytes % 4 != 0 ||
          (w->extra_state_bytes > 0 &&
           (w->extra_state_while.index >= params_.size() || params_[w->extra_state_while.index].bytes != 4)))
        throw Error("pass " + pass.name + " keeps extra state that is not in whole words or not behind a 4-byte parameter");
    }
    if (pass.conditional() &&
        (pass.runs_while.index >= params_.size() || params_[pass.runs_while.index].bytes != 4 || !pass.emits.empty() ||
         pass.culls() || pass.worklist))
      throw Error("pass " + pass.name + " runs only while a parameter is set, but that is not a 4-byte parameter, or the "
                  "pass emits, culls or refines a work list");
    if (!pass.variant_kernel.empty() &&
        (pass.variant_while.index >= params_.size() || params_[pass.variant_while.index].bytes != 4 || pass.worklist))
      throw Error("pass " + pass.name + " launches " + pass.variant_kernel +
                  " while a parameter is set, but that is not a 4-byte parameter, or the pass refines a work list");
    for (StreamId s : pass.updates) {
      if (stream(s).variable) throw Error("pass " + pass.name + " updates variable-length stream " + stream(s).name);
      if (!pass.emits.empty() || pass.culls())
        throw Error("pass " + pass.name + " updates " + stream(s).name +
                    " in place but also emits or culls, and so may be rerun");
      updaters[s.index].push_back(p);
    }
    for (StreamId s : pass.lowers) {
      if (stream(s).variable) throw Error("pass " + pass.name + " lowers variable-length stream " + stream(s).name);
      updaters[s.index].push_back(p);
    }
    for (StreamId s : pass_outputs(pass)) {
      if (in_place(pass, s)) continue;
      const auto& spec = stream(s);
      if (writer[s.index] >= 0)
        throw Error("stream " + spec.name + " is written by both " + passes_[writer[s.index]].name + " and " + pass.name);
      writer[s.index] = long(p);
    }
    for (StreamId s : pass.emits)
      if (!stream(s).variable) throw Error("pass " + pass.name + " emits into fixed-length stream " + stream(s).name);
    for (StreamId s : pass.writes)
      if (stream(s).variable)
        throw Error("pass " + pass.name + " writes variable-length stream " + stream(s).name + " without emitting");
    if (pass.stops() &&
        std::find(pass.writes.begin(), pass.writes.end(), pass.stop_flag) == pass.writes.end())
      throw Error("pass " + pass.name + " stops the run on a flag it does not write");
    if (pass.culls() && !stream(pass.cull_target).variable)
      throw Error("pass " + pass.name + " compacts into fixed-length stream " + stream(pass.cull_target).name);
    for (const auto& [input, output] : pass.handovers) {
      const auto inputs = pass_inputs(pass);
      if (std::find(inputs.begin(), inputs.end(), input) == inputs.end() ||
          std::find(pass.emits.begin(), pass.emits.end(), output) == pass.emits.end() || !stream(input).variable ||
          stream(input).element_bytes != stream(output).element_bytes)
        throw Error("pass " + pass.name + " hands the buffer of " + stream(input).name + " over to " +
                    stream(output).name + ": it must read the first, a variable stream, and emit the second, "
                    "with items of the same size");
      for (const auto& other : passes_) {
        const auto reads = pass_inputs(other);
        if (&other != &pass && std::find(reads.begin(), reads.end(), input) != reads.end())
          throw Error("pass " + pass.name + " hands the buffer of " + stream(input).name + " over to " +
                      stream(output).name + ", but pass " + other.name + " reads it too");
      }
    }
  }

  std::vector<std::vector<std::size_t>> deps(passes_.size());
  for (std::size_t p = 0; p < passes_.size(); ++p) {
    const auto outputs = pass_outputs(passes_[p]);
    for (StreamId s : pass_inputs(passes_[p])) {
      if (std::find(outputs.begin(), outputs.end(), s) != outputs.end())
        throw Error("pass " + passes_[p].name + " both reads and writes stream " + stream(s).name);
      if (writer[s.index] >= 0) deps[p].push_back(std::size_t(writer[s.index]));
      for (std::size_t u : updaters[s.index]) deps[p].push_back(u);  // readers see every update
    }
    const auto& pass = passes_[p];
    std::vector<StreamId> in_place_outputs = pass.updates;
    in_place_outputs.insert(in_place_outputs.end(), pass.lowers.begin(), pass.lowers.end());
    for (StreamId s : in_place_outputs) {
      if (writer[s.index] >= 0) deps[p].push_back(std::size_t(writer[s.index]));
      for (std::size_t u : updaters[s.index])
        if (u < p) deps[p].push_back(u);  // updates apply in declaration order
    }
  }

  std::vector<std::size_t> order;
  std::vector<bool> done(passes_.size(), false);
  while (order.size() < passes_.size()) {
    bool progressed = false;
    for (std::size_t p = 0; p < passes_.size() && !progressed; ++p) {
      if (done[p]) continue;
      if (std::all_of(deps[p].begin(), deps[p].end(), [&](std::size_t d) { return done[d]; })) {
        done[p] = true;
        order.push_back(p);
        progressed = true;
      }
    }
    if (!progressed) {
      std::string stuck;
      for (std::size_t p = 0; p < passes_.size(); ++p)
        if (!done[p]) stuck += (stuck.empty() ? "" : ", ") + passes_[p].name;
      throw Error("the stream graph has a cycle among passes " + stuck);
    }
  }
  return order;
}

}  // namespace cstreams::runtime
