#include "late_packing.hpp"

#include "../step_arena.hpp"

#include <cstreams/runtime/error.hpp>

#include <algorithm>

namespace cstreams::runtime {

void LatePacker::pack(PassState& p)
{
  bool first = true;
  for (auto& e : p.emitters) {
    if (!registrar_.packs_late(p, e)) {
      leave_spent_where_pressed(p, e);
      continue;
    }
    if (!first && scratch_.use_arena()) give_back_spent_inputs(p, items(e) * streams_.spec(e.stream).element_bytes);
    first = false;
    if (Registrar::hands_over(p, e)) {
      hand_over(p, e);
    } else if (streams_.state(e.stream).capacity < items(e)) {
      scratch_.with_memory([&] { streams_.grow(e.stream, items(e), false); });
    }
    if (e.segments > 0) registrar_.merge_segments(p, e);
    if (scratch_.use_arena()) scratch_.drop_segments(e);
  }
}

// Once memory has run short, an output to be handed over that the pass wrote into a
// buffer of its own (through the global counter) leaves its input spent as a hand-over
// would: held beside it for the rest of the run, the front left the refinement no room
// under budgets above those that ran (NVIDIA, a generated n-body scene whose step peaks
// at 10.4 MiB: 8.0 and 8.2 MiB failed, 7.5 ran). Not before memory runs short: a run
// that registers through the global counter by choice keeps both buffers, which then
// swap from step to step without an allocation. Not where the pass runs in slices,
// whose later slices read the input.
void LatePacker::leave_spent_where_pressed(PassState& p, const EmitterState& e)
{
  if (scratch_.pressed() && e.handed_from != StreamId{} && std::size_t(&p - passes_.data()) < sliced_pass_)
    leave_spent(p, e);
}

// Before pass p packs an output of `bytes` late: its inputs that live within the run
// (StreamGraph::within_run) and that no pass after it reads go back, where the output
// then still fits in the arena's buffer (so that taking it allocates nothing and
// cannot fail, which would leave a pass to run again without its input). After its
// first output only: packed first, that one takes a place of its own, and the input's
// place joins the first output's segments for the rest. n-body's triangle pairs
// (35.1 MiB) so let its edge-edge candidates (59.0 MiB) pack where they and the
// vertex-face candidates' segments lay: the step held 387.6 MiB, now 328.6.
void LatePacker::give_back_spent_inputs(PassState& p, std::size_t bytes)
{
  const std::size_t at = std::size_t(&p - passes_.data());
  for (StreamId s : p.inputs) {
    auto& st = streams_.state(s);
    if (!streams_.spec(s).within_run || st.arena_at == StepArena::none || !arena_.fits_without(st.arena_at, bytes))
      continue;
    const bool read_later = std::any_of(passes_.begin() + std::ptrdiff_t(at) + 1, passes_.end(), [&](const PassState& q) {
      return std::find(q.inputs.begin(), q.inputs.end(), s) != q.inputs.end();
    });
    if (read_later) continue;
    st.released = std::max(st.released, st.capacity);
    streams_.drop(st);
    st.spent = true;
  }
}

// A handed-over output takes a buffer that holds its items (its own, else the
// input's, else a new one), and the other goes back. The input is left empty, which
// run() checks for before it reads the input again. Taking the input's buffer gives
// the input the output's, in steady state the empty one the input was left with last
// run, so that a step allocates nothing here. Where the output needs a new buffer, the
// input, spent, goes first where the new one fits the memory limit without it: the two
// fronts and the segments between them had set the 1.5M-triangle sheet's peak in each
// step where its front grew. Else the input is kept until the output has a buffer: the
// pass may then still run again, in slices, if there is no room for it.
void LatePacker::hand_over(PassState& p, const EmitterState& e)
{
  auto &in = streams_.state(e.handed_from), &out = streams_.state(e.stream);
  const std::size_t n = items(e);
  if (n > out.limit) throw StreamLimitExceeded(streams_.spec(e.stream).name, n, out.limit);
  if (out.capacity < n && in.capacity >= n) {
    std::swap(out.buffer, in.buffer);
    std::swap(out.capacity, in.capacity);
    out.peak_bytes = std::max(out.peak_bytes, out.buffer.bytes());
  }
  if (out.capacity < n) {
    const std::size_t bytes = streams_.grown_items(e.stream, n) * streams_.spec(e.stream).element_bytes;
    if (scratch_.fits_once_gone(in.buffer.bytes(), bytes)) leave_spent(p, e);
    scratch_.with_memory([&] { streams_.grow(e.stream, n); });
  }
  leave_spent(p, e);
}

// The input of a hand-over once its output holds the items: empty, and marked as
// given, which run() checks for before it reads the input again.
void LatePacker::leave_spent(PassState& p, const EmitterState& e)
{
  auto& in = streams_.state(e.handed_from);
  if (in.capacity > 0) streams_.allocate(e.handed_from, 0);
  in.count = 0;
  in.known = true;
  in.handed_to = streams_.spec(e.stream).name;
  p.handed_over = true;
}

}  // namespace cstreams::runtime
