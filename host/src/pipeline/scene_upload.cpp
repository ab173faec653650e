#include "scene_upload.hpp"

#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>

#include <array>
#include <string>

namespace cstreams {

namespace {

// The nodes as the kernels read them, in half the bytes (bounds.h): the first child or
// -1 - face, then parent + 1 above the depth's bits.
std::vector<std::array<std::int32_t, 2>> device_nodes(const SceneLayout& layout)
{
  std::vector<std::array<std::int32_t, 2>> packed(layout.nodes.size());
  for (std::size_t n = 0; n < packed.size(); ++n) {
    const auto& [child, face, parent, depth] = layout.nodes[n];
    packed[n] = {child >= 0 ? child : -1 - face,
                 std::int32_t((std::uint32_t(parent + 1) << node_depth_bits) | std::uint32_t(depth))};
  }
  return packed;
}

// Writes one object's positions to a float stream and, in double precision, its exact twin.
void write_positions(runtime::Scheduler& scheduler, const SceneLayout& layout, runtime::StreamId single,
                     runtime::StreamId exact, std::uint32_t o, const FloatPositions& rounded,
                     const std::vector<Vec3>& x)
{
  const std::uint32_t first = layout.slots[layout.slot_of[o]].first_vertex;
  scheduler.write(single, first, rounded.rounded.data(), x.size());
  if (has(exact)) scheduler.write(exact, first, x.data(), x.size());
}

}  // namespace

void check_moving_object(const SceneDescription& scene, std::uint32_t o, PositionSpan x)
{
  if (o >= scene.objects.size())
    throw InputError("no object " + std::to_string(o) + " in a scene of " + std::to_string(scene.objects.size()));
  const ObjectDescription& d = scene.objects[o];
  if (d.kind == ObjectKind::static_) throw InputError("object '" + d.name + "' is static and cannot move");
  if (x.size() != d.positions.size())
    throw InputError("object '" + d.name + "' has " + std::to_string(d.positions.size()) + " vertices, not " +
                     std::to_string(x.size()));
}

void check_positions(const SceneDescription& scene, std::uint32_t o, PositionSpan x)
{
  check_moving_object(scene, o, x);
  try {
    check_float_positions(x);
  } catch (const InputError& e) {
    throw InputError("object '" + scene.objects[o].name + "': " + e.what());
  }
}

std::vector<bool> upload_scene(runtime::Scheduler& q, const CcdGraph& g, const SceneLayout& layout,
                               const SceneDescription& scene, double min_separation)
{
  const CcdStreams& s = g.streams;
  std::vector<bool> exact(scene.objects.size());
  const Topology& t = layout.topology;
  q.write(s.faces, 0, t.faces.data(), t.faces.size());
  q.write(s.edges, 0, t.edges.data(), t.edges.size());
  q.write(s.nodes, 0, device_nodes(layout).data(), layout.nodes.size());
  std::vector<std::uint32_t> face_words(t.owned.begin(), t.owned.end());
  for (std::size_t n = 0; n < layout.nodes.size(); ++n)
    if (const std::int32_t face = layout.nodes[n][1]; face >= 0)
      face_words[std::size_t(face)] |= std::uint32_t(n) << face_leaf_shift;
  q.write(s.face_words, 0, face_words.data(), face_words.size());
  if (has(s.refit_ranges)) q.write(s.refit_ranges, 0, g.refit_ranges.data(), g.refit_ranges.size());
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
    const ObjectDescription& object = scene.objects[o];
    const std::vector<Vec3>& x = object.positions;
    // make_layout checked them.
    const FloatPositions f = rounded_positions(x);
    exact[o] = f.exact;
    write_positions(q, layout, s.x0, s.x0_double, o, f, x);
    write_positions(q, layout, s.x1, s.x1_double, o, f, x);
    const ObjectSlot& sl = layout.slots[layout.slot_of[o]];
    if (sl.moving) continue;
    // Static bounds never change: the host's float twin computes them once.
    const FloatBounds b = float_bounds(build_topology(object.faces, x.size()), layout.trees[o], x, x,
                                       float_above(min_separation));
    q.write(s.edge_boxes, sl.first_edge, b.edges.data(), b.edges.size());
    q.write(s.node_boxes, sl.first_node, b.nodes.data(), b.nodes.size());
  }
  if (!has(s.front)) return exact;
  q.write(s.face_edges, 0, t.face_edges.data(), t.face_edges.size());
  if (has(s.orphan_vf)) q.write(s.orphan_vf, 0, layout.orphans.vf.data(), layout.orphans.vf.size());
  if (has(s.orphan_ee)) q.write(s.orphan_ee, 0, layout.orphans.ee.data(), layout.orphans.ee.size());
  // The tests' and the contacts' (a proximity query has neither).
  if (has(s.vertex_object)) q.write(s.vertex_object, 0, layout.vertex_object.data(), layout.vertex_object.size());
  return exact;
}

}  // namespace cstreams
