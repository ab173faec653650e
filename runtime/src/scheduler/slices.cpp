#include "slices.hpp"

#include "growth.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <numeric>
#include <utility>

namespace cstreams::runtime {

void Slices::go_on(const Failure& failure)
{
  if (failure.error) {
    sliced_pass_ = slice_start(failure.pass);
    if (sliced_pass_ == SIZE_MAX) std::rethrow_exception(failure.error);
    slices_ = 1;
    try {
      std::rethrow_exception(failure.error);
    } catch (const std::exception& e) {
      short_of_memory_ = !dynamic_cast<const WorkListOverBudget*>(&e);
    }
  }
  run_in_slices(sliced_pass_);
}

// Only a pass over one stream can be sliced, and only where it reads that stream alone
// from there on (another pass would see a slice where it expects the stream); a
// culled stream would be compacted slice by slice over what it gathered before.
bool Slices::sliceable(std::size_t first) const
{
  const PassSpec& head = *p_.passes[first].spec;
  if (!head.launches_over_stream() || !head.also_over.empty() || head.culls()) return false;
  for (std::size_t j = first + 1; j < p_.passes.size(); ++j) {
    const auto& ins = p_.passes[j].inputs;
    if (std::find(ins.begin(), ins.end(), head.over) != ins.end()) return false;
    if (p_.passes[j].spec->culls() && p_.streams.spec(p_.passes[j].spec->cull_target).gathered) return false;
  }
  return true;
}

// Where slices start when pass `failed` finds no room: there, or where it cannot be
// sliced (a culling pass), at the nearest pass before it that can and that may run
// again (no pass from there on has packed an output into its input's buffer), so
// that smaller slices of that pass's work leave it room. SIZE_MAX: nowhere.
std::size_t Slices::slice_start(std::size_t failed) const
{
  for (std::size_t p = failed + 1; p-- > 0;) {
    if (p_.passes[p].handed_over) return SIZE_MAX;
    if (sliceable(p)) return p;
  }
  return SIZE_MAX;
}

// Items a slice of `total` holds when the run goes in `slices_` slices: a multiple of
// what starts a sub-buffer on the device's alignment.
std::size_t Slices::slice_items(StreamId over, std::size_t total) const
{
  const std::size_t bytes = p_.streams.spec(over).element_bytes, align = p_.context.device().base_address_align;
  const std::size_t step = align / std::gcd(align, bytes);
  return std::max(step, round_up((total + slices_ - 1) / slices_, step));
}

// Runs pass `first` and the rest of the graph in slices of its launch stream,
// doubling them until a slice fits.
void Slices::run_in_slices(std::size_t first)
{
  auto& passes = p_.passes;
  const StreamId over = passes[first].spec->over;
  // The passes that depend on what the sliced pass emits run every slice; the rest once.
  std::vector<bool> every_slice(passes.size(), false), sliced(p_.streams.all().size(), false);
  for (std::size_t j = first; j < passes.size(); ++j) {
    const auto& ins = passes[j].inputs;
    if (j == first || std::any_of(ins.begin(), ins.end(), [&](StreamId s) { return sliced[s.index]; })) {
      every_slice[j] = true;
      for (StreamId s : pass_outputs(*passes[j].spec)) sliced[s.index] = true;
    }
  }
  // Launch streams of those passes that come from passes run once count in the first
  // slice only, so that no item is tested twice.
  std::vector<StreamId> once;
  for (std::size_t j = first + 1; j < passes.size(); ++j) {
    if (!every_slice[j] || !passes[j].spec->launches_over_stream()) continue;
    std::vector<StreamId> launched{passes[j].spec->over};
    launched.insert(launched.end(), passes[j].spec->also_over.begin(), passes[j].spec->also_over.end());
    for (StreamId s : launched)
      if (!sliced[s.index] && s != over && std::find(once.begin(), once.end(), s) == once.end()) once.push_back(s);
  }
  // The variable streams the sliced passes emit, whose counts go slice by slice.
  std::vector<StreamId> outputs;
  for (std::uint32_t i = 0; i < sliced.size(); ++i)
    if (sliced[i] && p_.streams.spec(StreamId{i}).variable) outputs.push_back(StreamId{i});
  const std::size_t total = p_.streams.state(over).count;
  bool found = first == found_pass_ && found_input_ > 0;
  slices_ = found ? unsigned(std::max<std::size_t>(
                        1, (found_slices_ * std::min(total, found_input_) + found_input_ - 1) / found_input_))
                  : std::max(slices_, 2u);
  for (;;) {
    const std::size_t size = slice_items(over, total);
    try {
      run_slices(first, every_slice, outputs, once, size);
      if (!found) {
        found_slices_ = slices_;
        found_input_ = total;
        found_pass_ = first;
      }
      return;
    } catch (const DeviceMemoryExhausted& e) {
      if (size <= slice_items(over, 0) || slices_ >= (1u << 30)) throw;
      slices_ *= 2;
      found = false;
      if (!dynamic_cast<const WorkListOverBudget*>(&e)) short_of_memory_ = true;
    }
  }
}

// Before a run's slices: what an earlier attempt held goes back, and the outputs take
// what `count` slices of the last run's items need.
void Slices::prepare_slices(std::size_t first, const std::vector<bool>& every_slice,
                            const std::vector<StreamId>& outputs, std::size_t count)
{
  // What an earlier attempt held goes back: idle scratch where memory ran short, not
  // for a work list's budget (the 1.5M-triangle sheet, H200: its surge step, sliced for
  // its refinement's budget, had waited 54-87 ms on the host before the first slice in
  // three runs of five while the step arena went back and was taken anew, and the run
  // peaked at 2,639 MiB; without, 3 ms in both runs and 2,552 MiB); and sliced streams
  // beyond what a slice of the last run's items needs. The sliced passes register
  // through the global counter, whose memory is the streams themselves.
  p_.busy.clear();
  if (short_of_memory_) p_.scratch.release_idle();
  for (std::size_t j = first; j < p_.passes.size(); ++j)
    if (every_slice[j]) {
      PassState& pass = p_.passes[j];
      p_.registrar.fall_back_to_global_counter(pass);
      // A slice's work list is sized by the slice, not by what the whole input needed;
      // its statistics add up these slices alone, not an attempt that ran short.
      if (pass.list) {
        pass.list->released = 0;
        pass.stats.rounds = 0;
        pass.stats.list_items = 0;
        pass.stats.widest_list = 0;
      }
    }
  // A gathered stream takes what the last run gathered at once, instead of growing
  // slice by slice with its items held twice.
  for (const bool gathered : {false, true})
    for (StreamId s : outputs) {
      auto& st = p_.streams.state(s);
      if (p_.streams.spec(s).gathered != gathered) continue;
      st.base = st.earlier = st.released = 0;
      const std::size_t share = grown(gathered ? st.run_items : st.run_items / std::max<std::size_t>(count, 1));
      if (gathered ? st.capacity < st.run_items : st.capacity > share) p_.streams.grow(s, share, false);
    }
}

void Slices::run_slices(std::size_t first, const std::vector<bool>& every_slice, const std::vector<StreamId>& outputs,
                        const std::vector<StreamId>& once, std::size_t size)
{
  const StreamId over = p_.passes[first].spec->over;
  auto& in = p_.streams.state(over);
  const std::size_t total = in.count, count = std::max<std::size_t>(1, (total + size - 1) / size);
  prepare_slices(first, every_slice, outputs, count);
  // However the slices end, the input and the streams counted once are whole again.
  struct Whole {
    StreamState& in;
    const Buffer buffer;
    const std::size_t count;
    std::vector<std::pair<StreamState*, std::size_t>> once;
    std::vector<StreamState>& streams;
    ~Whole()
    {
      in.buffer = buffer;
      in.count = count;
      for (auto& [st, n] : once) st->count = n;
      for (auto& st : streams) st.base = 0;
    }
  } whole{in, in.buffer, in.count, {}, p_.streams.all()};
  const std::size_t bytes = p_.streams.spec(over).element_bytes;
  for (std::size_t k = 0, begin = 0; k == 0 || begin < total; ++k, begin += size) {
    const std::size_t n = std::min(size, total - begin);
    p_.streams.set_slices_left(count - std::min(count, k + 1));
    in.buffer = n > 0 ? whole.buffer.slice(begin * bytes, n * bytes) : whole.buffer;
    in.count = n;
    if (k == 1)
      for (StreamId s : once) {
        whole.once.emplace_back(&p_.streams.state(s), p_.streams.state(s).count);
        p_.streams.state(s).count = 0;
      }
    restart_slice(first, every_slice, k);
    std::vector<PassState*> stage;
    Failure failure;
    for (std::size_t j = first; j < p_.passes.size() && !failure; ++j)
      if (k == 0 || every_slice[j]) failure = p_.runner.step(p_.passes[j], stage);
    if (!failure) failure = p_.runner.end_stage(stage);
    if (failure) std::rethrow_exception(failure.error);
    for (StreamId s : outputs) {
      auto& st = p_.streams.state(s);
      if (p_.streams.spec(s).gathered) st.base = st.count;
      else if (begin + n < total) st.earlier += st.count;
    }
  }
  p_.stats.slices = unsigned(count);
  for (StreamId s : outputs) p_.streams.state(s).partial = p_.stats.slices > 1 && !p_.streams.spec(s).gathered;
  p_.stats.sliced_pass = p_.passes[first].spec->name;
}

// Before slice k: the counters clear (a gathered stream's from the items of earlier
// slices), and the passes that run in it start over.
void Slices::restart_slice(std::size_t first, const std::vector<bool>& every_slice, std::size_t k)
{
  p_.counters.clear_all();
  for (std::size_t j = first; j < p_.passes.size(); ++j) {
    if (k > 0 && !every_slice[j]) continue;
    if (p_.passes[j].list) p_.passes[j].list->restart();
    for (StreamId s : pass_outputs(*p_.passes[j].spec))
      if (p_.streams.spec(s).variable) {
        auto& st = p_.streams.state(s);
        st.known = false;
        if (st.base > 0) p_.counters.set(st.slot, std::uint32_t(st.base));
      }
  }
}

}  // namespace cstreams::runtime
