#pragma once
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cstreams::runtime {

class Context;

// Counter-slot value meaning "write no total" (CS_NO_SLOT in the kernels).
constexpr std::uint32_t no_slot = 0xffffffffu;

// Exclusive prefix sum of 32-bit unsigned integers on the device, and the stream
// compaction built on it. Scratch for the tile sums of each recursion level is kept and
// only ever grows.
class Scan {
public:
  explicit Scan(Context& context);

  // out[i] = in[0] + ... + in[i-1] for i < n; `in` and `out` may be the same buffer.
  // The sum of all n values goes to counters[slot] unless slot is no_slot.
  void exclusive(const Buffer& in, const Buffer& out, std::size_t n, const Buffer& counters, std::uint32_t slot,
                 Timeline* timeline = nullptr, const char* label = "scan");
  // One exclusive scan as above.
  struct Job {
    const Buffer* in;
    const Buffer* out;
    std::size_t n;
    std::uint32_t slot;
  };
  // Both scans, in one launch where each input is short enough for one group to scan
  // (a launch costs more than a group's scan of a few tiles: 5-15 us of host time on
  // the H100), else one after the other.
  void exclusive_both(const Job& a, const Job& b, const Buffer& counters, Timeline* timeline = nullptr,
                      const char* label = "scan");
  // Copies item i of `src` (items of `words` 32-bit words) for every i < n with
  // keep[i] != 0 into `dst`, in order, which holds `capacity` items; items past
  // capacity are dropped, and counters[slot] receives the number of kept items either
  // way. The scan's last launch places the items, so no offsets are stored.
  void compact(const Buffer& src, std::size_t words, const Buffer& keep, std::size_t n, const Buffer& dst,
               std::size_t capacity, const Buffer& counters, std::uint32_t slot, Timeline* timeline = nullptr,
               const char* label = "compact");
  std::size_t scratch_bytes() const;
  // Items one tile of the scan covers; inputs of a few tiles take a single launch.
  std::size_t tile_items() const;

private:
  // Where a compaction puts what it keeps; a plain scan has none.
  struct Placement {
    const Buffer* src;
    std::size_t words;
    const Buffer* dst;
    std::size_t capacity;
  };
  void level(const Buffer& in, const Buffer& out, std::size_t n, const Buffer& counters, std::uint32_t slot,
             std::size_t depth, const Placement* placement, Timeline* timeline, const char* label);

  Context& context_;
  std::size_t items_per_work_item_;
  Kernel reduce_;
  Kernel tiles_;
  Kernel one_group_;
  Kernel two_in_a_group_each_;
  Kernel compact_tiles_;
  Kernel compact_one_group_;
  std::vector<Buffer> levels_;
};

// Sorts records of `words` 32-bit words, compared word by word as unsigned integers
// (the first word most significant), on the device: blocks of a few hundred records in
// local memory, then merge passes that each double the sorted runs, each linear in n.
// The kernels are built for one record length, so that a work-item holds a record's
// words in private memory; scratch for the passes is kept and only ever grows.
class Sorter {
public:
  // Records of up to max_words words: longer ones would not fit a work-item's registers.
  static constexpr std::size_t max_words = 16;
  Sorter(Context& context, std::size_t words);

  // Sorts the first n records of `records` and returns the buffer that then holds them
  // in order: `records` itself or the sorter's scratch (valid until the next sort).
  // n must stay below 2^31.
  const Buffer& sort(const Buffer& records, std::size_t n, Timeline* timeline = nullptr, const char* label = "sort");
  // The same with the caller's scratch, of at least scratch_bytes_for(n) bytes.
  const Buffer& sort(const Buffer& records, const Buffer& scratch, std::size_t n, Timeline* timeline = nullptr,
                     const char* label = "sort");
  std::size_t scratch_bytes_for(std::size_t n) const;
  // Allocates the scratch that sorting n records takes, so that a caller short of
  // memory can make room before it sorts anything.
  void reserve(std::size_t n);
  std::size_t scratch_bytes() const { return scratch_.bytes(); }

  // The parts of sort() for a caller whose own kernels (built on runtime/sort.h) make
  // the records as they sort the blocks, and write them out as they merge the last
  // runs, saving a launch at either end: the records a work-group sorts, the local
  // memory it sorts them in, the records of a merge pass's tile and its local memory,
  // and the merge passes that n records take after the blocks.
  std::size_t block() const { return block_; }
  // The records each group of the first launch sorts when n records go into groups of
  // block(): block() itself, or where one group holds all n, the least power of two
  // that holds them, which leaves out the network's longest stages (the funnel's 368
  // contacts sort as 512 rather than 1024 on the H200: 0.038 -> 0.025 ms).
  std::size_t sorted_block(std::size_t n) const;
  std::size_t block_local_bytes() const { return block_ * words_ * sizeof(cl_uint); }
  std::size_t tile() const { return tile_; }
  // The work-groups of a merge pass over n records: one a tile.
  std::size_t tiles(std::size_t n) const { return (n + tile_ - 1) / tile_; }
  std::size_t tile_local_bytes() const { return tile_ * words_ * sizeof(cl_uint); }
  std::size_t merge_passes(std::size_t n) const;
  // Throws unless n records can be sorted with `scratch` (sort() and merge() check too).
  void check_sortable(const Buffer& scratch, std::size_t n, const char* label) const;
  // The first `passes` merge passes over n records sorted in blocks: the buffer that
  // then holds runs of block() << passes records, `records` or `scratch`.
  const Buffer& merge(const Buffer& records, const Buffer& scratch, std::size_t n, std::size_t passes,
                      Timeline* timeline, const char* label);

private:
  Context& context_;
  std::size_t words_;
  // Records a work-group sorts in local memory: a power of two.
  std::size_t block_;
  // Records a work-group of a merge pass merges, one a work-item: a tile of a block's
  // records left each item four to merge one after another, and the H200's passes
  // took 15% longer (cloth-ball's contacts: 0.132 -> 0.114 ms for the sort).
  std::size_t tile_;
  Kernel blocks_;
  Kernel merge_;
  Buffer scratch_;
};

}  // namespace cstreams::runtime
