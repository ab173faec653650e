#pragma once
// Positions uploaded ahead (Detector::upload_ahead): the next step's ends, and its
// starts where they are given too, uploaded while the step before runs and put in
// place as it ends by exchanging buffers rather than copying.
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstdint>
#include <future>
#include <optional>
#include <vector>

namespace cstreams {

// The callers' positions are rounded into pinned copies by a task of their own as the
// next step starts, and uploaded from there on the context's second queue once it is
// done; it keeps the step's uploads (once queued) and the last step's (which may still
// read the copies), and when the buffers they go to are no longer read.
class PositionsAhead {
public:
  // `layout`, `scene` and `streams` must outlive this.
  PositionsAhead(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                 const CcdStreams& streams);

  // Positions of object o for the next step's end, and its start where given; both must
  // stay as they are until the step ends.
  void give(runtime::Scheduler& scheduler, std::uint32_t o, const std::vector<Vec3>* start,
            const std::vector<Vec3>& end);
  // Whether positions were given for the next step.
  bool given() const { return uploading_.valid() || rounded_.has_value(); }
  // At the step's first counter read, or as it ends where none came: starts the task
  // that rounds the positions given into the pinned copies, off the step's path.
  void start_rounding();
  // Queues the uploads of what the task rounded: at a counter read where the task is
  // done (the device is busy, and the upload overlaps the rest of the step), else as
  // the step ends (`wait`).
  void queue_uploads(runtime::Scheduler& scheduler, bool wait);
  // As a step ends where positions were given: the end becomes the start, the uploads
  // the next ends (and starts), with per object whether they are floats.
  void end_step(runtime::Scheduler& scheduler, std::vector<bool>& start_exact, std::vector<bool>& end_exact);

private:
  // The step's ends, or its starts: where they go and the pinned copies they go from.
  struct Side {
    runtime::StreamId single, exact;
    runtime::HostStaging single_copy, exact_copy;
    std::vector<const std::vector<Vec3>*> given;  // per object; null: none
    bool any() const;
  };
  // Adjacent vertices of one side given ahead.
  struct Run {
    const Side* side;
    std::size_t first, count;
  };
  struct Uploads {
    std::vector<Run> runs;
    // Per object given positions: whether they are floats.
    std::vector<bool> end_floats, start_floats;
    std::vector<runtime::Handle<cl_event>> events;  // once queued
  };

  void prepare(runtime::Scheduler& scheduler, Side& side, runtime::StreamId single, runtime::StreamId exact);
  std::vector<bool> round_side(const Side& side, std::vector<Run>& runs) const;
  void fill_in(runtime::Scheduler& scheduler, const Side& side) const;

  runtime::Context& context_;
  const SceneLayout& layout_;
  const SceneDescription& scene_;
  const CcdStreams& streams_;
  Side ends_, starts_;
  std::future<Uploads> uploading_;
  std::optional<Uploads> rounded_;  // the task's, once its uploads are queued
  std::vector<runtime::Handle<cl_event>> taken_;
  runtime::Handle<cl_event> free_;
};

}  // namespace cstreams
