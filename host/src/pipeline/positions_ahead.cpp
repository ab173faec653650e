#include "positions_ahead.hpp"
#include "position_writes.hpp"

#include <cstreams/geometry/float_bounds.hpp>

#include <algorithm>
#include <chrono>

namespace cstreams {

namespace {

// Two position streams exchange buffers, with their float and exact twins.
void swap_positions(runtime::Scheduler& scheduler, runtime::StreamId a, runtime::StreamId a_exact, runtime::StreamId b,
                    runtime::StreamId b_exact)
{
  scheduler.swap(a, b);
  if (has(a_exact)) scheduler.swap(a_exact, b_exact);
}

}  // namespace

bool PositionsAhead::Side::any() const
{
  return std::any_of(given.begin(), given.end(), [](const auto* x) { return x != nullptr; });
}

PositionsAhead::PositionsAhead(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                               const CcdStreams& streams)
    : context_(context), layout_(layout), scene_(scene), streams_(streams)
{
}

// The first upload ahead to a side gives its buffers the vertices: a static object's
// never change, and those of moving objects given none are copied in after each step.
void PositionsAhead::prepare(runtime::Scheduler& q, Side& side, runtime::StreamId single, runtime::StreamId exact)
{
  const std::size_t n = q.count(streams_.x1);
  if (q.count(single) == n) return;
  side.single = single;
  side.exact = exact;
  q.resize(single, n);
  q.copy(streams_.x1, 0, single, 0, n);
  runtime::ensure_capacity(context_, side.single_copy, n * 3 * sizeof(float), "positions uploaded ahead");
  if (has(exact)) {
    q.resize(exact, n);
    q.copy(streams_.x1_double, 0, exact, 0, n);
    runtime::ensure_capacity(context_, side.exact_copy, n * sizeof(Vec3), "positions uploaded ahead");
  }
  side.given.assign(scene_.objects.size(), nullptr);
  free_ = context_.marker();
}

void PositionsAhead::give(runtime::Scheduler& scheduler, std::uint32_t o, const std::vector<Vec3>* start,
                          const std::vector<Vec3>& end)
{
  prepare(scheduler, ends_, streams_.x_next, streams_.x_next_double);
  if (start) prepare(scheduler, starts_, streams_.x0_next, streams_.x0_next_double);
  ends_.given[o] = &end;
  if (!starts_.given.empty()) starts_.given[o] = start;
}

// Rounds the positions given to one side into its pinned copies, where the vertices
// go, so that runs of adjacent vertices there go up in one write each; returns per
// object whether they were floats, and adds the side's runs to `runs`.
std::vector<bool> PositionsAhead::round_side(const Side& side, std::vector<Run>& runs) const
{
  std::vector<bool> floats(side.given.size(), false);
  if (!side.any()) return floats;
  std::vector<Run> own;  // joined within the side alone
  for (const ObjectSlot& slot : layout_.slots) {
    const std::vector<Vec3>* x = side.given[slot.object];
    if (!x) continue;
    const std::size_t first = slot.first_vertex;
    floats[slot.object] = round_to_float(*x, static_cast<float*>(side.single_copy.data()) + 3 * first,
                                         has(side.exact) ? static_cast<Vec3*>(side.exact_copy.data()) + first
                                                         : nullptr)
                              .exact;
    append_run(own, Run{&side, first, x->size()});
  }
  runs.insert(runs.end(), own.begin(), own.end());
  return floats;
}

// Not before the step's first launch, which its thread's start held back (an H200's
// cloth-ball step: 12-20 us), while at the read the device is busy. The task makes no
// OpenCL call: one from a second thread waited for the step's blocking reads and
// slowed the launches after them (cloth-ball, 0.12 ms). The copying is off the step's
// path: 27 MB of 1.5M triangles in double.
void PositionsAhead::start_rounding()
{
  if (!ends_.any() || uploading_.valid() || rounded_) return;
  // The copies are written again once the last step's uploads (long done) are.
  context_.block_until(taken_);
  taken_.clear();
  uploading_ = std::async(std::launch::async, [this] {
    Uploads uploads;
    uploads.end_floats = round_side(ends_, uploads.runs);
    uploads.start_floats = round_side(starts_, uploads.runs);
    return uploads;
  });
}

void PositionsAhead::queue_uploads(runtime::Scheduler& scheduler, bool wait)
{
  if (!uploading_.valid() || rounded_) return;
  if (!wait && uploading_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  rounded_ = uploading_.get();
  const std::size_t vertex = 3 * sizeof(float);
  for (const Run& r : rounded_->runs) {
    const Side& side = *r.side;
    rounded_->events.push_back(context_.write_ahead(scheduler.buffer(side.single),
                                                    static_cast<float*>(side.single_copy.data()) + 3 * r.first,
                                                    r.count * vertex, r.first * vertex, free_));
    if (has(side.exact))
      rounded_->events.push_back(context_.write_ahead(scheduler.buffer(side.exact),
                                                      static_cast<Vec3*>(side.exact_copy.data()) + r.first,
                                                      r.count * sizeof(Vec3), r.first * sizeof(Vec3), free_));
  }
}

// Where a side's buffers lack objects given none ahead, they take them from this
// step's end: so they stay where the step left them.
void PositionsAhead::fill_in(runtime::Scheduler& q, const Side& side) const
{
  for (const ObjectSlot& slot : layout_.slots) {
    if (!slot.moving || side.given[slot.object]) continue;
    const std::size_t count = scene_.objects[slot.object].positions.size();
    q.copy(streams_.x1, slot.first_vertex, side.single, slot.first_vertex, count);
    if (has(side.exact)) q.copy(streams_.x1_double, slot.first_vertex, side.exact, slot.first_vertex, count);
  }
}

// Buffers change places, and no copy stands between the step and its return: the end
// becomes the start, the positions uploaded ahead the next ends (or both ends, given
// with their starts), and the old start takes the next uploads once the step no longer
// reads it.
void PositionsAhead::end_step(runtime::Scheduler& q, std::vector<bool>& start_exact, std::vector<bool>& end_exact)
{
  const CcdStreams& s = streams_;
  queue_uploads(q, true);
  Uploads uploads = std::move(*rounded_);
  rounded_.reset();
  context_.wait_for(uploads.events);
  fill_in(q, ends_);
  if (starts_.any()) {
    fill_in(q, starts_);
    for (std::uint32_t o = 0; o < starts_.given.size(); ++o)
      start_exact[o] = starts_.given[o] ? bool(uploads.start_floats[o]) : end_exact[o];
    swap_positions(q, s.x0, s.x0_double, s.x0_next, s.x0_next_double);
  } else {
    start_exact = end_exact;
    swap_positions(q, s.x0, s.x0_double, s.x1, s.x1_double);
  }
  swap_positions(q, s.x1, s.x1_double, s.x_next, s.x_next_double);
  for (std::uint32_t o = 0; o < ends_.given.size(); ++o)
    if (ends_.given[o]) end_exact[o] = uploads.end_floats[o];
  // The next uploads go to buffers the step read, once nothing reads them.
  free_ = context_.marker();
  taken_ = std::move(uploads.events);
  std::fill(ends_.given.begin(), ends_.given.end(), nullptr);
  std::fill(starts_.given.begin(), starts_.given.end(), nullptr);
}

}  // namespace cstreams
