#include "close_pair_readback.hpp"
#include "contact_readback.hpp"
#include "feature_ids.hpp"
#include "front_control.hpp"
#include "position_writes.hpp"
#include "positions_ahead.hpp"
#include "scene_upload.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <future>
#include <map>
#include <optional>

namespace cstreams {

const char* to_string(FrontMode mode) noexcept
{
  switch (mode) {
  case FrontMode::none: return "none";
  case FrontMode::exact: return "exact";
  case FrontMode::deferred: return "deferred";
  }
  return "?";
}

FrontMode parse_front_mode(const std::string& text)
{
  for (FrontMode m : {FrontMode::none, FrontMode::exact, FrontMode::deferred})
    if (text == to_string(m)) return m;
  throw InputError("unknown front mode '" + text + "' (none, exact or deferred)");
}

std::uint32_t SceneDescription::add(ObjectDescription object)
{
  objects.push_back(std::move(object));
  return std::uint32_t(objects.size() - 1);
}

void SceneDescription::ignore(std::uint32_t a, std::uint32_t b)
{
  if (a == b) throw InputError("an object cannot be masked against itself; turn off its self_collision instead");
  ignored_pairs.emplace_back(std::min(a, b), std::max(a, b));
}

bool SceneDescription::may_collide(std::uint32_t a, std::uint32_t b) const
{
  return objects_may_collide(a, b, objects[a].kind, objects[a].self_collision, objects[b].kind, ignored_pairs);
}

SceneDescription describe(const Scene& scene, std::size_t frame)
{
  SceneDescription d;
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
    const SceneObject& object = scene.objects[o];
    d.add({object.name, object.topology.faces, scene.positions(o, frame), object.kind, object.self_collision});
  }
  d.ignored_pairs = scene.ignored_pairs;
  return d;
}

std::uint64_t DetectorStats::device_ns() const
{
  std::uint64_t ns = 0;
  for (const auto& p : run.passes) ns += p.device_ns;
  return ns;
}

std::size_t DetectorStats::device_bytes() const
{
  std::size_t bytes = run.scratch_bytes;
  for (const auto& s : run.streams) bytes += s.bytes;
  return bytes;
}

namespace {

using Pair = std::array<std::uint32_t, 2>;

}  // namespace

// What a detector holds between steps: the scene, its layout on the device, the
// scheduler running its graph, and the last step's results.
struct Detector::State {
  State(runtime::Context& device, SceneDescription s, const DetectorOptions& o)
      : context(device), scene(std::move(s)), options(o), layout(make_layout(scene, bounds_margin(o))),
        front(o, layout, 4 * device.device().compute_units * device.work_group_size(), device.work_group_size(),
              device.loop_trip_limit() != 0),
        ids(layout)
  {
    // The first front is refined on the host's threads while the programs build and the
    // scene goes up (cloth-ball: 23 ms on the H200's host, 26 on 2 cores).
    const std::vector<NodePair> cut = front.first_cut();
    std::future<std::vector<NodePair>> seeds =
        std::async(std::launch::async, [this, &cut] { return front.first_front(cut); });
    // Each kind of detector reads back its own results: a reader builds its sort and
    // pins its host memory as it is made.
    if (o.detects == Detects::contacts)
      readback.emplace(device, layout, scene, o.solver.precision, o.pinned_contact_bytes);
    else close_readback.emplace(device, layout, ids);
    CcdGraph g = build_ccd_graph(layout, options, cut.size(), graph_device(device));
    streams = g.streams;
    scheduler = std::make_unique<runtime::Scheduler>(device, std::move(g.graph),
                                                     runtime::SchedulerOptions{options.registration, options.profile});
    start_exact = end_exact = upload_scene(*scheduler, g, layout, scene, bounds_margin(options));
    scheduler->on_counter_read([this] {
      ahead.start_rounding();
      ahead.queue_uploads(*scheduler, false);
    });
    if (!has(streams.front)) return;
    front.install(*scheduler, streams, seeds.get());
  }

  std::size_t count(runtime::StreamId s) const { return has(s) ? scheduler->count(s) : 0; }

  runtime::Context& context;
  SceneDescription scene;
  DetectorOptions options;
  SceneLayout layout;
  FrontControl front;
  FeatureIds ids;
  std::optional<ContactReadback> readback;
  std::optional<ClosePairReadback> close_readback;
  PositionWrites given{context};  // set_positions() and set_step()'s
  CcdStreams streams;
  std::unique_ptr<runtime::Scheduler> scheduler;
  PositionsAhead ahead{context, layout, scene, streams};  // upload_ahead()'s
  ContactSpan contacts;  // in the readback's host memory
  std::vector<ClosePair> close;  // a proximity query's
  // Per object, whether its positions at the step's start and end are floats: where all
  // are, the step's float kernels take them as the exact input (CcdStreams::exact_floats).
  std::vector<bool> start_exact, end_exact;
  bool have_contacts = false;
  // An earliest-only step's times, as float bits per object: they come back with the
  // step's last counter read (Scheduler::read_after_run).
  std::vector<std::uint32_t> earliest_bits;
  bool have_earliest = false;
  DetectorStats stats;
  // Why a step failed part-way on the device (its streams, front and positions are then
  // in an unknown state); empty while the detector is usable.
  std::string failure;

  void check_usable() const
  {
    if (!failure.empty())
      throw Error("this detector cannot be used after its step failed on the device (" + failure +
                  "); create a new one");
  }

  // Stages one object's positions for a float stream and, in double precision, its
  // exact twin, uncommitted (PositionWrites::commit), and checks its coordinates as it
  // rounds them.
  FloatRounding stage_positions(runtime::StreamId single, runtime::StreamId exact, std::uint32_t o, PositionSpan x)
  {
    const std::size_t first = layout.slots[layout.slot_of[o]].first_vertex, n = x.size();
    float* const rounded = static_cast<float*>(given.stage(single, first, n, 3 * sizeof(float)));
    Vec3* const copy = has(exact) ? static_cast<Vec3*>(given.stage(exact, first, n, sizeof(Vec3))) : nullptr;
    return round_to_float(x, rounded, copy);
  }

  // Positions given for the next step's ends: staged together, or (a coordinate that is
  // not a finite float) none of them, and an InputError that names the coordinate.
  void stage_ends(std::uint32_t o, const PositionSpan* start, PositionSpan end)
  {
    const FloatRounding r0 = start ? stage_positions(streams.x0, streams.x0_double, o, *start) : FloatRounding{};
    const FloatRounding r1 = stage_positions(streams.x1, streams.x1_double, o, end);
    if (!r0.finite || !r1.finite) {
      given.discard();
      // The rounding's own test, which names the vertex: one of them throws.
      if (start) check_positions(scene, o, *start);
      check_positions(scene, o, end);
    }
    given.commit();
    if (start) start_exact[o] = r0.exact;
    end_exact[o] = r1.exact;
  }

  void upload_ahead(std::uint32_t o, const std::vector<Vec3>* start, const std::vector<Vec3>& end)
  {
    ahead.give(*scheduler, o, start, end);
  }

  // After a step, the next one starts where it ended: without positions given ahead
  // the end is copied into the starts; with them, buffers change places.
  void end_step()
  {
    runtime::Scheduler& q = *scheduler;
    ahead.start_rounding();  // where no counter read did
    if (ahead.given()) {
      ahead.end_step(q, start_exact, end_exact);
      return;
    }
    q.copy(streams.x1, 0, streams.x0, 0, layout.moving_vertices);
    if (has(streams.x1_double)) q.copy(streams.x1_double, 0, streams.x0_double, 0, layout.moving_vertices);
    start_exact = end_exact;
  }

  // Runs device work; a failure other than bad input marks the detector unusable.
  template <class Work> void guarded(Work work)
  {
    check_usable();
    runtime::Context::ThreadGuard one_thread(context);
    try {
      work();
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      failure = e.what();
      throw;
    }
  }
};

namespace {

// Fails before anything is built when the device cannot run the options.
runtime::Context& checked_device(runtime::Context& device, const DetectorOptions& options)
{
  check_solver_options(device, options.solver);
  check_option("DetectorOptions::front_budget_mb", options.front_budget_mb, option_ranges::front_budget_mb);
  if (options.detects == Detects::close_pairs) check_option("DetectorOptions::dhat", options.dhat, option_ranges::dhat);
  device.programs().add_sources(ccd_kernel_sources());
  return device;
}

}  // namespace

Detector::Detector(runtime::Context& device, SceneDescription scene, DetectorOptions options)
{
  // The cubic's coplanarity test holds for any point and a degenerate face.
  for (const ObjectDescription& o : scene.objects)
    if ((!o.segments.empty() || !o.points.empty()) && options.solver.solver == Solver::cubic &&
        options.detects == Detects::contacts)
      throw InputError("object '" + o.name + "': segments and points need the conservative solver");
  runtime::Context::ThreadGuard one_thread(device);
  state_ = std::make_unique<State>(checked_device(device, options), std::move(scene), options);
}

Detector::~Detector() = default;

std::uint32_t Detector::object(const std::string& name) const
{
  const auto& objects = state_->scene.objects;
  for (std::uint32_t o = 0; o < objects.size(); ++o)
    if (objects[o].name == name) return o;
  throw InputError("no object named '" + name + "'");
}

void Detector::set_positions(std::uint32_t object, PositionSpan end)
{
  State& s = *state_;
  s.check_usable();
  check_moving_object(s.scene, object, end);
  s.guarded([&] { s.stage_ends(object, nullptr, end); });
}

void Detector::set_step(std::uint32_t object, PositionSpan start, PositionSpan end)
{
  State& s = *state_;
  s.check_usable();
  check_moving_object(s.scene, object, start);
  check_moving_object(s.scene, object, end);
  s.guarded([&] { s.stage_ends(object, &start, end); });
}

void Detector::upload_ahead(std::uint32_t object, const std::vector<Vec3>& end)
{
  State& s = *state_;
  s.check_usable();
  check_positions(s.scene, object, end);
  s.guarded([&] { s.upload_ahead(object, nullptr, end); });
}

void Detector::upload_ahead(std::uint32_t object, const std::vector<Vec3>& start, const std::vector<Vec3>& end)
{
  State& s = *state_;
  s.check_usable();
  check_positions(s.scene, object, start);
  check_positions(s.scene, object, end);
  s.guarded([&] { s.upload_ahead(object, &start, end); });
}

void Detector::detect(Report report)
{
  State& s = *state_;
  s.check_usable();
  s.have_contacts = false;
  s.guarded([&] { run_step(report); });
}

void Detector::run_step(Report report)
{
  State& s = *state_;
  const auto started = std::chrono::steady_clock::now();
  const std::uint64_t launches = s.context.kernel_launches(), reads = s.context.blocking_reads();
  s.context.reset_memory_high_water();
  s.given.queue(*s.scheduler);
  const CcdStreams& st = s.streams;
  // A proximity query has no times of impact.
  if (s.options.detects == Detects::contacts) s.scheduler->set(st.earliest_only, cl_uint(report == Report::earliest_toi));
  const auto all = [](const std::vector<bool>& v) { return std::find(v.begin(), v.end(), false) == v.end(); };
  s.scheduler->set(st.exact_floats, cl_uint(all(s.start_exact) && all(s.end_exact)));
  s.have_earliest = false;
  if (report == Report::earliest_toi && has(st.earliest)) {
    s.earliest_bits.resize(s.count(st.earliest));
    s.scheduler->read_after_run(st.earliest, s.earliest_bits.data(), s.earliest_bits.size());
  }
  s.stats.front_retries = s.front.run(*s.scheduler, st);
  s.have_earliest = report == Report::earliest_toi;
  runtime::Scheduler& q = *s.scheduler;
  DetectorStats& stats = s.stats;
  // What the host does once the run is over (its figures, the front and the positions
  // handed on to the next step): while the device sorts the contacts, where it does
  // (cloth-ball on an H200: 20-40 us that the sort's launch waited for, or the step's
  // end after the read).
  const auto after_run = [&] {
    stats.run = q.stats();
    if (s.options.front != FrontMode::none && has(st.front)) q.swap(st.front, st.next_front);
    s.end_step();
  };
  if (s.options.detects == Detects::close_pairs) {
    after_run();
    if (has(st.close_pairs)) {
      runtime::PassStats sort;
      s.close_readback->read(q, st.close_pairs, s.options.profile, sort, s.close);
      stats.run.passes.push_back(sort);
    }
  } else if (report == Report::contacts) {
    runtime::PassStats readback;
    std::vector<runtime::Timeline::Entry> commands;
    s.contacts = s.readback->read(q, st, s.options.profile, readback, commands, after_run);
    s.have_contacts = true;
    stats.run.passes.push_back(readback);
    stats.run.commands.insert(stats.run.commands.end(), commands.begin(), commands.end());
  } else {
    after_run();
  }
  stats.device_span_ns = stats.run.span().nanoseconds();
  stats.front_pairs = s.options.front == FrontMode::none ? 0 : s.count(st.front);
  stats.front_level_cap = s.front.level_cap();
  // Over every slice of a step that ran in slices (a stream's count is the last one's).
  const auto items = [&](runtime::StreamId id) { return has(id) ? stats.run.streams.at(id.index).items : 0; };
  stats.triangle_pairs = items(st.triangle_pairs);
  stats.vf_candidates = items(st.vf) + items(st.kept_vf);
  stats.ee_candidates = items(st.ee) + items(st.kept_ee);
  stats.escalated = items(st.escalated);
  stats.contacts = 0;
  for (const auto& c : st.contacts) stats.contacts += s.count(c.first);
  stats.peak_bytes = s.context.memory_high_water();
  stats.launches = unsigned(s.context.kernel_launches() - launches);
  stats.blocking_reads = unsigned(s.context.blocking_reads() - reads);
  stats.started = started;
  stats.host_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
}

const std::vector<ClosePair>& Detector::close_pairs() const
{
  state_->check_usable();
  if (state_->options.detects != Detects::close_pairs) throw Error("close_pairs() needs a detector made for Detects::close_pairs");
  return state_->close;
}

ContactSpan Detector::contacts() const
{
  state_->check_usable();
  if (!state_->have_contacts) throw Error("the last step read back only the earliest times; detect(Report::contacts)");
  return state_->contacts;
}

std::vector<double> Detector::earliest_toi() const
{
  const State& s = *state_;
  s.check_usable();
  runtime::Context::ThreadGuard one_thread(s.context);
  std::vector<double> out(s.scene.objects.size(), 1.0);
  // A step that read its contacts back left the device's minimum undone (ccd_graph.cpp):
  // the same minimum over the same times, each rounded down to float as earliest.cl
  // rounds it.
  if (s.have_contacts) {
    for (const Contact& c : s.contacts) {
      float t = static_cast<float>(c.toi);
      if (double(t) > c.toi) t = std::nextafter(t, 0.0f);
      for (const std::uint32_t o : {c.object_a, c.object_b}) out[o] = std::min(out[o], double(t));
    }
    return out;
  }
  if (!s.have_earliest) return out;
  for (std::size_t o = 0; o < out.size() && o < s.earliest_bits.size(); ++o) {
    float t;
    std::memcpy(&t, &s.earliest_bits[o], sizeof t);
    out[o] = t;
  }
  return out;
}

Candidates Detector::candidates() const
{
  const State& s = *state_;
  s.check_usable();
  runtime::Context::ThreadGuard one_thread(s.context);
  const auto n = std::uint32_t(s.scene.objects.size());
  std::map<std::pair<std::uint32_t, std::uint32_t>, CandidateBlock> blocks;
  for (std::uint32_t a = 0; a < n; ++a)
    for (std::uint32_t b = a; b < n; ++b)
      if (s.scene.may_collide(a, b)) {
        blocks[{a, b}] = {a, b, {}, {}};
        blocks[{b, a}] = {b, a, {}, {}};
      }
  const CcdStreams& st = s.streams;
  for (auto stream : {st.vf, st.kept_vf, st.ee, st.kept_ee}) {
    if (!has(stream)) continue;
    const ContactKind kind = stream == st.vf || stream == st.kept_vf ? ContactKind::vertex_face : ContactKind::edge_edge;
    for (const Pair& p : s.scheduler->download<Pair>(stream)) {
      const auto l = s.ids.local(kind, p[0], p[1]);
      CandidateBlock& block = blocks.at({l.object_a, l.object_b});
      if (kind == ContactKind::vertex_face) block.vf.push_back({l.a, l.b});
      else block.ee.push_back({l.a, l.b});
    }
  }
  Candidates out;
  for (auto& [key, block] : blocks) {
    std::sort(block.vf.begin(), block.vf.end());
    std::sort(block.ee.begin(), block.ee.end());
    out.blocks.push_back(std::move(block));
  }
  return out;
}

const DetectorStats& Detector::stats() const { return state_->stats; }
const runtime::StreamGraph& Detector::graph() const { return state_->scheduler->graph(); }
const SceneDescription& Detector::scene() const { return state_->scene; }

}  // namespace cstreams
