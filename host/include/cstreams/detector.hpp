#pragma once
// The public API: continuous collision detection of a scene of triangle meshes on an
// OpenCL device, step after step.
//
//   cstreams::runtime::Context device("nvidia");          // or "pocl", "gpu", "0:1", ...
//   cstreams::SceneDescription scene;
//   const auto cloth = scene.add({"cloth", cloth_faces, cloth_rest});
//   scene.add({"ball", ball_faces, ball_rest, cstreams::ObjectKind::static_});
//   cstreams::Detector detector(device, scene, {});       // named defaults: DetectorOptions
//   for (...) {
//     detector.set_positions(cloth, next_cloth_positions);
//     detector.detect();                                  // the step from the last positions
//     for (const cstreams::Contact& c : detector.contacts()) ...
//   }
//
// Replaying recorded frames, upload_ahead(cloth, frame[n + 1]) before the detect() of
// step n (ending at frame n) lets that upload overlap the step, and the step hands its
// end to the next one without a copy.
#include <cstreams/contacts.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/proximity.hpp>
#include <cstreams/reference/reference_ccd.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/scene/scene.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cstreams {

namespace runtime {
class Context;
}

// How the BVTT front (where last step's search of the bounding volume test tree
// stopped) carries over to the next step. Every mode reports the same contacts.
enum class FrontMode {
  none,     // search from the roots every step; no front kept
  exact,    // the paper's front tracking: the next search starts from the last front
  deferred  // the front kept at ancestors, as deep as the memory budget allows
};
const char* to_string(FrontMode mode) noexcept;
FrontMode parse_front_mode(const std::string& text);

// One object as the detector sees it: a triangle mesh and where it starts.
struct ObjectDescription {
  ObjectDescription() = default;
  ObjectDescription(std::string name, std::vector<Face> faces, std::vector<Vec3> positions,
                    ObjectKind kind = ObjectKind::deformable, bool self_collision = true)
      : name(std::move(name)), faces(std::move(faces)), positions(std::move(positions)), kind(kind),
        self_collision(self_collision)
  {
  }

  std::string name;
  std::vector<Face> faces;
  std::vector<Vec3> positions;  // a static object stays here for good
  ObjectKind kind = ObjectKind::deformable;
  bool self_collision = true;   // deformable objects only
  // Codimensional geometry, which needs the conservative solver: segments that belong to
  // no face (rods, seams), as pairs of vertices, and vertices that belong to no face or
  // segment (particles). Each collides as a degenerate face, (a, b, b) or (p, p, p),
  // after the object's faces: contacts and close pairs name it by the face id past
  // them (segments first, then points) and by those vertices.
  std::vector<Edge> segments;
  std::vector<std::uint32_t> points;
};

struct SceneDescription {
  std::vector<ObjectDescription> objects;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ignored_pairs;  // (a < b): never collide

  std::uint32_t add(ObjectDescription object);
  void ignore(std::uint32_t a, std::uint32_t b);
  bool may_collide(std::uint32_t a, std::uint32_t b) const;
};

// A loaded scene's objects at one of its frames.
SceneDescription describe(const Scene& scene, std::size_t frame = 0);

// What a detector's steps look for.
enum class Detects {
  contacts,    // along each object's motion from its start to its end positions (CCD)
  close_pairs  // pairs closer than DetectorOptions::dhat at the end positions (starts unread)
};

struct DetectorOptions {
  SolverOptions solver;  // elementary tests: solver, precision, tolerance, minimum separation
  Detects detects = Detects::contacts;
  // Proximity: the distance (units of the positions) below which a pair is reported.
  // Distances are computed in the solver's precision.
  double dhat = 0;
  FrontMode front = FrontMode::exact;
  // Deferred front: device memory for the front (both of its buffers), in MiB.
  double front_budget_mb = 16;
  // A kept front's pairs climb where boxes move apart, each to its highest ancestor
  // whose boxes are apart, but to no level nearer the roots than this many BVTT levels
  // above the deepest a pair may be: the trees' deepest pairs of leaves, or a deferred
  // front's level cap (the roots at most). Where pairs that climbed far
  // overlap again, each of their whole subtrees falls to one work-group, and the
  // device waits for the busiest (H200, the 1.5M-triangle sheet: the front update of
  // the step where contact surges took 95-195 ms with no floor, 35-45 ms with this
  // one). Higher values keep fewer pairs in the front; contacts are the same whatever
  // the value.
  std::uint32_t front_climb_levels = 16;
  runtime::Registration registration = runtime::Registration::segmented_lock;
  // Per-pass device times (OpenCL profiling events). They cost the host 5-7 us a
  // kernel launch (0.4-0.9 ms of a cloth-ball step on the H200); a program that does
  // not read them saves that with false.
  bool profile = true;
  // First capacity of every variable-length stream; 0 sizes them from the scene.
  // Streams grow as needed either way (tests force tiny capacities to prove it).
  std::size_t initial_capacity = 0;
  // The most host memory the detector pins for the contacts it reads, in bytes (at
  // least two contacts' worth). Pinned memory is read fastest but slow to get: NVIDIA's
  // driver pins about 2 GB/s. A step with more contacts reads them through it in chunks
  // into ordinary memory, kept while later steps need it.
  std::size_t pinned_contact_bytes = std::size_t(64) << 20;
};

// What detect() reads back.
enum class Report {
  contacts,     // every contact (and the earliest time per object)
  // Only the earliest time of impact per object, the very one the full list gives; the
  // solvers then leave unsettled the pairs that cannot hold one (the conservative
  // refinement gives them up, the cubic test skips them).
  earliest_toi
};

struct DetectorStats {
  runtime::RunStats run;            // the last step: per-pass device time, per-stream counts and bytes
  std::size_t front_pairs = 0;      // the front carried to the next step
  std::uint32_t front_level_cap = 0;  // deepest level the front may hold (deferred)
  unsigned front_retries = 0;       // runs repeated at a coarser front to fit the budget
  std::size_t triangle_pairs = 0, vf_candidates = 0, ee_candidates = 0;
  // With Report::earliest_toi, the solvers settle only the pairs that may hold an
  // object's earliest time, and this counts their contacts alone.
  std::size_t contacts = 0;
  // Conservative solver in single precision: the queries whose float answer was not
  // proven and that ran again in double (SolverOptions::escalate).
  std::size_t escalated = 0;
  double host_ms = 0;               // wall time of the last detect(), uploads and readbacks included
  std::chrono::steady_clock::time_point started;  // when the last detect() began
  unsigned launches = 0;            // kernel launches of the last detect(), every one
  unsigned blocking_reads = 0;      // and its blocking reads (counters, flags, contacts)
  std::uint64_t device_ns() const;  // sum of the passes' device time
  // With profiling on, from the start of the last run's first command on the device to
  // the end of its last (the contacts' read): the passes, the counter clears and reads,
  // and the device's idle time between them, waiting on the host.
  std::uint64_t device_span_ns = 0;
  std::size_t device_bytes() const; // streams and scratch held after the step
  // The most the device context held during the step, passing scratch included (and
  // whatever else the context holds: other detectors on it, say).
  std::size_t peak_bytes = 0;
};

// Continuous collision detection of one scene on one device.
//
// Each step moves every object linearly from its start to its end positions; contacts
// are the vertex-face and edge-edge pairs that touch within the step (or come closer
// than the minimum separation), with their first time of impact. The start of a step
// is the end of the one before; objects given no new positions stay where they are.
// Bad input (an unknown object, a static one moved, a wrong vertex count, NaN or
// infinite coordinates) is an InputError that changes nothing.
class Detector {
public:
  Detector(runtime::Context& device, SceneDescription scene, DetectorOptions options = {});
  ~Detector();
  Detector(const Detector&) = delete;
  Detector& operator=(const Detector&) = delete;

  std::uint32_t object(const std::string& name) const;
  // The positions at the end of the next step. They are copied (the memory may change
  // on return) and go up with every object's as the next detect() starts: one write
  // per run of adjacent objects, not one per object.
  void set_positions(std::uint32_t object, PositionSpan end);
  // Both ends of the next step (replaying recorded frames, repeating a step), copied
  // and uploaded as set_positions().
  void set_step(std::uint32_t object, PositionSpan start, PositionSpan end);
  // The positions at the end of the step after the next one, where they are known
  // before the next step runs (replaying recorded frames): rounded, copied and uploaded
  // while the next detect() runs, they become the ends of the step after it when it
  // returns. `end` is read then: it must stay as it is until the next detect() returns.
  // Objects given none stay where that step leaves them; set_positions() afterwards
  // still replaces them, and a second call before the next detect() this one.
  void upload_ahead(std::uint32_t object, const std::vector<Vec3>& end);
  // Both ends of the step after the next (repeating a step, or starting it elsewhere
  // than where the next one ends), uploaded ahead as upload_ahead(object, end); both
  // are read until the next detect() returns. Objects given no start this way start
  // where the next step leaves them.
  void upload_ahead(std::uint32_t object, const std::vector<Vec3>& start, const std::vector<Vec3>& end);

  // A failure on the device part-way through a step (memory exhausted, a lost device)
  // is thrown as runtime::Error and leaves the detector refusing every further call
  // with that reason: no step that did not run reports "no collision". Create a new
  // detector (on a new context after a lost device).
  void detect(Report report = Report::contacts);

  // The last step's contacts in canonical order (needs Report::contacts), read in
  // place: valid until the next detect(). Copy them into a std::vector to keep them.
  ContactSpan contacts() const;
  // Per object, the earliest time of impact in the last step (1 without contact),
  // rounded down to float.
  std::vector<double> earliest_toi() const;
  // The last step's pairs closer than dhat (Detects::close_pairs), in canonical order.
  const std::vector<ClosePair>& close_pairs() const;
  // The last step's feature pairs before the elementary tests, as the host reference
  // lays them out. A step that ran in slices to fit the device's memory
  // (stats().run.slices > 1) kept only its last slice's, and this throws.
  Candidates candidates() const;
  const DetectorStats& stats() const;
  const runtime::StreamGraph& graph() const;
  const SceneDescription& scene() const;

private:
  struct State;
  void run_step(Report report);
  std::unique_ptr<State> state_;
};

}  // namespace cstreams
