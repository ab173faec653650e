#include "registrar.hpp"

#include "growth.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <vector>

namespace cstreams::runtime {

namespace {

using details::SegmentPlanner;

// Segments of an output packed late up to which its merge adds up the counts before each
// group's segments itself (a few loads a work-item) rather than after a scan's launch.
constexpr std::size_t own_offsets_most_segments = 8192;

// Segmented lock: the most segments one group of the merge copies (CS_MERGE_SEGMENTS
// in cl_kernels/runtime/compact.cl).
constexpr std::size_t most_merged_per_group = 64;

}  // namespace

Kernel build_pass_kernel(Context& context, const PassSpec& spec, Registration mode, const std::string& name)
{
  const std::string define = "-DCS_REGISTRATION=" + std::to_string(int(mode));
  const std::string opts = spec.kernel.options.empty() ? define : spec.kernel.options + " " + define;
  return context.programs().kernel(spec.kernel.program, name, opts);
}

Registrar::Registrar(Context& context, Registration registration, StreamBuffers& streams, Scratch& scratch,
                     Counters& counters, Timeline* timeline)
    : context_(context), streams_(streams), scratch_(scratch), timeline_(timeline), counters_(counters),
      registration_(registration), planner_(registration, context.work_group_size()), scan_(context),
      merge_interleaved_(context.programs().kernel("runtime/compact.cl", "cs_merge_interleaved")),
      merge_planned_(context.programs().kernel("runtime/compact.cl", "cs_merge_planned")),
      no_plan_(context, sizeof(cl_uint), "registration plan")
{
  context.fill_u32(no_plan_, 0, 0, 1);
}

// Segments follow the last run, so one burst (a first step searched from the roots,
// say) can ask for more memory than the device has, or than is left of it. Then the
// pass registers this run through one global counter instead: slower under
// contention, but its memory is the stream itself.
bool Registrar::segments_fit(const EmitterState& e, std::size_t global) const
{
  const std::uint64_t items = planner_.segment_items(e, planner_.segment_count(e, global));
  if (items > 0xffffffffu) return false;  // the kernels index segments with 32 bits
  const std::size_t bytes = std::size_t(items) * streams_.spec(e.stream).element_bytes;
  const std::size_t in_use = context_.memory_in_use(), limit = context_.memory_limit();
  return bytes <= context_.device().max_allocation && in_use <= limit && bytes <= limit - in_use;
}

void Registrar::set_up(PassState& p, std::size_t global)
{
  for (auto& e : p.emitters) {
    if (e.segment_capacity == 0) e.segment_capacity = planner_.first_segment_capacity(e);
    SegmentPlanner::forget_stale_plan(e, planner_.segment_count(e, global));
    if (p.mode != Registration::global_atomic && !segments_fit(e, global) &&
        !(scratch_.release_idle() && segments_fit(e, global)))
      fall_back_to_global_counter(p);
  }
  // Each emitter's segments fit alone; all of them together may not.
  if (p.mode != Registration::global_atomic) {
    try {
      for (auto& e : p.emitters) prepare_segments(e, global);
    } catch (const DeviceMemoryExhausted&) {
      fall_back_to_global_counter(p);
    }
  }
  // Lock-free: the next run tries small segments again.
  if (p.mode == Registration::global_atomic)
    for (auto& e : p.emitters) e.segment_capacity = planner_.first_segment_capacity(e);
}

void Registrar::fall_back_to_global_counter(PassState& p)
{
  for (auto& e : p.emitters) {
    scratch_.drop_segments(e);
    e.segment_bytes = 0;
  }
  build_fallback(context_, p);
  p.mode = Registration::global_atomic;
  p.atomic_this_run = true;
}

void build_fallback(Context& context, PassState& p)
{
  if (p.atomic_kernel.get()) return;
  p.atomic_kernel = build_pass_kernel(context, *p.spec, Registration::global_atomic, p.spec->kernel.kernel);
  if (!p.spec->variant_kernel.empty())
    p.atomic_variant = build_pass_kernel(context, *p.spec, Registration::global_atomic, p.spec->variant_kernel);
}

void Registrar::prepare_segments(EmitterState& e, std::size_t global)
{
  planner_.prepare(e, global);
  const std::size_t bytes = std::size_t(planner_.segment_items(e, e.segments)) * streams_.spec(e.stream).element_bytes;
  // Segments still held from this run's overflowing execution are written anew: kept
  // while they fit.
  if (e.items.bytes() < bytes) scratch_.give_back_segments(e);
  if (!e.items) scratch_.take_segments(e, bytes);
  e.needed = bytes;
  e.segment_bytes = e.items.bytes();
  // Segmented lock: each spilled item's group and rank follow the counts.
  scratch_.take_stage_scratch(e.counts, e.counts_at, (e.segments + 2 * e.pool) * sizeof(cl_uint),
                              "registration counts");
}

void Registrar::register_outputs(PassState& p, std::size_t n, std::size_t global, std::size_t wg)
{
  const std::string& label = p.spec->name;
  if (p.mode == Registration::lock_free) {
    for (auto& e : p.emitters) {
      auto& dst = streams_.state(e.stream);
      scratch_.with_memory([&] {
        ensure_capacity(context_, offsets_, e.segments * sizeof(cl_uint), "registration offsets");
        scan_.exclusive(e.counts, offsets_, e.segments, counters_.device(), dst.slot, timeline_, label.c_str());
      });
      merge_interleaved_.set_args(e.items, cl_uint(streams_.words(e.stream)), e.counts, offsets_, cl_uint(e.segments),
                                  cl_uint(e.segment_capacity), dst.buffer, cl_uint(dst.capacity));
      context_.launch(merge_interleaved_, e.segments * e.segment_capacity, wg, timeline_, label);
    }
  } else if (p.mode == Registration::segmented_lock && global > 0) {
    scan_and_merge(p);
  }
  if (p.spec->culls()) {
    auto& dst = streams_.state(p.spec->cull_target);
    scratch_.with_memory([&] {
      scan_.compact(streams_.state(p.spec->cull_source).buffer, streams_.words(p.spec->cull_source), p.keep, n,
                    dst.buffer, dst.capacity, counters_.device(), dst.slot, timeline_, label.c_str());
    });
  }
}

// Segmented lock: the scans first, two outputs' at once, then the merges.
void Registrar::scan_and_merge(PassState& p)
{
  const char* label = p.spec->name.c_str();
  std::vector<Scan::Job> scans;
  for (auto& e : p.emitters) {
    scratch_.with_memory(
        [&] { ensure_capacity(context_, e.offsets, (e.segments + 1) * sizeof(cl_uint), "registration offsets"); });
    if (scans_at_once(p, e)) scans.push_back({&e.counts, &e.offsets, e.segments, streams_.state(e.stream).slot});
  }
  scratch_.with_memory([&] {
    for (std::size_t k = 0; k < scans.size(); k += 2)
      if (k + 1 < scans.size()) scan_.exclusive_both(scans[k], scans[k + 1], counters_.device(), timeline_, label);
      else scan_.exclusive(*scans[k].in, *scans[k].out, scans[k].n, counters_.device(), scans[k].slot, timeline_, label);
  });
  for (auto& e : p.emitters)
    if (!packs_late(p, e)) merge_segments(p, e);
}

void Registrar::merge_segments(const PassState& p, const EmitterState& e, bool copy)
{
  const auto& dst = streams_.state(e.stream);
  const std::size_t wg = context_.work_group_size(), per_group = merged_per_group(e);
  // A spilled item finds its place through the scanned offset of its group's segment.
  const bool scanned = scans_at_once(p, e), own_offsets = !scanned && copy && count(e.overflow_slot) == 0;
  if (!scanned && !own_offsets)
    scan_.exclusive(e.counts, e.offsets, e.segments, counters_.device(), no_slot, timeline_, p.spec->name.c_str());
  merge_planned_.set_args(e.items, cl_uint(streams_.words(e.stream)), e.counts, e.offsets, cl_uint(e.segments),
                          plan_of(e, no_plan_), cl_uint(e.planned), cl_uint(planner_.first_segment_capacity(e)),
                          counters_.device(), cl_uint(e.overflow_slot), cl_uint(e.pool), dst.buffer,
                          cl_uint(copy ? dst.capacity : 0), cl_uint(per_group), cl_uint(own_offsets));
  const std::size_t groups = (e.segments + per_group - 1) / per_group;
  const std::size_t spill_groups = own_offsets ? 0 : (e.pool + wg - 1) / wg;
  context_.launch(merge_planned_, copy ? (groups + spill_groups) * wg : 1, wg, timeline_, p.spec->name);
}

// Segments a merging group copies: about eight groups' worth of items, judged by the
// plan's average segment (else the room of an unplanned one), and at most
// most_merged_per_group and a work-item each, which reads its bounds.
std::size_t Registrar::merged_per_group(const EmitterState& e) const
{
  const std::size_t wg = context_.work_group_size(), most = std::min(most_merged_per_group, wg);
  const std::size_t average = e.planned ? e.planned_total / e.planned : planner_.first_segment_capacity(e);
  return std::clamp<std::size_t>(8 * wg / std::max<std::size_t>(average, 1), 1, most);
}

// Whether the emitter's counts are scanned into its offsets right after its kernel. An
// output packed once the counters are read needs no scan before: its kernel added up
// its count (registration.h), and where few segments hold it and none spilled, its
// merge finds their offsets itself (merge_segments).
bool Registrar::scans_at_once(const PassState& p, const EmitterState& e) const
{
  return !packs_late(p, e) || e.segments > own_offsets_most_segments;
}

bool Registrar::packs_late(const PassState& p, const EmitterState& e) const
{
  return hands_over(p, e) ||
         (p.mode == Registration::segmented_lock && scratch_.late() && streams_.state(e.stream).transient);
}

bool Registrar::segments_overflowed(const PassState& p, const EmitterState& e) const
{
  return planner_.overflowed(p.mode, e, count(e.overflow_slot));
}

bool Registrar::outgrew(const PassState& p, const EmitterState& e) const
{
  return !packs_late(p, e) && count(streams_.state(e.stream).slot) > streams_.state(e.stream).capacity;
}

bool Registrar::overflowed(const PassState& p) const
{
  if (p.list && !p.list->settled) return true;
  for (const auto& e : p.emitters)
    if (segments_overflowed(p, e) || outgrew(p, e)) return true;
  if (!p.spec->culls()) return false;
  const auto& target = streams_.state(p.spec->cull_target);
  return count(target.slot) > target.capacity;
}

void Registrar::adopt_plan(EmitterState& e)
{
  SegmentPlanner::adopt(e, count(streams_.state(e.stream).slot), count(e.overflow_slot));
  std::swap(e.plan, e.offsets);
}

void Registrar::replan(const PassState& p, EmitterState& e)
{
  if (packs_late(p, e)) merge_segments(p, e, false);
  if (p.mode == Registration::segmented_lock) {
    adopt_plan(e);
    e.exact_plan = true;
  } else {
    e.segment_capacity = grown(count(e.overflow_slot));
  }
}

}  // namespace cstreams::runtime
