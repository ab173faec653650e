#include "measurement.hpp"

#include "commands.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/scenes/generators.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <unistd.h>

namespace cstreams::cli {

namespace {

// timed: whether the passes' device times are known (null in JSON where not).
nlohmann::json step_json(std::size_t frame, const DetectorStats& s, double host_ms, bool timed)
{
  nlohmann::json passes = nlohmann::json::object(), streams = nlohmann::json::object();
  for (const auto& p : s.run.passes) {
    auto& pass = passes[p.name] = {{"ms", timed ? nlohmann::json(p.device_ns * 1e-6) : nlohmann::json()},
                                   {"launches", p.launches},
                                   {"reruns", p.reruns},
                                   {"scratch_bytes", p.scratch_bytes},
                                   {"segment_bytes", p.segment_bytes}};
    if (p.rounds) pass.update({{"rounds", p.rounds}, {"list_items", p.list_items}, {"widest_list", p.widest_list}});
  }
  // Every command of the step on the device's clock, in microseconds from the first
  // one's start: where the device waited for the host (before a command was queued) and
  // for a launch (between its queueing and its start). And on the host's clock, from
  // the step's start, when it was queued: what the host did before the first command
  // and after the last is the rest of the step's wall time.
  nlohmann::json commands = nlohmann::json::array();
  // Apart in integers first: a device clock counts from its epoch, past what a double
  // holds to the nanosecond.
  const std::int64_t first = std::int64_t(s.run.span().start);
  const auto us = [&](std::uint64_t t) { return double(std::int64_t(t) - first) * 1e-3; };
  const auto host_us = [&](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::micro>(t - s.started).count();
  };
  if (timed)
    for (const auto& c : s.run.commands)
      commands.push_back({{"what", c.label},
                          {"queued_us", us(c.queued)},
                          {"start_us", us(c.start)},
                          {"end_us", us(c.end)},
                          {"host_us", host_us(c.host_queued)}});
  for (const auto& st : s.run.streams)
    streams[st.name] = {{"count", st.count},
                        {"items", st.items},
                        {"capacity", st.capacity},
                        {"bytes", st.bytes},
                        {"peak_bytes", st.peak_bytes}};
  return {{"frame", frame},
          {"host_ms", host_ms},
          {"device_ms", s.device_ns() * 1e-6},
          {"device_span_ms", timed ? nlohmann::json(s.device_span_ns * 1e-6) : nlohmann::json()},
          {"launches", s.launches},
          {"blocking_reads", s.blocking_reads},
          {"triangle_pairs", s.triangle_pairs},
          {"vf_candidates", s.vf_candidates},
          {"ee_candidates", s.ee_candidates},
          {"contacts", s.contacts},
          {"escalated", s.escalated},
          {"front_pairs", s.front_pairs},
          {"front_level_cap", s.front_level_cap},
          {"front_retries", s.front_retries},
          {"device_bytes", s.device_bytes()},
          {"peak_bytes", s.peak_bytes},
          {"scratch_bytes", s.run.scratch_bytes},
          {"segment_bytes", s.run.segment_bytes},
          {"slices", s.run.slices},
          {"sliced_pass", s.run.sliced_pass},
          {"passes", passes},
          {"streams", streams},
          {"commands", commands}};
}

}  // namespace

void add_measure_options(CLI::App& cmd, MeasureOptions& o)
{
  cmd.add_option("scene", o.paths,
                 "A scene manifest (.json), a mesh file, or the frame files of one mesh; default: a bundled "
                 "cloth-on-sphere scene");
  cmd.add_flag("--split", o.split, "Treat each connected component of the mesh as an object");
  cmd.add_option("--solver", o.solver, "conservative (never misses) or cubic (the paper's)");
  cmd.add_option("--precision", o.precision, "single or double");
  cmd.add_option("--tolerance", o.tolerance, "Solver tolerance, relative to the query's coordinates");
  cmd.add_option("--min-separation", o.min_separation, "Distance below which primitives count as colliding");
  cmd.add_option("--max-iterations", o.max_iterations,
                 "Conservative solver's work limit per pair; reaching it reports a collision");
  cmd.add_flag("--no-escalation", o.no_escalation,
               "Single precision: report the contacts float cannot prove as they are, rather than deciding them "
               "again in double");
  cmd.add_option("--front", o.front, "BVTT front: none, exact or deferred");
  cmd.add_option("--front-budget", o.front_budget, "Deferred front: device memory for the front, MiB");
  cmd.add_option("--front-climb", o.front_climb,
                 "Kept front: BVTT levels above the deepest to which pairs that move apart may climb");
  cmd.add_option("--memory-budget", o.memory_budget,
                 "Device memory for the whole pipeline, MiB (default: all the device has); registration trades speed "
                 "for memory to stay under it");
  cmd.add_option("--registration", o.registration, "segmented-lock, lock-free or global-atomic");
  cmd.add_option("--frames", o.frames, "Steps A:B (from frame A to B), or one step A; default: all");
  cmd.add_option("--repeat", o.repeat, "Run each step this many times and report medians (the first is a warm-up)");
  cmd.add_flag("--no-profile", o.no_profile,
               "Record no kernel timings: device times are unknown, wall times leave out what timing costs the host");
  cmd.add_flag("--no-upload-ahead", o.no_upload_ahead,
               "Upload each step's positions just before it runs, not while the step before runs (or the run "
               "before it, with --repeat)");
}

DetectorOptions detector_options(const MeasureOptions& o)
{
  DetectorOptions options;
  options.solver.solver = parse_solver(o.solver);
  options.solver.precision = parse_precision(o.precision);
  options.solver.tolerance = o.tolerance;
  options.solver.min_separation = o.min_separation;
  options.solver.max_iterations = o.max_iterations;
  options.solver.escalate = !o.no_escalation;
  options.front = parse_front_mode(o.front);
  options.front_budget_mb = o.front_budget;
  options.front_climb_levels = o.front_climb;
  options.registration = runtime::parse_registration(o.registration);
  options.profile = !o.no_profile;
  return options;
}

bool uploads_ahead(const MeasureOptions& o) { return !o.no_upload_ahead; }

void check(const MeasureOptions& o)
{
  check_option("--tolerance", o.tolerance, option_ranges::tolerance);
  check_option("--min-separation", o.min_separation, option_ranges::min_separation);
  check_option("--max-iterations", o.max_iterations, option_ranges::max_iterations);
  check_option("--front-budget", o.front_budget, option_ranges::front_budget_mb);
  if (o.memory_budget != 0) check_option("--memory-budget", o.memory_budget, option_ranges::memory_budget_mb);
  check_option("--repeat", o.repeat, {1, 1000000});
  detector_options(o);
  parse_step_range(o.frames);
}

std::vector<double> warm_call_ms(unsigned repeat, const std::function<void()>& call)
{
  std::vector<double> ms;
  for (unsigned i = 0; i <= repeat; ++i) {
    const auto begin = std::chrono::steady_clock::now();
    call();
    const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - begin;
    if (i > 0) ms.push_back(took.count());
  }
  return ms;
}

void print_passes(const DetectorStats& stats)
{
  std::printf("\ndevice time per pass in the last call (ms):\n");
  for (const auto& p : stats.run.passes)
    std::printf("  %-44s %9.3f  (%u launches)\n", p.name.c_str(), double(p.device_ns) * 1e-6, p.launches);
  std::printf("  %-44s %9.3f\n  %-44s %9.3f\n", "all passes", double(stats.device_ns()) * 1e-6, "call (host wall time)",
              stats.host_ms);
}

double median(std::vector<double> v)
{
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

Tail tail(const std::vector<double>& per_step, std::size_t first_frame)
{
  Tail t;
  if (per_step.empty()) return t;
  if (std::any_of(per_step.begin(), per_step.end(), [](double v) { return std::isnan(v); })) {
    t.p90 = t.max = std::numeric_limits<double>::quiet_NaN();
    return t;
  }
  std::vector<double> sorted = per_step;
  std::sort(sorted.begin(), sorted.end());
  t.p90 = sorted[std::size_t(std::ceil(0.9 * double(sorted.size()))) - 1];
  const auto slowest = std::max_element(per_step.begin(), per_step.end());
  t.max = *slowest;
  t.max_frame = first_frame + std::size_t(slowest - per_step.begin());
  return t;
}

SceneSource::~SceneSource()
{
  std::error_code ignored;
  if (!temporary.empty()) std::filesystem::remove_all(temporary, ignored);
}

std::unique_ptr<SceneSource> scene_source(const MeasureOptions& o)
{
  auto source = std::make_unique<SceneSource>();
  if (!o.paths.empty()) {
    source->scene = open_scene(o.paths, o.split);
    return source;
  }
  source->temporary =
      (std::filesystem::temp_directory_path() / ("cstreams-default-scene-" + std::to_string(::getpid()))).string();
  // A 30x30 cloth dropped on a static sphere: self-contacts and contacts with the
  // sphere within a few seconds on any device.
  source->scene = load_scene(scenes::generate_scene({"cloth-sphere", source->temporary, 1, 24, 30}));
  return source;
}

namespace {

// One run's positions: the step's ends (both, where the step repeats), unless they were
// uploaded ahead; and ahead, what the next run needs (this step again, or the next's end).
void give_positions(Detector& detector, const Scene& scene, const Step& step, bool repeated, bool given_ahead,
                    bool repeats_ahead, const Step* next)
{
  for (std::uint32_t obj = 0; obj < scene.objects.size(); ++obj) {
    if (scene.objects[obj].kind == ObjectKind::static_) continue;
    if (!given_ahead) {
      if (repeated) detector.set_step(obj, step.x0[obj], step.x1[obj]);
      else detector.set_positions(obj, step.x1[obj]);
    }
    if (repeats_ahead) detector.upload_ahead(obj, step.x0[obj], step.x1[obj]);
    else if (next) detector.upload_ahead(obj, next->x1[obj]);
  }
}

// A step's contacts (or earliest times), and the first contact of the run.
void record_contacts(Measurement& m, const Detector& detector, bool earliest_only, std::size_t found, std::size_t frame)
{
  m.contact_count += found;
  std::vector<double> earliest;
  if (earliest_only) {
    earliest = detector.earliest_toi();
  } else {
    const auto& contacts = detector.contacts();
    m.contacts.insert(m.contacts.end(), contacts.begin(), contacts.end());
    for (const Contact& c : contacts) earliest.push_back(c.toi);
  }
  m.step_ends.push_back(m.contacts.size());
  // 1 is "no contact" in earliest_toi(), and the end of the step for a contact.
  const bool any = earliest_only ? found > 0 : !earliest.empty();
  if (m.first_contact_toi > 1 && any) {
    m.first_contact_toi = *std::min_element(earliest.begin(), earliest.end());
    m.first_contact_frame = frame;
  }
}

}  // namespace

Measurement measure(const MeasureOptions& o, const Scene& scene, std::size_t first, std::size_t last,
                    runtime::Context& context)
{
  Measurement m;
  m.device = context.device().name + (context.device().profile.empty() ? "" : " as " + context.device().profile);
  m.platform = context.device().platform_name;
  if (o.memory_budget > 0) context.set_memory_limit(std::size_t(o.memory_budget * (1 << 20)));
  const DetectorOptions options = detector_options(o);
  m.escalates = escalates(options.solver, graph_device(context));
  const SceneDescription description = describe(scene, first);
  const auto making = std::chrono::steady_clock::now();
  Detector detector(context, description, options);
  m.detector_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - making).count();
  const bool terminal = ::isatty(STDERR_FILENO);
  // A device without a kernel timer, or a run that records none, reports times as
  // unknown (NaN; null in JSON).
  const bool timed = context.device().profiling_timer && !o.no_profile;
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  const bool ahead = uploads_ahead(o);
  std::optional<Step> next;
  for (std::size_t frame = first; frame < last; ++frame) {
    const Step step = next ? std::move(*next) : load_step(scene, frame);
    next.reset();
    if (ahead && frame + 1 < last) next = load_step(scene, frame + 1);
    std::vector<double> host, device, span, uploads_and_step;
    DetectorStats stats;
    for (unsigned r = 0; r < o.repeat; ++r) {
      const auto started = std::chrono::steady_clock::now();
      // Steps that follow each other need only the new end; a repeated step both. Ahead,
      // each run uploads what the run after it needs: the first run of the first step
      // alone has its positions given before it.
      give_positions(detector, scene, step, r > 0, ahead && (r > 0 || frame != first), ahead && r + 1 < o.repeat,
                     next ? &*next : nullptr);
      detector.detect(o.earliest_only ? Report::earliest_toi : Report::contacts);
      const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
      stats = detector.stats();
      // A warm-up's peak counts: it is what the step costs when it first runs.
      m.peak_bytes = std::max(m.peak_bytes, stats.peak_bytes);
      // With repeats, the first run of a step is a warm-up.
      if (o.repeat == 1 || r > 0) {
        host.push_back(stats.host_ms);
        uploads_and_step.push_back(wall);
        device.push_back(timed ? stats.device_ns() * 1e-6 : unknown);
        span.push_back(timed ? stats.device_span_ns * 1e-6 : unknown);
        for (const auto& p : stats.run.passes) m.pass_ms[p.name].push_back(timed ? p.device_ns * 1e-6 : unknown);
      }
    }
    if (m.pass_order.empty())
      for (const auto& p : stats.run.passes) m.pass_order.push_back(p.name);
    const double host_ms = median(host), device_ms = median(device);
    m.host_ms.push_back(host_ms);
    m.device_ms.push_back(device_ms);
    m.step_ms.push_back(median(uploads_and_step));
    m.steps.push_back(step_json(frame, stats, host_ms, timed));
    m.steps.back()["step_ms"] = m.step_ms.back();
    m.steps.back()["device_ms"] = device_ms;
    if (timed) m.steps.back()["device_span_ms"] = median(span);
    record_contacts(m, detector, o.earliest_only, stats.contacts, frame);
    if (terminal)
      std::fprintf(stderr, "\rstep %zu/%zu on %s: %zu contacts, %.3f ms   ", frame - first + 1, last - first,
                   m.device.c_str(), stats.contacts, host_ms);
  }
  if (terminal) std::fprintf(stderr, "\n");
  return m;
}

}  // namespace cstreams::cli
