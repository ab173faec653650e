#include <cstreams/device_broad_phase.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/narrow_phase.hpp>
#include <cstreams/runtime/context.hpp>

#include <algorithm>
#include <cstring>

namespace cstreams {

namespace {
// Depth-first BVTT search holds at most 2 * depth + 1 pairs (see broad_phase.cl);
// CS_BVTT_STACK = 128 covers trees of up to 40 levels, about 2^39 faces.
constexpr std::size_t max_tree_depth = 40;
using Pair = std::array<std::uint32_t, 2>;
}  // namespace

std::vector<std::array<std::int32_t, 2>> seed_front(const Bvh& bvh, std::size_t target)
{
  std::vector<std::array<std::int32_t, 2>> front{{0, 0}};
  while (front.size() < target) {
    std::vector<std::array<std::int32_t, 2>> next;
    bool expanded = false;
    for (const auto& [i, j] : front) {
      const std::int32_t li = bvh.nodes[std::size_t(i)].left, lj = bvh.nodes[std::size_t(j)].left;
      // The same choices as the traversal kernel, without the bounds tests.
      if (i == j) {
        if (li < 0) continue;  // a leaf against itself pairs nothing
        next.insert(next.end(), {{li, li}, {li + 1, li + 1}, {li, li + 1}});
      } else if (li < 0 && lj < 0) {
        next.push_back({i, j});
        continue;
      } else if (lj < 0 || (li >= 0 && i <= j)) {
        next.insert(next.end(), {{li, j}, {li + 1, j}});
      } else {
        next.insert(next.end(), {{i, lj}, {i, lj + 1}});
      }
      expanded = true;
    }
    front = std::move(next);
    if (!expanded) break;
  }
  return front;
}

struct DeviceBroadPhase::Streams {
  BoundsStreams bounds;
  runtime::StreamId seeds, face_edges, owned, triangle_pairs, vf, ee, orphan_vf, orphan_ee, kept_vf, kept_ee;
  std::vector<std::pair<runtime::StreamId, ContactKind>> contacts;  // one per candidate stream
};

DeviceBroadPhase::DeviceBroadPhase(runtime::Context& context, const Topology& t, const Bvh& bvh, float separation,
                                   runtime::Registration registration, std::optional<SolverOptions> narrow_phase)
    : streams_(std::make_unique<Streams>()), topology_(t),
      narrow_phase_(narrow_phase.has_value())
{
  using namespace runtime;
  if (bvh.depth() > max_tree_depth)
    throw Error("a BVH of depth " + std::to_string(bvh.depth()) + " is deeper than the traversal's stack allows (" +
                std::to_string(max_tree_depth) + ")");
  context.programs().add_sources(ccd_kernel_sources());
  const char* program = "ccd/broad_phase.cl";
  const auto seeds = seed_front(bvh, 4 * context.device().compute_units * context.work_group_size());
  const OrphanSet orphans = build_orphans(t);
  // Expected sizes only; every variable stream grows as its counter demands.
  const std::size_t guess = std::max<std::size_t>(1024, t.faces.size());

  StreamGraph g;
  Streams& s = *streams_;
  s.bounds = add_bounds_passes(g, t, bvh, separation);
  s.seeds = g.fixed("bvtt seeds", 8, seeds.size());
  s.face_edges = g.fixed("face edges", 12, t.faces.size());
  s.owned = g.fixed("ownership", 4, t.faces.size());
  s.orphan_vf = g.fixed("orphan vf", 8, orphans.vf.size());
  s.orphan_ee = g.fixed("orphan ee", 8, orphans.ee.size());
  s.triangle_pairs = g.variable("triangle pairs", 8, guess);
  s.vf = g.variable("vf candidates", 8, guess);
  s.ee = g.variable("ee candidates", 8, guess);
  s.kept_vf = g.variable("orphan vf candidates", 8, guess / 4);
  s.kept_ee = g.variable("orphan ee candidates", 8, guess / 4);
  const BoundsStreams& b = s.bounds;
  g.pass("traverse", {program, "cs_traverse"})
      .launch_over(s.seeds)
      .read(b.node_boxes)
      .emit(s.triangle_pairs)
      .expect_items(4)
      .arg(buffer_of(s.seeds))
      .arg(count_of(s.seeds))
      .arg(buffer_of(b.nodes))
      .arg(buffer_of(b.node_boxes))
      .arg(buffer_of(b.faces));
  g.pass("decompose", {program, "cs_decompose"})
      .launch_over(s.triangle_pairs)
      .emit(s.vf)
      .emit(s.ee)
      .arg(buffer_of(s.triangle_pairs))
      .arg(count_of(s.triangle_pairs))
      .arg(buffer_of(b.faces))
      .arg(buffer_of(s.face_edges))
      .arg(buffer_of(s.owned))
      .arg(buffer_of(b.vertex_boxes))
      .arg(buffer_of(b.edge_boxes))
      .arg(buffer_of(b.face_boxes));
  auto cull_orphans = [&](const char* name, StreamId pairs, StreamId kept, StreamId first, StreamId second) {
    g.pass(name, {program, "cs_cull_pairs"})
        .launch_over(pairs)
        .cull(pairs, kept)
        .arg(buffer_of(pairs))
        .arg(count_of(pairs))
        .arg(buffer_of(first))
        .arg(buffer_of(second));
  };
  cull_orphans("cull orphan vf", s.orphan_vf, s.kept_vf, b.vertex_boxes, b.face_boxes);
  cull_orphans("cull orphan ee", s.orphan_ee, s.kept_ee, b.edge_boxes, b.edge_boxes);
  if (narrow_phase) {
    const SolverOptions& o = *narrow_phase;
    if (o.precision != Precision::single)
      throw Error("the device pipeline runs its elementary tests in single precision only, for now");
    const std::string options = solver_build_options(o);
    const float tolerance = float_above(o.tolerance);
    const float min_separation = float_above(o.min_separation);
    const std::pair<StreamId, ContactKind> inputs[] = {{s.vf, ContactKind::vertex_face},
                                                       {s.kept_vf, ContactKind::vertex_face},
                                                       {s.ee, ContactKind::edge_edge},
                                                       {s.kept_ee, ContactKind::edge_edge}};
    for (const auto& [input, kind] : inputs) {
      const std::string name = g.stream(input).name;
      const StreamId out = g.variable("contacts from " + name, 16, 256);
      g.pass("test " + name, {"ccd/narrow_phase_pairs.cl", "cs_narrow_phase_pairs", options})
          .launch_over(input)
          .emit(out)
          .expect_items(0.25)
          .arg(buffer_of(input))
          .arg(count_of(input))
          .arg(value_of(cl_uint(kind == ContactKind::vertex_face)))
          .arg(buffer_of(b.x0))
          .arg(buffer_of(b.x1))
          .arg(buffer_of(b.faces))
          .arg(buffer_of(b.edges))
          .arg(value_of(cl_uint(0)))
          .arg(value_of(tolerance))
          .arg(value_of(min_separation))
          .arg(value_of(cl_uint(o.max_iterations)))
          .arg(value_of(cl_uint(o.filter)));
      s.contacts.emplace_back(out, kind);
    }
  }
  scheduler_ = std::make_unique<Scheduler>(context, std::move(g), SchedulerOptions{registration, true});

  upload_topology(*scheduler_, b, t, bvh);
  scheduler_->upload(s.seeds, seeds);
  scheduler_->upload(s.face_edges, t.face_edges);
  std::vector<std::uint32_t> owned(t.owned.begin(), t.owned.end());
  scheduler_->upload(s.owned, owned);
  scheduler_->upload(s.orphan_vf, orphans.vf);
  scheduler_->upload(s.orphan_ee, orphans.ee);
}

DeviceBroadPhase::~DeviceBroadPhase() = default;

Candidates DeviceBroadPhase::run(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1)
{
  const Streams& s = *streams_;
  upload_positions(*scheduler_, s.bounds, x0, x1, topology_.vertex_count);
  scheduler_->run();

  CandidateBlock block{0, 0, {}, {}};
  for (auto stream : {s.vf, s.kept_vf})
    for (const auto& p : scheduler_->download<Pair>(stream)) block.vf.push_back({p[0], p[1]});
  for (auto stream : {s.ee, s.kept_ee})
    for (const auto& p : scheduler_->download<Pair>(stream)) block.ee.push_back({p[0], p[1]});
  std::sort(block.vf.begin(), block.vf.end());
  std::sort(block.ee.begin(), block.ee.end());
  Candidates out;
  out.blocks.push_back(std::move(block));
  return out;
}

std::vector<Contact> DeviceBroadPhase::contacts() const
{
  if (!narrow_phase_) throw Error("this device broad phase was built without a narrow phase");
  std::vector<Contact> out;
  const Topology& t = topology_;
  for (const auto& [stream, kind] : streams_->contacts)
    for (const auto& c : scheduler_->download<std::array<std::uint32_t, 4>>(stream)) {
      float toi;
      std::memcpy(&toi, &c[3], sizeof toi);
      Contact contact;
      contact.kind = kind;
      contact.toi = toi;
      if (kind == ContactKind::vertex_face) {
        const Face& f = t.faces[c[1]];
        contact.v = {c[0], f[0], f[1], f[2]};
      } else {
        Edge a = t.edges[c[0]], b = t.edges[c[1]];
        if (b < a) std::swap(a, b);
        contact.v = {a[0], a[1], b[0], b[1]};
      }
      out.push_back(contact);
    }
  sort_canonical(out);
  return out;
}

}  // namespace cstreams
