#include <cstreams/ccd_graph.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/float_bounds.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>

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

constexpr std::uint32_t exact_front = 0xffffffffu;
using Pair = std::array<std::uint32_t, 2>;
using Found = std::array<std::uint32_t, 4>;

}  // namespace

struct Detector::State {
  State(runtime::Context& c, SceneDescription s, const DetectorOptions& o) : context(c), scene(std::move(s)), options(o)
  {
  }

  runtime::Context& context;
  SceneDescription scene;
  DetectorOptions options;
  SceneLayout layout;
  CcdStreams streams;
  std::unique_ptr<runtime::Scheduler> scheduler;
  std::uint32_t level_cap = exact_front;
  std::uint32_t deepest_level = 0;
  std::size_t front_limit = 0;
  std::vector<Contact> contacts;
  bool have_contacts = false;
  DetectorStats stats;

  bool has(runtime::StreamId s) const { return s.index != runtime::StreamId{}.index; }
  const ObjectSlot& slot(std::uint32_t object) const { return layout.slots[layout.slot_of[object]]; }
  const ObjectDescription& object(std::uint32_t o) const { return scene.objects[o]; }

  std::uint32_t object_index(std::uint32_t o) const
  {
    if (o >= scene.objects.size())
      throw InputError("no object " + std::to_string(o) + " in a scene of " + std::to_string(scene.objects.size()));
    return o;
  }

  // Checks positions for an object that moves and rounds them to float.
  std::vector<float> checked(std::uint32_t o, const std::vector<Vec3>& x) const
  {
    object_index(o);
    const ObjectDescription& d = object(o);
    if (d.kind == ObjectKind::static_) throw InputError("object '" + d.name + "' is static and cannot move");
    if (x.size() != d.positions.size())
      throw InputError("object '" + d.name + "' has " + std::to_string(d.positions.size()) + " vertices, not " +
                       std::to_string(x.size()));
    try {
      return to_float_positions(x);
    } catch (const InputError& e) {
      throw InputError("object '" + d.name + "': " + e.what());
    }
  }

  void write_positions(runtime::StreamId single, runtime::StreamId exact, std::uint32_t o, const std::vector<float>& f,
                       const std::vector<Vec3>& x)
  {
    const std::uint32_t first = slot(o).first_vertex;
    scheduler->write(single, first, f.data(), x.size());
    if (has(exact)) scheduler->write(exact, first, x.data(), x.size());
  }

  void upload_scene()
  {
    const CcdStreams& s = streams;
    runtime::Scheduler& q = *scheduler;
    const Topology& t = layout.topology;
    q.write(s.faces, 0, t.faces.data(), t.faces.size());
    q.write(s.edges, 0, t.edges.data(), t.edges.size());
    q.write(s.nodes, 0, layout.nodes.data(), layout.nodes.size());
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      const std::vector<Vec3>& x = object(o).positions;
      const auto f = to_float_positions(x);
      write_positions(s.x0, s.x0_double, o, f, x);
      write_positions(s.x1, s.x1_double, o, f, x);
      const ObjectSlot& sl = slot(o);
      if (sl.moving) continue;
      // Static bounds never change: the host's float twin computes them once.
      const FloatBounds b = float_bounds(build_topology(object(o).faces, x.size()), layout.trees[o], x, x,
                                         float_above(options.solver.min_separation));
      q.write(s.face_boxes, sl.first_face, b.faces.data(), b.faces.size());
      q.write(s.edge_boxes, sl.first_edge, b.edges.data(), b.edges.size());
      q.write(s.vertex_boxes, sl.first_vertex, b.vertices.data(), b.vertices.size());
      q.write(s.node_boxes, sl.first_node, b.nodes.data(), b.nodes.size());
    }
    if (!has(s.front)) return;
    q.write(s.face_edges, 0, t.face_edges.data(), t.face_edges.size());
    const std::vector<std::uint32_t> owned(t.owned.begin(), t.owned.end());
    q.write(s.owned, 0, owned.data(), owned.size());
    if (has(s.orphan_vf)) q.write(s.orphan_vf, 0, layout.orphans.vf.data(), layout.orphans.vf.size());
    if (has(s.orphan_ee)) q.write(s.orphan_ee, 0, layout.orphans.ee.data(), layout.orphans.ee.size());
    q.write(s.vertex_object, 0, layout.vertex_object.data(), layout.vertex_object.size());
  }

  std::size_t count(runtime::StreamId s) const { return has(s) ? scheduler->count(s) : 0; }

  // Runs the graph; a deferred front that outgrows its budget is kept coarser and
  // the step runs again.
  void run()
  {
    for (;;) {
      try {
        scheduler->run();
        break;
      } catch (const runtime::StreamLimitExceeded& e) {
        if (options.front != FrontMode::deferred || level_cap == 0)
          throw Error("the front does not fit its budget of " + std::to_string(options.front_budget_mb) +
                      " MiB even at the roots: " + e.what());
        level_cap = level_cap > 2 ? level_cap - 2 : 0;
        scheduler->set(streams.level_cap, level_cap);
        ++stats.front_retries;
      }
    }
    if (options.front == FrontMode::deferred && level_cap < deepest_level &&
        count(streams.next_front) < front_limit / 4)
      scheduler->set(streams.level_cap, ++level_cap);
  }

  // (object, local id) of a global vertex, face or edge.
  std::uint32_t object_of_vertex(std::uint32_t v) const { return layout.vertex_object[v]; }
  std::uint32_t object_of_face(std::uint32_t f) const { return object_of_vertex(layout.topology.faces[f][0]); }
  std::uint32_t object_of_edge(std::uint32_t e) const { return object_of_vertex(layout.topology.edges[e][0]); }

  // A device feature pair in the host's terms: a vertex of object_a and a face of
  // object_b, or an edge of object_a and an edge of object_b with object_a <= object_b;
  // ids local to their objects.
  struct LocalPair {
    std::uint32_t object_a, object_b, a, b;
  };
  LocalPair local(ContactKind kind, std::uint32_t a, std::uint32_t b) const
  {
    if (kind == ContactKind::vertex_face) {
      const std::uint32_t oa = object_of_vertex(a), ob = object_of_face(b);
      return {oa, ob, a - slot(oa).first_vertex, b - slot(ob).first_face};
    }
    std::uint32_t oa = object_of_edge(a), ob = object_of_edge(b);
    if (oa > ob) {
      std::swap(oa, ob);
      std::swap(a, b);
    }
    return {oa, ob, a - slot(oa).first_edge, b - slot(ob).first_edge};
  }

  Contact contact(ContactKind kind, const Found& c) const
  {
    Contact out;
    out.kind = kind;
    if (options.solver.precision == Precision::double_) {
      const std::uint64_t bits = std::uint64_t(c[2]) | std::uint64_t(c[3]) << 32;
      std::memcpy(&out.toi, &bits, sizeof bits);
    } else {
      float toi;
      std::memcpy(&toi, &c[2], sizeof toi);
      out.toi = toi;
    }
    const LocalPair p = local(kind, c[0], c[1]);
    out.object_a = p.object_a;
    out.object_b = p.object_b;
    if (kind == ContactKind::vertex_face) {
      const Face& f = object(p.object_b).faces[p.b];
      out.v = {p.a, f[0], f[1], f[2]};
      return out;
    }
    auto edge = [&](std::uint32_t o, std::uint32_t e) {
      const ObjectSlot& sl = slot(o);
      const Edge& g = layout.topology.edges[sl.first_edge + e];
      return Edge{g[0] - sl.first_vertex, g[1] - sl.first_vertex};
    };
    Edge a = edge(p.object_a, p.a), b = edge(p.object_b, p.b);
    if (p.object_a == p.object_b && b < a) std::swap(a, b);
    out.v = {a[0], a[1], b[0], b[1]};
    return out;
  }
};

Detector::Detector(runtime::Context& device, SceneDescription scene, DetectorOptions options)
    : state_(std::make_unique<State>(device, std::move(scene), options))
{
  State& s = *state_;
  if (options.solver.precision == Precision::double_ && !device.device().fp64)
    throw InputError("device " + device.device().name + " has no double precision; use single");
  if (options.front == FrontMode::deferred && !(options.front_budget_mb > 0))
    throw InputError("the deferred front needs a positive memory budget");
  device.programs().add_sources(ccd_kernel_sources());
  s.layout = make_layout(s.scene, options.solver.min_separation);
  std::size_t target = 4 * device.device().compute_units * device.work_group_size();
  if (options.front == FrontMode::deferred) {
    // Both front buffers share the budget.
    s.front_limit = std::size_t(options.front_budget_mb * 1024 * 1024) / (2 * sizeof(NodePair));
    target = std::min(target, s.front_limit / 4);
    s.deepest_level = s.layout.depth > 0 ? 2 * std::uint32_t(s.layout.depth - 1) : 0;
    s.level_cap = s.deepest_level;
  }
  const std::vector<NodePair> front = expand_front(s.layout, target);
  CcdGraph g = build_ccd_graph(s.layout, options, front.size());
  s.streams = g.streams;
  s.scheduler = std::make_unique<runtime::Scheduler>(
      device, std::move(g.graph), runtime::SchedulerOptions{options.registration, options.profile});
  s.upload_scene();
  if (!s.has(s.streams.front)) return;
  if (options.front == FrontMode::deferred) {
    s.scheduler->set_limit(s.streams.front, s.front_limit);
    s.scheduler->set_limit(s.streams.next_front, s.front_limit);
  }
  s.scheduler->upload(s.streams.front, front);
  s.scheduler->set(s.streams.level_cap, s.level_cap);
}

Detector::~Detector() = default;

std::uint32_t Detector::object(const std::string& name) const
{
  const auto& objects = state_->scene.objects;
  for (std::uint32_t o = 0; o < objects.size(); ++o)
    if (objects[o].name == name) return o;
  throw InputError("no object named '" + name + "'");
}

void Detector::set_positions(std::uint32_t object, const std::vector<Vec3>& end)
{
  State& s = *state_;
  const auto f = s.checked(object, end);
  s.write_positions(s.streams.x1, s.streams.x1_double, object, f, end);
}

void Detector::set_step(std::uint32_t object, const std::vector<Vec3>& start, const std::vector<Vec3>& end)
{
  State& s = *state_;
  const auto f0 = s.checked(object, start), f1 = s.checked(object, end);
  s.write_positions(s.streams.x0, s.streams.x0_double, object, f0, start);
  s.write_positions(s.streams.x1, s.streams.x1_double, object, f1, end);
}

void Detector::detect(Report report)
{
  State& s = *state_;
  const auto started = std::chrono::steady_clock::now();
  const CcdStreams& st = s.streams;
  s.stats.front_retries = 0;
  s.run();
  runtime::Scheduler& q = *s.scheduler;
  if (s.options.front != FrontMode::none && s.has(st.front)) q.swap(st.front, st.next_front);
  // The end of this step starts the next one.
  q.copy(st.x1, 0, st.x0, 0, s.layout.moving_vertices);
  if (s.has(st.x1_double)) q.copy(st.x1_double, 0, st.x0_double, 0, s.layout.moving_vertices);

  s.contacts.clear();
  s.have_contacts = report == Report::contacts;
  if (s.have_contacts) {
    for (const auto& [stream, kind] : st.contacts)
      for (const Found& c : q.download<Found>(stream)) s.contacts.push_back(s.contact(kind, c));
    sort_canonical(s.contacts);
  }
  DetectorStats& stats = s.stats;
  stats.run = q.stats();
  stats.front_pairs = s.options.front == FrontMode::none ? 0 : s.count(st.front);
  stats.front_level_cap = s.level_cap;
  stats.triangle_pairs = s.count(st.triangle_pairs);
  stats.vf_candidates = s.count(st.vf) + s.count(st.kept_vf);
  stats.ee_candidates = s.count(st.ee) + s.count(st.kept_ee);
  stats.contacts = 0;
  for (const auto& c : st.contacts) stats.contacts += s.count(c.first);
  stats.host_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
}

const std::vector<Contact>& Detector::contacts() const
{
  if (!state_->have_contacts) throw Error("the last step read back only the earliest times; detect(Report::contacts)");
  return state_->contacts;
}

std::vector<double> Detector::earliest_toi() const
{
  const State& s = *state_;
  std::vector<double> out(s.scene.objects.size(), 1.0);
  if (!s.has(s.streams.earliest)) return out;
  const auto bits = s.scheduler->download<std::uint32_t>(s.streams.earliest);
  for (std::size_t o = 0; o < out.size(); ++o) {
    float t;
    std::memcpy(&t, &bits[o], sizeof t);
    out[o] = t;
  }
  return out;
}

Candidates Detector::candidates() const
{
  const State& s = *state_;
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
    if (!s.has(stream)) continue;
    const ContactKind kind = stream == st.vf || stream == st.kept_vf ? ContactKind::vertex_face : ContactKind::edge_edge;
    for (const Pair& p : s.scheduler->download<Pair>(stream)) {
      const auto l = s.local(kind, p[0], p[1]);
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
