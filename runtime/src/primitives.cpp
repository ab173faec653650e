#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/primitives.hpp>

#include <algorithm>
#include <string>

namespace cstreams::runtime {

namespace {
// Items each work-item scans sequentially. GPUs want many work-items and a small tile
// in local memory; on a CPU every barrier is a loop over the work-group, so pocl does
// best with long sequential runs and few barriers per item. The tile (padded, see
// scan.cl) and the group's scratch must fit the device's local memory.
std::size_t scan_items_for(const Context& context)
{
  const std::size_t group = context.work_group_size();
  auto local_bytes = [&](std::size_t items) {
    const std::size_t tile = group * items;
    return 4 * (tile + tile / 32 + group);
  };
  std::size_t items = context.device().kind == DeviceKind::cpu ? 32 : 8;
  while (items > 1 && local_bytes(items) > context.device().local_memory) items /= 2;
  return items;
}

std::string scan_options(const Context& context) { return "-DCS_SCAN_ITEMS=" + std::to_string(scan_items_for(context)); }

// Inputs of up to this many tiles are scanned by one group, tile after tile, in one
// launch instead of two (the tile sums, then the tiles; each cost 4-8 us on the H100
// for inputs this short).
constexpr std::size_t one_group_tiles = 4;
// Inputs of up to this many tiles are scanned two at once, one group each: a group
// scans cloth-ball's front update's 21.8K segment counts (11 tiles) in about the time
// the two launches of a scan take.
constexpr std::size_t each_group_tiles = 16;
}  // namespace

Scan::Scan(Context& context)
    : context_(context),
      items_per_work_item_(scan_items_for(context)),
      reduce_(context.programs().kernel("runtime/scan.cl", "cs_scan_reduce", scan_options(context))),
      tiles_(context.programs().kernel("runtime/scan.cl", "cs_scan_tiles", scan_options(context))),
      one_group_(context.programs().kernel("runtime/scan.cl", "cs_scan_in_one_group", scan_options(context))),
      two_in_a_group_each_(
          context.programs().kernel("runtime/scan.cl", "cs_scan_two_in_a_group_each", scan_options(context))),
      compact_tiles_(context.programs().kernel("runtime/scan.cl", "cs_compact_tiles", scan_options(context))),
      compact_one_group_(context.programs().kernel("runtime/scan.cl", "cs_compact_in_one_group", scan_options(context)))
{
}

std::size_t Scan::tile_items() const { return context_.work_group_size() * items_per_work_item_; }

std::size_t Scan::scratch_bytes() const
{
  std::size_t total = 0;
  for (const auto& b : levels_) total += b.bytes();
  return total;
}

void Scan::exclusive(const Buffer& in, const Buffer& out, std::size_t n, const Buffer& counters, std::uint32_t slot,
                     Timeline* timeline, const char* label)
{
  if (n == 0) {
    if (slot != no_slot) context_.fill_u32(counters, 0, slot, 1, timeline);
    return;
  }
  level(in, out, n, counters, slot, 0, nullptr, timeline, label);
}

void Scan::exclusive_both(const Job& a, const Job& b, const Buffer& counters, Timeline* timeline, const char* label)
{
  const auto short_enough = [&](const Job& j) { return j.n > 0 && j.n <= each_group_tiles * tile_items(); };
  if (!short_enough(a) || !short_enough(b)) {
    exclusive(*a.in, *a.out, a.n, counters, a.slot, timeline, label);
    exclusive(*b.in, *b.out, b.n, counters, b.slot, timeline, label);
    return;
  }
  two_in_a_group_each_.set_args(*a.in, cl_uint(a.n), *a.out, a.slot, *b.in, cl_uint(b.n), *b.out, b.slot, counters);
  const std::size_t wg = context_.work_group_size();
  context_.launch(two_in_a_group_each_, 2 * wg, wg, timeline, label);
}

void Scan::compact(const Buffer& src, std::size_t words, const Buffer& keep, std::size_t n, const Buffer& dst,
                   std::size_t capacity, const Buffer& counters, std::uint32_t slot, Timeline* timeline,
                   const char* label)
{
  if (n == 0) {
    context_.fill_u32(counters, 0, slot, 1, timeline);
    return;
  }
  const Placement placement{&src, words, &dst, capacity};
  level(keep, keep, n, counters, slot, 0, &placement, timeline, label);
}

void Scan::level(const Buffer& in, const Buffer& out, std::size_t n, const Buffer& counters, std::uint32_t slot,
                 std::size_t depth, const Placement* placement, Timeline* timeline, const char* label)
{
  const std::size_t wg = context_.work_group_size();
  const std::size_t tiles = (n + tile_items() - 1) / tile_items();
  const cl_uint count = cl_uint(n);
  if (tiles <= one_group_tiles) {
    if (placement) {
      compact_one_group_.set_args(in, count, *placement->src, cl_uint(placement->words), *placement->dst,
                                  cl_uint(placement->capacity), counters, slot);
      context_.launch(compact_one_group_, wg, wg, timeline, label);
    } else {
      one_group_.set_args(in, count, out, counters, slot);
      context_.launch(one_group_, wg, wg, timeline, label);
    }
    return;
  }
  if (levels_.size() <= depth) levels_.resize(depth + 1);
  ensure_capacity(context_, levels_[depth], tiles * sizeof(cl_uint), "scan tile sums");
  const Buffer sums = levels_[depth];
  reduce_.set_args(in, count, sums);
  context_.launch(reduce_, tiles * wg, wg, timeline, label);
  const bool summed = tiles <= tile_items();
  if (!summed) level(sums, sums, tiles, counters, no_slot, depth + 1, nullptr, timeline, label);
  if (placement) {
    compact_tiles_.set_args(in, count, *placement->src, cl_uint(placement->words), *placement->dst,
                            cl_uint(placement->capacity), sums, cl_uint(summed), counters, slot);
    context_.launch(compact_tiles_, tiles * wg, wg, timeline, label);
  } else {
    tiles_.set_args(in, count, out, sums, cl_uint(summed), counters, slot);
    context_.launch(tiles_, tiles * wg, wg, timeline, label);
  }
}

namespace {
std::size_t checked_record_words(std::size_t words)
{
  if (words == 0 || words > Sorter::max_words)
    throw Error("sort: records of " + std::to_string(words) + " words; the sort takes 1 to " +
                std::to_string(Sorter::max_words));
  return words;
}

// Half the local memory at most, so that two groups can share a compute unit, and no
// more than 16 KiB: longer blocks save a merge pass each but lengthen the network.
std::size_t block_records(const Context& context, std::size_t words)
{
  const std::size_t bytes = std::min<std::size_t>(context.device().local_memory / 2, 16384);
  std::size_t block = 1;
  while (2 * block * words * sizeof(cl_uint) <= bytes) block *= 2;
  if (block < 2)
    throw Error("sort: device " + context.device().name + " has too little local memory for two records of " +
                std::to_string(words) + " words");
  return block;
}
}  // namespace

Sorter::Sorter(Context& context, std::size_t words)
    : context_(context),
      words_(checked_record_words(words)),
      block_(block_records(context, words)),
      tile_(std::min(block_, context.work_group_size())),
      blocks_(context.programs().kernel("runtime/sort.cl", "cs_sort_blocks", "-DCS_SORT_WORDS=" + std::to_string(words))),
      merge_(context.programs().kernel("runtime/sort.cl", "cs_merge_runs", "-DCS_SORT_WORDS=" + std::to_string(words)))
{
}

// Runs that fit one block sort in local memory and merge nothing.
std::size_t Sorter::scratch_bytes_for(std::size_t n) const { return n >= 2 && block_ < n ? n * words_ * sizeof(cl_uint) : 0; }

std::size_t Sorter::sorted_block(std::size_t n) const
{
  std::size_t block = 2;
  while (block < std::min(n, block_)) block *= 2;
  return block;
}

void Sorter::reserve(std::size_t n)
{
  if (const std::size_t bytes = scratch_bytes_for(n)) ensure_capacity(context_, scratch_, bytes, "sort scratch");
}

const Buffer& Sorter::sort(const Buffer& records, std::size_t n, Timeline* timeline, const char* label)
{
  reserve(n);
  return sort(records, scratch_, n, timeline, label);
}

const Buffer& Sorter::sort(const Buffer& records, const Buffer& scratch, std::size_t n, Timeline* timeline,
                           const char* label)
{
  check_sortable(scratch, n, label);
  if (n < 2) return records;
  const std::size_t wg = context_.work_group_size();
  blocks_.set_args(records, cl_uint(n), cl_uint(sorted_block(n)));
  blocks_.set_local(3, block_local_bytes());
  context_.launch(blocks_, (n + block_ - 1) / block_ * wg, wg, timeline, label);
  return merge(records, scratch, n, merge_passes(n), timeline, label);
}

void Sorter::check_sortable(const Buffer& scratch, std::size_t n, const char* label) const
{
  if (n >= (std::size_t(1) << 31))
    throw Error(std::string(label) + ": " + std::to_string(n) + " records, the sort takes fewer than 2^31");
  if (scratch.bytes() < scratch_bytes_for(n))
    throw Error(std::string(label) + ": " + std::to_string(scratch.bytes()) + " bytes of scratch for " +
                std::to_string(n) + " records, which take " + std::to_string(scratch_bytes_for(n)));
}

std::size_t Sorter::merge_passes(std::size_t n) const
{
  std::size_t passes = 0;
  for (std::size_t width = block_; width < n; width *= 2) ++passes;
  return passes;
}

const Buffer& Sorter::merge(const Buffer& records, const Buffer& scratch, std::size_t n, std::size_t passes,
                            Timeline* timeline, const char* label)
{
  check_sortable(scratch, n, label);
  const std::size_t wg = context_.work_group_size();
  const std::size_t groups = tiles(n);
  const Buffer* in = &records;
  const Buffer* out = &scratch;
  for (std::size_t pass = 0; pass < passes; ++pass) {
    merge_.set_args(*in, *out, cl_uint(n), cl_uint(block_ << pass), cl_uint(tile_));
    merge_.set_local(5, tile_local_bytes());
    context_.launch(merge_, groups * wg, wg, timeline, label);
    std::swap(in, out);
  }
  return *in;
}

}  // namespace cstreams::runtime
