#include "work_list.hpp"

#include "growth.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <string>
#include <utility>

namespace cstreams::runtime {

namespace {

void note_held(ListState& l)
{
  l.held_bytes = std::max(l.held_bytes, l.state.bytes() + l.lists[0].bytes() + l.lists[1].bytes());
}

void give_back_lists(ListState& l, ListHost& host)
{
  l.capacity = 0;
  for (int k = 0; k < 2; ++k) host.give_back(l.lists[k], l.lists_at[k]);
}

void allocate_lists(ListState& l, std::size_t items, std::size_t item_bytes, ListHost& host)
{
  // The old memory goes back before more is taken; a failed allocation leaves no
  // capacity that the buffers do not have.
  give_back_lists(l, host);
  for (int k = 0; k < 2; ++k)
    host.take(l.lists[k], l.lists_at[k], std::max<std::size_t>(items, 1) * item_bytes, "work list");
  l.capacity = items;
  note_held(l);
}

// Grows the lists to `items`, keeping the first `kept` items of lists[keep]: the input
// of a round that overflowed. The other list goes back first and the kept one once
// copied, so no more is held at once than two lists of the new size.
void grow_lists(ListState& l, std::size_t items, std::size_t item_bytes, unsigned keep, std::size_t kept,
                ListHost& host)
{
  Buffer input = std::move(l.lists[keep]);
  std::size_t input_at = std::exchange(l.lists_at[keep], StepArena::none);
  l.capacity = 0;
  host.give_back(l.lists[1 - keep], l.lists_at[1 - keep]);
  host.take(l.lists[keep], l.lists_at[keep], items * item_bytes, "work list");
  host.context.copy(input, l.lists[keep], kept * item_bytes, 0, 0, host.timeline);
  host.give_back(input, input_at);
  host.take(l.lists[1 - keep], l.lists_at[1 - keep], items * item_bytes, "work list");
  l.capacity = items;
  note_held(l);
}

// After a run's rounds (or a slice's, `widest` the most any round of the run held so
// far): lists more than twice what it needed (a burst that has passed) go back, and
// the next run takes lists of that size, so that a detector held for many steps holds
// what its steps need. Lists grow to no more than twice what their run needed, so a
// run like the last keeps them. Lists taken anew each run (from the step arena) take
// `needed`: in a sequence whose rounds widen step by step (a cloth settling on a
// sphere), what the last step outgrew the one before by, twice, saves a replay a step.
void keep_needed_lists(ListState& l, std::size_t widest, std::size_t item_bytes, ListHost& host)
{
  const std::size_t needed = grown(widest);
  l.needed = needed + 2 * (widest - std::min(widest, l.widest));
  l.widest = widest;
  if (l.capacity <= 2 * needed || l.capacity * item_bytes <= kept_list_bytes) return;
  give_back_lists(l, host);
  l.released = needed;
}

}  // namespace

void refine(const PassSpec& spec, ListState& l, PassStats& stats, std::size_t n, ListHost& host)
{
  const Worklist& w = *spec.worklist;
  const std::string& label = spec.name;
  const std::size_t wg = host.context.work_group_size();
  const std::size_t round_group = w.round_group ? std::min(w.round_group, wg) : wg;
  const bool bounded_loops = host.context.loop_trip_limit() != 0;
  // The last batch's counts, brought by the stage's counter read: the rounds go on.
  if (l.awaiting && settle_list(spec, l, stats, host)) return;
  if (l.reseed) {
    const std::size_t state_bytes = w.state_bytes + (host.extra_state ? w.extra_state_bytes : 0);
    const std::size_t state_needed = std::max<std::size_t>(n, 1) * state_bytes;
    const std::size_t held = state_needed + 2 * grown(n) * w.item_bytes;
    if (w.most_bytes && n > 1 && held > w.most_bytes)
      throw WorkListOverBudget("the work list of " + label, held,
                               "a work list may take at most " + mebibytes(w.most_bytes));
    // A state far larger than this run's goes back too (keep_needed_lists).
    if (l.state.bytes() > 2 * state_needed + kept_list_bytes) host.give_back(l.state, l.state_at);
    host.take(l.state, l.state_at, state_needed, "work list state");
    if (n == 0) {
      keep_needed_lists(l, 0, w.item_bytes, host);
      return;
    }
    // Lists taken by memory pressure come back at their size, not at one that the
    // rounds would overflow again.
    if (l.capacity < n) allocate_lists(l, std::max(grown(n), l.released), w.item_bytes, host);
    l.released = 0;
    note_held(l);
  }
  std::uint32_t* const counts = host.counts;
  do {
    if (l.reseed) {
      l.reseed = false;
      // The seed sets its counts up from zeros (worklist.h); those of a run's first
      // seed were cleared with the run's counters.
      if (!l.counts_clear) host.context.fill_u32(host.counters, 0, l.counts_at, list_words, host.timeline);
      l.counts_clear = false;
      unsigned a = host.bind_own_args(l.seed);
      l.seed.set_arg(a++, l.state);
      l.seed.set_arg(a++, l.lists[0]);
      l.seed.set_arg(a++, l.counts);
      l.seed.set_arg(a++, cl_uint(l.capacity));
      host.context.launch(l.seed, round_up(n, round_group), round_group, host.timeline, label);
      ++stats.launches;
      // Rounds launched over exactly their items must know the seed's.
      if (bounded_loops) {
        host.context.read(l.counts, counts, list_count_bytes, 0, host.timeline);
        ++host.readbacks;
      }
      l.at_round = 0;
      l.batch = bounded_loops ? 1 : std::max(*std::max_element(l.recent_rounds.begin(), l.recent_rounds.end()), 1u);
      l.next_batch = l.runs_settled ? 2 : 8;
    }
    for (const unsigned last = l.at_round + l.batch; l.at_round < last; ++l.at_round) {
      const unsigned round = l.at_round;
      unsigned r = host.bind_own_args(l.round);
      l.round.set_arg(r++, l.state);
      l.round.set_arg(r++, l.lists[round % 2]);
      l.round.set_arg(r++, l.lists[(round + 1) % 2]);
      l.round.set_arg(r++, l.counts);
      l.round.set_arg(r++, cl_uint(round));
      l.round.set_arg(r++, cl_uint(l.capacity));
      const std::size_t items = bounded_loops ? std::min<std::size_t>(counts[round % 3], l.capacity) : w.round_items;
      host.context.launch(l.round, round_up(items, round_group), round_group, host.timeline, label);
      ++stats.launches;
    }
    if (!bounded_loops) {
      l.awaiting = true;
      return;
    }
    host.context.read(l.counts, counts, list_count_bytes, 0, host.timeline);
    ++host.readbacks;
  } while (!settle_list(spec, l, stats, host));
}

bool settle_list(const PassSpec& spec, ListState& l, PassStats& stats, ListHost& host)
{
  const Worklist& w = *spec.worklist;
  const std::string& label = spec.name;
  std::uint32_t* const counts = host.counts;
  l.awaiting = false;
  // A search deeper than this is a kernel that never settles, not work.
  constexpr unsigned most_rounds = 1u << 20;
  if (counts[8])
    throw Error("pass " + label + ": device " + host.context.device().name + " ended a round's loops early, after " +
                std::to_string(host.context.loop_trip_limit()) + " trips; its results would be incomplete");
  if (l.batch_finished(counts)) {
    l.recent_rounds[l.runs_settled++ % l.recent_rounds.size()] = counts[7];
    stats.rounds += counts[7];
    stats.list_items += std::uint64_t(counts[4]) | std::uint64_t(counts[5]) << 32;
    stats.widest_list = std::max<std::size_t>(stats.widest_list, counts[6]);
    keep_needed_lists(l, stats.widest_list, w.item_bytes, host);
    l.reseed = true;
    return true;
  }
  if (counts[3] <= l.capacity) {
    if (l.at_round >= most_rounds)
      throw Error("pass " + label + ": its work list still holds " + std::to_string(counts[l.at_round % 3]) +
                  " items after " + std::to_string(l.at_round) + " rounds");
    if (host.context.loop_trip_limit() == 0) {
      l.batch = l.next_batch;
      l.next_batch *= 2;
    }
    return false;
  }
  ++stats.reruns;
  const std::size_t needed = std::max(grown(counts[3]), 2 * l.capacity);
  // Rounds after the one that overflowed did nothing; where no round ran, the seed's
  // own first items overflowed.
  if (counts[7] == 0) {
    allocate_lists(l, needed, w.item_bytes, host);
    l.reseed = true;
    return false;
  }
  const unsigned round = l.at_round = counts[7] - 1;
  grow_lists(l, needed, w.item_bytes, round % 2, counts[round % 3], host);
  counts[(round + 1) % 3] = counts[3] = counts[10] = 0;
  counts[11] = round + 1;
  for (const std::size_t word : {std::size_t((round + 1) % 3), std::size_t(3), std::size_t(10), std::size_t(11)})
    host.context.fill_u32(l.counts, counts[word], word, 1, host.timeline);
  return false;
}

}  // namespace cstreams::runtime
