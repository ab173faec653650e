#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/reference/reference_ccd.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <type_traits>

namespace cstreams {

Step load_step(const Scene& scene, std::size_t frame)
{
  if (frame + 1 >= scene.frame_count() && scene.frame_count() > 1)
    throw InputError("scene " + scene.name + " has " + std::to_string(scene.frame_count()) +
                     " frames; a step from frame " + std::to_string(frame) + " needs the next one");
  Step step;
  step.scene = &scene;
  const std::size_t next = scene.frame_count() > 1 ? frame + 1 : frame;
  // Frame by frame, not object by object: the objects of a split mesh share their frame
  // files, which the scene reads one at a time (the 300 bodies of the generated n-body
  // scene took 600 reads, 22 s, a step).
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) step.x0.push_back(scene.positions(o, frame));
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
    step.x1.push_back(scene.objects[o].kind == ObjectKind::static_ ? step.x0[o] : scene.positions(o, next));
  return step;
}

std::size_t Candidates::vf_count() const
{
  std::size_t n = 0;
  for (const auto& b : blocks) n += b.vf.size();
  return n;
}

std::size_t Candidates::ee_count() const
{
  std::size_t n = 0;
  for (const auto& b : blocks) n += b.ee.size();
  return n;
}

bool operator==(const Candidates& a, const Candidates& b)
{
  if (a.blocks.size() != b.blocks.size()) return false;
  for (std::size_t i = 0; i < a.blocks.size(); ++i) {
    const auto &x = a.blocks[i], &y = b.blocks[i];
    if (x.object_a != y.object_a || x.object_b != y.object_b || x.vf != y.vf || x.ee != y.ee) return false;
  }
  return true;
}

namespace {

using FacePairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

// Face pairs of overlapping BVs, by traversing the BVTT of two trees (or one, for
// self): tree layouts from `a` and `b`, node boxes from `boxes_a` and `boxes_b`.
template <class Box>
FacePairs traverse(const Bvh& a, const std::vector<Box>& boxes_a, const Bvh& b, const std::vector<Box>& boxes_b,
                   bool self)
{
  FacePairs out;
  if (a.nodes.empty() || b.nodes.empty()) return out;
  std::vector<std::pair<std::int32_t, std::int32_t>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    const BvhNode &ni = a.nodes[std::size_t(i)], &nj = b.nodes[std::size_t(j)];
    if (self && i == j) {
      if (ni.left < 0) continue;
      stack.push_back({ni.left, ni.left});
      stack.push_back({ni.left + 1, ni.left + 1});
      stack.push_back({ni.left, ni.left + 1});
      continue;
    }
    if (!boxes_a[std::size_t(i)].overlaps(boxes_b[std::size_t(j)])) continue;
    if (ni.left < 0 && nj.left < 0) {
      out.emplace_back(std::uint32_t(ni.face), std::uint32_t(nj.face));
    } else if (nj.left < 0 || (ni.left >= 0 && i <= j)) {
      stack.push_back({ni.left, j});
      stack.push_back({ni.left + 1, j});
    } else {
      stack.push_back({i, nj.left});
      stack.push_back({i, nj.left + 1});
    }
  }
  return out;
}

template <class Box> FacePairs brute_force(const std::vector<Box>& a, const std::vector<Box>& b, bool self)
{
  FacePairs out;
  for (std::uint32_t i = 0; i < a.size(); ++i)
    for (std::uint32_t j = self ? i + 1 : 0; j < b.size(); ++j)
      if (a[i].overlaps(b[j])) out.emplace_back(i, j);
  return out;
}

// The bounds of one object in either precision, the tree's node boxes included.
template <class Box> struct Bounds {
  std::vector<Box> faces, edges, vertices, nodes;
};

template <class T> void sort_unique(std::vector<T>& v)
{
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace

namespace {

// The decomposition's cull of the device (broad_phase.cl, cs_ends_apart) in the same
// arithmetic, for the feature pairs of faces fa and fb: their six points at both ends of
// the step (fa's, then fb's) and the margin.
template <class Real> class EndsCull {
public:
  EndsCull(const Face& fa, const std::vector<Vec3>& a0, const std::vector<Vec3>& a1, const Face& fb,
           const std::vector<Vec3>& b0, const std::vector<Vec3>& b1, Real separation, Real tolerance)
  {
    Real scale = 0;
    for (int j = 0; j < 6; ++j) {
      const std::uint32_t v = j < 3 ? fa[j] : fb[j - 3];
      const Vec3 &x = j < 3 ? a0[v] : b0[v], &y = j < 3 ? a1[v] : b1[v];
      for (int k = 0; k < 3; ++k) {
        p0_[j][k] = Real(x[k]);
        p1_[j][k] = Real(y[k]);
        scale = std::max(scale, std::max(std::abs(p0_[j][k]), std::abs(p1_[j][k])));
      }
    }
    // Exact positions need room only for the double gaps' rounding; staying under the
    // device's 2^-16 keeps every pair the double boxes keep among the float boxes' pairs.
    const Real rounding = std::is_same<Real, float>::value ? Real(0x1p-16) : Real(0x1p-17);
    margin_ = separation + (3 * tolerance + rounding) * scale;
  }

  // Whether points (a0, a1, a2) and (b0, b1, b2) stay more than the margin apart.
  bool apart(int a0, int a1, int a2, int b0, int b1, int b2) const
  {
    for (int k = 0; k < 3; ++k) {
      const auto lo = [k](const Real (&p)[6][3], int i, int j, int l) { return std::min(std::min(p[i][k], p[j][k]), p[l][k]); };
      const auto hi = [k](const Real (&p)[6][3], int i, int j, int l) { return std::max(std::max(p[i][k], p[j][k]), p[l][k]); };
      if ((lo(p0_, b0, b1, b2) - hi(p0_, a0, a1, a2) > margin_ && lo(p1_, b0, b1, b2) - hi(p1_, a0, a1, a2) > margin_) ||
          (lo(p0_, a0, a1, a2) - hi(p0_, b0, b1, b2) > margin_ && lo(p1_, a0, a1, a2) - hi(p1_, b0, b1, b2) > margin_))
        return true;
    }
    return false;
  }

private:
  Real p0_[6][3], p1_[6][3];
  Real margin_;
};

int local_index(const std::array<std::uint32_t, 3>& ids, std::uint32_t id)
{
  return ids[0] == id ? 0 : ids[1] == id ? 1 : 2;
}

// The feature pairs of faces fa (object a) and fb (object b), less those whose features
// stay apart through the step. Face edge k joins the face's vertices k and k + 1.
template <class Real>
void decompose_and_cull(const Step& step, std::uint32_t a, std::uint32_t fa, std::uint32_t b, std::uint32_t fb,
                        Real separation, Real tolerance, std::vector<VertexFace>& vf_ab,
                        std::vector<VertexFace>& vf_ba, std::vector<EdgeEdge>& ee)
{
  const Topology &ta = step.scene->objects[a].topology, &tb = step.scene->objects[b].topology;
  std::vector<VertexFace> ab, ba;
  std::vector<EdgeEdge> edges;
  decompose(ta, fa, tb, fb, ab, ba, edges);
  const EndsCull<Real> cull(ta.faces[fa], step.x0[a], step.x1[a], tb.faces[fb], step.x0[b], step.x1[b], separation,
                            tolerance);
  for (const auto& p : ab) {
    const int k = local_index(ta.faces[fa], p.vertex);
    if (!cull.apart(k, k, k, 3, 4, 5)) vf_ab.push_back(p);
  }
  for (const auto& p : ba) {
    const int k = 3 + local_index(tb.faces[fb], p.vertex);
    if (!cull.apart(k, k, k, 0, 1, 2)) vf_ba.push_back(p);
  }
  for (const auto& p : edges) {
    const int i = local_index(ta.face_edges[fa], p.a), j = local_index(tb.face_edges[fb], p.b);
    if (!cull.apart(i, (i + 1) % 3, i, 3 + j, 3 + (j + 1) % 3, 3 + j)) ee.push_back(p);
  }
}

template <class Real, class Box>
Candidates candidates(const Step& step, const std::vector<Bounds<Box>>& bounds, const std::vector<Bvh>& trees,
                      BroadPhase broad_phase, Real separation, Real tolerance)
{
  const Scene& scene = *step.scene;
  const std::uint32_t n = std::uint32_t(scene.objects.size());
  Candidates out;
  for (std::uint32_t a = 0; a < n; ++a)
    for (std::uint32_t b = a; b < n; ++b) {
      if (!scene.may_collide(a, b)) continue;
      const bool self = a == b;
      const Topology& ta = scene.objects[a].topology;
      const Bounds<Box>&bounds_a = bounds[a], &bounds_b = bounds[b];
      const FacePairs pairs = broad_phase == BroadPhase::bvh
                                  ? traverse(trees[a], bounds_a.nodes, trees[b], bounds_b.nodes, self)
                                  : brute_force(bounds_a.faces, bounds_b.faces, self);
      CandidateBlock ab{a, b, {}, {}}, ba{b, a, {}, {}};
      for (const auto& [fa, fb] : pairs) {
        if (self && ta.adjacent(fa, fb)) continue;
        decompose_and_cull(step, a, fa, b, fb, separation, tolerance, ab.vf, ba.vf, ab.ee);
      }
      if (self) {
        ab.vf.insert(ab.vf.end(), ba.vf.begin(), ba.vf.end());
        ba.vf.clear();
        for (auto& e : ab.ee)
          if (e.a > e.b) std::swap(e.a, e.b);
        // Orphans are culled by their swept boxes (orphans.cl).
        const OrphanSet orphans = build_orphans(ta);
        for (const auto& p : orphans.vf)
          if (bounds_a.vertices[p.vertex].overlaps(bounds_a.faces[p.face])) ab.vf.push_back(p);
        for (const auto& p : orphans.ee)
          if (bounds_a.edges[p.a].overlaps(bounds_a.edges[p.b])) ab.ee.push_back(p);
      }
      sort_unique(ab.vf);
      sort_unique(ab.ee);
      sort_unique(ba.vf);
      out.blocks.push_back(std::move(ab));
      if (!self) out.blocks.push_back(std::move(ba));
    }
  std::sort(out.blocks.begin(), out.blocks.end(), [](const CandidateBlock& x, const CandidateBlock& y) {
    return x.object_a != y.object_a ? x.object_a < y.object_a : x.object_b < y.object_b;
  });
  return out;
}

}  // namespace

Candidates reference_broad_phase(const Step& step, const ReferenceOptions& options)
{
  const Scene& scene = *step.scene;
  const std::size_t n = scene.objects.size();
  const double separation = options.solver.min_separation;
  // Trees are always built from the exact boxes, so both precisions share their layout.
  std::vector<SweptBounds> exact(n);
  std::vector<Bvh> trees(n);
  for (std::size_t o = 0; o < n; ++o) {
    exact[o] = swept_bounds(scene.objects[o].topology, step.x0[o], step.x1[o], separation);
    trees[o] = build_bvh(exact[o].faces);
  }
  if (options.bounds == BoundsPrecision::double_) {
    std::vector<Bounds<Kdop18>> bounds(n);
    for (std::size_t o = 0; o < n; ++o)
      bounds[o] = {std::move(exact[o].faces), std::move(exact[o].edges), std::move(exact[o].vertices), trees[o].boxes};
    return candidates(step, bounds, trees, options.broad_phase, separation, options.tolerance);
  }
  // The float separation is rounded up, so the float boxes stay conservative.
  const float float_separation = float_above(separation);
  std::vector<Bounds<Kdop18f>> bounds(n);
  for (std::size_t o = 0; o < n; ++o) {
    FloatBounds f = float_bounds(scene.objects[o].topology, trees[o], step.x0[o], step.x1[o], float_separation);
    bounds[o] = {std::move(f.faces), std::move(f.edges), std::move(f.vertices), std::move(f.nodes)};
  }
  return candidates(step, bounds, trees, options.broad_phase, float_separation, float_above(options.tolerance));
}

Query vertex_face_query(const Step& step, std::uint32_t oa, std::uint32_t ob, VertexFace p)
{
  const Face& f = step.scene->objects[ob].topology.faces[p.face];
  const auto &a0 = step.x0[oa], &a1 = step.x1[oa], &b0 = step.x0[ob], &b1 = step.x1[ob];
  return {a0[p.vertex], b0[f[0]], b0[f[1]], b0[f[2]], a1[p.vertex], b1[f[0]], b1[f[1]], b1[f[2]]};
}

Query edge_edge_query(const Step& step, std::uint32_t oa, std::uint32_t ob, EdgeEdge p)
{
  const Edge& ea = step.scene->objects[oa].topology.edges[p.a];
  const Edge& eb = step.scene->objects[ob].topology.edges[p.b];
  const auto &a0 = step.x0[oa], &a1 = step.x1[oa], &b0 = step.x0[ob], &b1 = step.x1[ob];
  return {a0[ea[0]], a0[ea[1]], b0[eb[0]], b0[eb[1]], a1[ea[0]], a1[ea[1]], b1[eb[0]], b1[eb[1]]};
}

Contact make_contact(const Step& step, std::uint32_t oa, std::uint32_t ob, VertexFace p, double toi)
{
  const Face& f = step.scene->objects[ob].topology.faces[p.face];
  return {ContactKind::vertex_face, oa, ob, {p.vertex, f[0], f[1], f[2]}, toi};
}

Contact make_contact(const Step& step, std::uint32_t oa, std::uint32_t ob, EdgeEdge p, double toi)
{
  Edge ea = step.scene->objects[oa].topology.edges[p.a];
  Edge eb = step.scene->objects[ob].topology.edges[p.b];
  if (oa == ob && eb < ea) std::swap(ea, eb);
  return {ContactKind::edge_edge, oa, ob, {ea[0], ea[1], eb[0], eb[1]}, toi};
}

std::vector<Contact> reference_narrow_phase(const Step& step, const Candidates& candidates,
                                            const ReferenceSolverOptions& options)
{
  std::vector<Contact> contacts;
  std::mutex merge;
  for (const auto& block : candidates.blocks) {
    const std::size_t nvf = block.vf.size(), total = nvf + block.ee.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 64), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Contact> found;
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        if (i < nvf) {
          const auto& p = block.vf[i];
          const CcdResult res = vertex_face_reference(vertex_face_query(step, block.object_a, block.object_b, p), options);
          if (res.collides) found.push_back(make_contact(step, block.object_a, block.object_b, p, res.toi));
        } else {
          const auto& p = block.ee[i - nvf];
          const CcdResult res = edge_edge_reference(edge_edge_query(step, block.object_a, block.object_b, p), options);
          if (res.collides) found.push_back(make_contact(step, block.object_a, block.object_b, p, res.toi));
        }
      }
      std::lock_guard<std::mutex> lock(merge);
      contacts.insert(contacts.end(), found.begin(), found.end());
    });
  }
  sort_canonical(contacts);
  return contacts;
}

std::vector<Contact> reference_ccd(const Step& step, const ReferenceOptions& options)
{
  return reference_narrow_phase(step, reference_broad_phase(step, options), options.solver);
}

}  // namespace cstreams
