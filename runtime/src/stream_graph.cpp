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

namespace {

// Throws naming the pass where its launch, work list or parameters break a rule of
// PassSpec.
void check_launch(const StreamGraph& g, std::size_t p)
{
  const auto& passes = g.passes();
  const auto& params = g.params();
  const auto& pass = passes[p];
  const std::size_t streams = g.streams().size();
  if (pass.launches_over_stream() && pass.over.index >= streams)
    throw Error("pass " + pass.name + " is launched over an unknown stream");
  for (std::size_t q = 0; q < p; ++q)
    if (passes[q].name == pass.name) throw Error("two passes are named " + pass.name);
  for (StreamId s : pass.also_over)
    if (s.index >= streams) throw Error("pass " + pass.name + " is launched over an unknown stream");
  if ((pass.culls() || pass.worklist) && !pass.also_over.empty())
    throw Error("pass " + pass.name + " culls or refines a work list, so it must be launched over one stream");
  if (pass.culls() && pass.cull_source != pass.over)
    throw Error("pass " + pass.name + " culls " + g.stream(pass.cull_source).name + " but is launched over " +
                g.stream(pass.over).name);
  const auto four_bytes = [&](ParamId param) { return param.index < params.size() && params[param.index].bytes == 4; };
  if (const auto& w = pass.worklist) {
    if (!pass.launches_over_stream() || w->seed.empty() || w->round.empty() || w->item_bytes == 0 ||
        w->item_bytes % 4 != 0 || w->state_bytes == 0 || w->state_bytes % 4 != 0 || w->round_items == 0 || !pass.updates.empty())
      throw Error("pass " + pass.name +
                  " refines a work list but lacks an input stream, a seed or round kernel, a round size or "
                  "item and state sizes in whole words, or updates a stream in place");
    if (w->extra_state_bytes % 4 != 0 || (w->extra_state_bytes > 0 && !four_bytes(w->extra_state_while)))
      throw Error("pass " + pass.name + " keeps extra state that is not in whole words or not behind a 4-byte parameter");
  }
  if (pass.conditional() && (!four_bytes(pass.runs_while) || !pass.emits.empty() || pass.culls() || pass.worklist))
    throw Error("pass " + pass.name + " runs only while a parameter is set, but that is not a 4-byte parameter, or the "
                "pass emits, culls or refines a work list");
  if (!pass.variant_kernel.empty() && (!four_bytes(pass.variant_while) || pass.worklist))
    throw Error("pass " + pass.name + " launches " + pass.variant_kernel +
                " while a parameter is set, but that is not a 4-byte parameter, or the pass refines a work list");
}

// Throws naming the pass where what it writes, emits, culls or hands over breaks a
// rule of PassSpec.
void check_outputs(const StreamGraph& g, const PassSpec& pass)
{
  for (StreamId s : pass.updates) {
    if (g.stream(s).variable) throw Error("pass " + pass.name + " updates variable-length stream " + g.stream(s).name);
    if (!pass.emits.empty() || pass.culls())
      throw Error("pass " + pass.name + " updates " + g.stream(s).name +
                  " in place but also emits or culls, and so may be rerun");
  }
  for (StreamId s : pass.lowers)
    if (g.stream(s).variable) throw Error("pass " + pass.name + " lowers variable-length stream " + g.stream(s).name);
  for (StreamId s : pass.emits)
    if (!g.stream(s).variable) throw Error("pass " + pass.name + " emits into fixed-length stream " + g.stream(s).name);
  for (StreamId s : pass.writes)
    if (g.stream(s).variable)
      throw Error("pass " + pass.name + " writes variable-length stream " + g.stream(s).name + " without emitting");
  if (pass.stops() && std::find(pass.writes.begin(), pass.writes.end(), pass.stop_flag) == pass.writes.end())
    throw Error("pass " + pass.name + " stops the run on a flag it does not write");
  if (pass.culls() && !g.stream(pass.cull_target).variable)
    throw Error("pass " + pass.name + " compacts into fixed-length stream " + g.stream(pass.cull_target).name);
  for (const auto& [input, output] : pass.handovers) {
    const auto inputs = pass_inputs(pass);
    const std::string what = "pass " + pass.name + " hands the buffer of " + g.stream(input).name + " over to " +
                             g.stream(output).name;
    if (std::find(inputs.begin(), inputs.end(), input) == inputs.end() ||
        std::find(pass.emits.begin(), pass.emits.end(), output) == pass.emits.end() || !g.stream(input).variable ||
        g.stream(input).element_bytes != g.stream(output).element_bytes)
      throw Error(what + ": it must read the first, a variable stream, and emit the second, with items of the same size");
    for (const auto& other : g.passes()) {
      const auto reads = pass_inputs(other);
      if (&other != &pass && std::find(reads.begin(), reads.end(), input) != reads.end())
        throw Error(what + ", but pass " + other.name + " reads it too");
    }
  }
}

// Each stream's writer (-1: none), and the passes that update or lower it in place, in
// declaration order.
struct Producers {
  std::vector<long> writer;
  std::vector<std::vector<std::size_t>> updaters;
};

void add_producer(const StreamGraph& g, std::size_t p, Producers& producers)
{
  const auto& pass = g.passes()[p];
  for (StreamId s : pass.updates) producers.updaters[s.index].push_back(p);
  for (StreamId s : pass.lowers) producers.updaters[s.index].push_back(p);
  for (StreamId s : pass_outputs(pass)) {
    if (in_place(pass, s)) continue;
    long& writer = producers.writer[s.index];
    if (writer >= 0)
      throw Error("stream " + g.stream(s).name + " is written by both " + g.passes()[std::size_t(writer)].name +
                  " and " + pass.name);
    writer = long(p);
  }
}

// The passes each pass waits for: the writers and updaters of what it reads, and of
// what it updates the writer and the updaters declared before it.
std::vector<std::vector<std::size_t>> dependencies(const StreamGraph& g, const Producers& producers)
{
  const auto& passes = g.passes();
  std::vector<std::vector<std::size_t>> deps(passes.size());
  for (std::size_t p = 0; p < passes.size(); ++p) {
    const auto outputs = pass_outputs(passes[p]);
    for (StreamId s : pass_inputs(passes[p])) {
      if (std::find(outputs.begin(), outputs.end(), s) != outputs.end())
        throw Error("pass " + passes[p].name + " both reads and writes stream " + g.stream(s).name);
      if (producers.writer[s.index] >= 0) deps[p].push_back(std::size_t(producers.writer[s.index]));
      for (std::size_t u : producers.updaters[s.index]) deps[p].push_back(u);  // readers see every update
    }
    std::vector<StreamId> in_place_outputs = passes[p].updates;
    in_place_outputs.insert(in_place_outputs.end(), passes[p].lowers.begin(), passes[p].lowers.end());
    for (StreamId s : in_place_outputs) {
      if (producers.writer[s.index] >= 0) deps[p].push_back(std::size_t(producers.writer[s.index]));
      for (std::size_t u : producers.updaters[s.index])
        if (u < p) deps[p].push_back(u);  // updates apply in declaration order
    }
  }
  return deps;
}

// Among passes free to go, declaration order; throws naming the passes of a cycle.
std::vector<std::size_t> in_dependency_order(const StreamGraph& g, const std::vector<std::vector<std::size_t>>& deps)
{
  const auto& passes = g.passes();
  std::vector<std::size_t> order;
  std::vector<bool> done(passes.size(), false);
  while (order.size() < passes.size()) {
    bool progressed = false;
    for (std::size_t p = 0; p < passes.size() && !progressed; ++p) {
      if (done[p]) continue;
      if (std::all_of(deps[p].begin(), deps[p].end(), [&](std::size_t d) { return done[d]; })) {
        done[p] = true;
        order.push_back(p);
        progressed = true;
      }
    }
    if (!progressed) {
      std::string stuck;
      for (std::size_t p = 0; p < passes.size(); ++p)
        if (!done[p]) stuck += (stuck.empty() ? "" : ", ") + passes[p].name;
      throw Error("the stream graph has a cycle among passes " + stuck);
    }
  }
  return order;
}

}  // namespace

std::vector<std::size_t> StreamGraph::schedule() const
{
  Producers producers{std::vector<long>(streams_.size(), -1), std::vector<std::vector<std::size_t>>(streams_.size())};
  for (std::size_t p = 0; p < passes_.size(); ++p) {
    check_launch(*this, p);
    check_outputs(*this, passes_[p]);
    add_producer(*this, p, producers);
  }
  return in_dependency_order(*this, dependencies(*this, producers));
}

}  // namespace cstreams::runtime
