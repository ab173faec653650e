#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/errors.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/parallel_for.h>

namespace cstreams {

namespace {

// Depth-first BVTT search holds at most 2 * depth + 1 pairs (see broad_phase.cl);
// CS_BVTT_STACK = 128 covers trees of up to 40 levels, about 2^39 faces.
constexpr std::size_t max_tree_depth = 40;
static_assert(max_tree_depth < (std::size_t(1) << node_depth_bits) &&
                  max_scene_nodes <= (std::size_t(1) << (32 - node_depth_bits)),
              "a device node's word holds every depth and parent + 1");

void check_object(const ObjectDescription& o)
{
  const std::string what = "object '" + o.name + "': ";
  if (o.faces.empty() && o.segments.empty() && o.points.empty()) throw InputError(what + "has no faces");
  const std::size_t n = o.positions.size();
  const auto check_vertex = [&](std::uint32_t v, const char* kind, std::size_t i) {
    if (v >= n)
      throw InputError(what + kind + " " + std::to_string(i) + " uses vertex " + std::to_string(v) + " of " +
                       std::to_string(n));
  };
  for (std::size_t f = 0; f < o.faces.size(); ++f) {
    const Face& face = o.faces[f];
    for (std::uint32_t v : face) check_vertex(v, "face", f);
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2])
      throw InputError(what + "face " + std::to_string(f) + " repeats a vertex");
  }
  for (std::size_t e = 0; e < o.segments.size(); ++e) {
    for (std::uint32_t v : o.segments[e]) check_vertex(v, "segment", e);
    if (o.segments[e][0] == o.segments[e][1]) throw InputError(what + "segment " + std::to_string(e) + " repeats a vertex");
  }
  for (std::size_t p = 0; p < o.points.size(); ++p) check_vertex(o.points[p], "point", p);
  try {
    to_float_positions(o.positions);
  } catch (const InputError& e) {
    throw InputError(what + e.what());
  }
}

std::vector<std::uint32_t> node_depths(const Bvh& bvh)
{
  std::vector<std::uint32_t> depth(bvh.nodes.size());
  for (std::size_t d = 0; d < bvh.depth(); ++d)
    for (std::uint32_t i = bvh.level_offsets[d]; i < bvh.level_offsets[d + 1]; ++i) depth[i] = std::uint32_t(d);
  return depth;
}

// Every object valid, names unique, ignored pairs naming objects that exist.
void check_scene(const SceneDescription& scene)
{
  const auto n = std::uint32_t(scene.objects.size());
  for (std::uint32_t o = 0; o < n; ++o) {
    check_object(scene.objects[o]);
    for (std::uint32_t p = 0; p < o; ++p)
      if (scene.objects[p].name == scene.objects[o].name)
        throw InputError("two objects are named '" + scene.objects[o].name + "'");
  }
  for (const auto& [a, b] : scene.ignored_pairs)
    if (a >= n || b >= n) throw InputError("an ignored pair names object " + std::to_string(std::max(a, b)) + " of " + std::to_string(n));
}

// Each object's topology, and its tree over its starting positions, within what the
// device's node words and the traversal's stack can hold.
std::vector<Topology> build_trees(const SceneDescription& scene, double separation, SceneLayout& l)
{
  const std::size_t n = scene.objects.size();
  std::vector<Topology> topologies(n);
  l.trees.resize(n);
  for (std::size_t o = 0; o < n; ++o) {
    const ObjectDescription& d = scene.objects[o];
    topologies[o] = build_topology(collision_faces(d), d.positions.size());
    l.trees[o] = build_bvh(swept_bounds(topologies[o], d.positions, d.positions, separation).faces);
    if (l.trees[o].depth() > max_tree_depth)
      throw InputError("object '" + d.name + "': its BVH has " + std::to_string(l.trees[o].depth()) +
                       " levels, more than the traversal's stack allows (" + std::to_string(max_tree_depth) + ")");
    l.depth = std::max(l.depth, l.trees[o].depth());
  }
  std::size_t nodes = 0;
  for (const Bvh& t : l.trees) nodes += t.nodes.size();
  if (nodes >= max_scene_nodes)
    throw InputError("the scene's BVHs have " + std::to_string(nodes) + " nodes, more than the " +
                     std::to_string(max_scene_nodes - 1) + " a face's word on the device can name");
  return topologies;
}

// Slots: moving objects, then static ones, each at the end of the one before.
void place_slots(const SceneDescription& scene, const std::vector<Topology>& topologies, SceneLayout& l)
{
  const auto n = std::uint32_t(scene.objects.size());
  for (int pass = 0; pass < 2; ++pass)
    for (std::uint32_t o = 0; o < n; ++o) {
      const ObjectDescription& d = scene.objects[o];
      const bool moving = d.kind != ObjectKind::static_;
      if (moving != (pass == 0)) continue;
      ObjectSlot s;
      s.object = o;
      s.moving = moving;
      s.self = scene.may_collide(o, o);
      if (!l.slots.empty()) {
        const ObjectSlot& p = l.slots.back();
        const Topology& pt = topologies[p.object];
        s.first_vertex = p.first_vertex + std::uint32_t(pt.vertex_count);
        s.first_face = p.first_face + std::uint32_t(pt.faces.size());
        s.first_edge = p.first_edge + std::uint32_t(pt.edges.size());
      }
      l.slots.push_back(s);
    }
  l.slot_of.resize(n);
  for (std::uint32_t i = 0; i < l.slots.size(); ++i) l.slot_of[l.slots[i].object] = i;
}

// The forest: moving trees interleaved level by level, then static trees whole.
void lay_out_forest(SceneLayout& l)
{
  std::vector<std::vector<std::int32_t>> global(l.trees.size());
  std::int32_t next = 0;
  for (std::size_t d = 0;; ++d) {
    bool any = false;
    l.levels.push_back(std::uint32_t(next));
    for (const ObjectSlot& s : l.slots) {
      const Bvh& t = l.trees[s.object];
      if (!s.moving || d >= t.depth()) continue;
      global[s.object].resize(t.nodes.size());
      for (std::uint32_t i = t.level_offsets[d]; i < t.level_offsets[d + 1]; ++i) global[s.object][i] = next++;
      any = true;
    }
    if (!any) {
      l.levels.pop_back();
      break;
    }
  }
  if (l.levels.size() > 0) l.levels.push_back(std::uint32_t(next));
  l.moving_nodes = std::size_t(next);
  for (ObjectSlot& s : l.slots) {
    const Bvh& t = l.trees[s.object];
    if (!s.moving) {
      s.first_node = std::uint32_t(next);
      global[s.object].resize(t.nodes.size());
      for (std::size_t i = 0; i < t.nodes.size(); ++i) global[s.object][i] = next++;
    }
    s.root = global[s.object][0];
  }
  l.nodes.resize(std::size_t(next));
  l.node_object.resize(std::size_t(next));
  l.node_local.resize(std::size_t(next));
  for (const ObjectSlot& s : l.slots) {
    const Bvh& t = l.trees[s.object];
    const auto depth = node_depths(t);
    const auto& g = global[s.object];
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {
      const BvhNode& node = t.nodes[i];
      l.node_object[std::size_t(g[i])] = s.object;
      l.node_local[std::size_t(g[i])] = std::uint32_t(i);
      l.nodes[std::size_t(g[i])] = {node.left < 0 ? -1 : g[std::size_t(node.left)],
                                    node.face < 0 ? -1 : node.face + std::int32_t(s.first_face),
                                    node.parent < 0 ? -1 : g[std::size_t(node.parent)], std::int32_t(depth[i])};
    }
  }
}

// Global topology: concatenating the objects' meshes keeps each one's edge order and
// feature ownership, so the union's topology is theirs at offsets.
void join_topologies(const std::vector<Topology>& topologies, SceneLayout& l)
{
  std::vector<Face> faces;
  for (const ObjectSlot& s : l.slots) {
    const Topology& t = topologies[s.object];
    for (const Face& f : t.faces) faces.push_back({f[0] + s.first_vertex, f[1] + s.first_vertex, f[2] + s.first_vertex});
    l.vertex_object.insert(l.vertex_object.end(), t.vertex_count, s.object);
    if (s.moving) {
      l.moving_vertices += t.vertex_count;
      l.moving_faces += t.faces.size();
      l.moving_edges += t.edges.size();
    }
    if (s.self) {
      const OrphanSet orphans = build_orphans(t);
      for (const VertexFace& p : orphans.vf) l.orphans.vf.push_back({p.vertex + s.first_vertex, p.face + s.first_face});
      for (const EdgeEdge& p : orphans.ee) l.orphans.ee.push_back({p.a + s.first_edge, p.b + s.first_edge});
    }
  }
  l.topology = build_topology(faces, l.vertex_object.size());
}

}  // namespace

std::vector<Face> collision_faces(const ObjectDescription& object)
{
  std::vector<Face> faces = object.faces;
  for (const Edge& e : object.segments) faces.push_back({e[0], e[1], e[1]});
  for (const std::uint32_t p : object.points) faces.push_back({p, p, p});
  return faces;
}

SceneLayout make_layout(const SceneDescription& scene, double separation)
{
  check_scene(scene);
  SceneLayout l;
  const std::vector<Topology> topologies = build_trees(scene, separation, l);
  place_slots(scene, topologies, l);
  lay_out_forest(l);
  join_topologies(topologies, l);
  for (std::size_t i = 0; i < l.slots.size(); ++i)
    for (std::size_t j = i; j < l.slots.size(); ++j)
      if (scene.may_collide(l.slots[i].object, l.slots[j].object)) l.seeds.push_back({l.slots[i].root, l.slots[j].root});
  return l;
}

RefitPlan plan_refit(const SceneLayout& layout, std::size_t group)
{
  RefitPlan plan;
  if (layout.levels.size() < 2) return plan;
  std::size_t levels = 1;
  while ((std::size_t(1) << levels) <= group) ++levels;
  // The top band is one group's alone, which may take four nodes a work-item at its
  // deepest level: two levels more, and a launch fewer where they are all that is left
  // (n-body's level 0 took a launch of 4 us on the H100).
  const std::size_t top_levels = levels + 2;
  for (std::size_t end = layout.levels.size() - 1; end > 0;) {
    const std::size_t top = end > top_levels ? end - levels : 0;
    plan.bands.push_back({top, end - top, plan.ranges.size()});
    for (std::uint32_t n = layout.levels[top]; n < layout.levels[top + 1]; ++n) {
      std::array<std::uint32_t, 2> range{n, n + 1};
      for (std::size_t level = top; level < end; ++level) {
        plan.ranges.push_back(range);
        std::array<std::uint32_t, 2> below{0, 0};
        for (std::uint32_t m = range[0]; m < range[1]; ++m)
          if (const std::int32_t child = layout.nodes[m][0]; child >= 0) {
            if (below[0] == below[1]) below[0] = std::uint32_t(child);
            below[1] = std::uint32_t(child) + 2;
          }
        range = below;
      }
    }
    end = top;
  }
  return plan;
}

std::vector<NodePair> expand_front(const SceneLayout& layout, std::size_t target)
{
  return expand_front(layout, layout.seeds, target, std::numeric_limits<std::size_t>::max());
}

std::vector<NodePair> expand_front(const SceneLayout& layout, std::vector<NodePair> front, std::size_t target,
                                   std::size_t most)
{
  // The same choices as cs_front_update, without the bounds tests.
  const auto& nodes = layout.nodes;
  while (front.size() < target) {
    std::vector<NodePair> next;
    bool expanded = false;
    for (std::size_t k = 0; k < front.size(); ++k) {
      // A pair's children add at most two pairs; past `most`, the rest stay as they are.
      if (next.size() + (front.size() - k) + 2 > most) {
        next.insert(next.end(), front.begin() + std::ptrdiff_t(k), front.end());
        break;
      }
      const auto [i, j] = front[k];
      const auto &a = nodes[std::size_t(i)], &b = nodes[std::size_t(j)];
      if (i == j) {
        if (a[0] < 0) continue;  // a leaf against itself pairs nothing
        next.insert(next.end(), {{a[0], a[0] + 1}, {a[0], a[0]}, {a[0] + 1, a[0] + 1}});
      } else if (a[0] < 0 && b[0] < 0) {
        next.push_back({i, j});
        continue;
      } else if (a[0] >= 0 && (b[0] < 0 || a[3] <= b[3])) {
        next.insert(next.end(), {{a[0], j}, {a[0] + 1, j}});
      } else {
        next.insert(next.end(), {{i, b[0]}, {i, b[0] + 1}});
      }
      expanded = true;
    }
    front = std::move(next);
    if (!expanded) break;
  }
  return front;
}

namespace {

// The axis-aligned part of the nodes' boxes at the starting positions, in floats rounded
// outward, in the forest's order, where pairs near each other in a cut read them nearly
// in turn: read from the trees' 18-DOPs, which lie in each object's order, the tests
// missed the caches and took cloth-ball's expansion to 2.2 million pairs 0.36 s.
using StartBox = std::array<float, 6>;

std::vector<StartBox> start_boxes(const SceneLayout& layout)
{
  std::vector<StartBox> boxes(layout.nodes.size());
  for (std::size_t n = 0; n < boxes.size(); ++n) {
    const Kdop18& k = layout.start_box(std::int32_t(n));
    for (std::size_t a = 0; a < 3; ++a) {
      boxes[n][a] = std::nextafter(float(k.lo[a]), -HUGE_VALF);
      boxes[n][a + 3] = std::nextafter(float(k.hi[a]), HUGE_VALF);
    }
  }
  return boxes;
}

bool apart(const StartBox& a, const StartBox& b)
{
  return a[0] > b[3] || b[0] > a[3] || a[1] > b[4] || b[1] > a[4] || a[2] > b[5] || b[2] > a[5];
}

// The pairs below p down to `levels` levels, depth first, which is the breadth-first
// expansion's order; as there, pairs of leaves and pairs apart stay.
void refine_pair(const SceneLayout& layout, const std::vector<StartBox>& boxes, const NodePair& p, unsigned levels,
                 std::vector<NodePair>& out)
{
  const auto [i, j] = p;
  const auto &a = layout.nodes[std::size_t(i)], &b = layout.nodes[std::size_t(j)];
  if (i == j && a[0] < 0) return;  // a leaf against itself pairs nothing
  if (levels == 0 || (i != j && ((a[0] < 0 && b[0] < 0) || apart(boxes[std::size_t(i)], boxes[std::size_t(j)])))) {
    out.push_back(p);
    return;
  }
  if (i == j) {
    for (const NodePair& c : {NodePair{a[0], a[0] + 1}, NodePair{a[0], a[0]}, NodePair{a[0] + 1, a[0] + 1}})
      refine_pair(layout, boxes, c, levels - 1, out);
  } else if (a[0] >= 0 && (b[0] < 0 || a[3] <= b[3])) {
    refine_pair(layout, boxes, {a[0], j}, levels - 1, out);
    refine_pair(layout, boxes, {a[0] + 1, j}, levels - 1, out);
  } else {
    refine_pair(layout, boxes, {i, b[0]}, levels - 1, out);
    refine_pair(layout, boxes, {i, b[0] + 1}, levels - 1, out);
  }
}

}  // namespace

std::vector<NodePair> expand_overlapping(const SceneLayout& layout, const std::vector<NodePair>& front,
                                         unsigned levels)
{
  const std::vector<StartBox> boxes = start_boxes(layout);
  // Runs of the front refined on the host's threads, then joined in order.
  constexpr std::size_t run = 1024;
  std::vector<std::vector<NodePair>> parts((front.size() + run - 1) / run);
  tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t k) {
    for (std::size_t n = k * run; n < std::min(front.size(), (k + 1) * run); ++n)
      refine_pair(layout, boxes, front[n], levels, parts[k]);
  });
  std::size_t total = 0;
  for (const auto& part : parts) total += part.size();
  std::vector<NodePair> refined;
  refined.reserve(total);
  for (const auto& part : parts) refined.insert(refined.end(), part.begin(), part.end());
  return refined;
}

std::vector<NodePair> spread_over_groups(const std::vector<NodePair>& front, std::size_t group)
{
  // The input read as rows of `groups` pairs and written column by column: the pairs
  // of one work-group lie `groups` apart in the input, across all of it.
  const std::size_t groups = std::max<std::size_t>(1, (front.size() + group - 1) / std::max<std::size_t>(group, 1));
  std::vector<NodePair> spread;
  spread.reserve(front.size());
  for (std::size_t first = 0; first < groups; ++first)
    for (std::size_t k = first; k < front.size(); k += groups) spread.push_back(front[k]);
  return spread;
}

}  // namespace cstreams
