#include <cstreams/geometry/bvh.hpp>
#include <cstreams/geometry/topology.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace cstreams {

namespace {
constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double sqrt2_up = 1.4142135623730952;  // above sqrt(2)

double down(double x) { return std::nextafter(x, -inf); }
double up(double x) { return std::nextafter(x, inf); }
}  // namespace

void project(const Vec3& p, std::array<double, 9>& lo, std::array<double, 9>& hi)
{
  const double d[9] = {p.x(), p.y(), p.z(), p.x() + p.y(), p.x() - p.y(), p.y() + p.z(), p.y() - p.z(),
                       p.z() + p.x(), p.z() - p.x()};
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = d[k];
  // One rounded addition is within half an ulp of the exact sum: one step out covers it.
  for (int k = 3; k < 9; ++k) {
    lo[k] = down(d[k]);
    hi[k] = up(d[k]);
  }
}

Kdop18 Kdop18::empty()
{
  Kdop18 k;
  k.lo.fill(inf);
  k.hi.fill(-inf);
  return k;
}

void Kdop18::add(const Vec3& p)
{
  std::array<double, 9> l, h;
  project(p, l, h);
  for (int k = 0; k < 9; ++k) {
    lo[k] = std::min(lo[k], l[k]);
    hi[k] = std::max(hi[k], h[k]);
  }
}

void Kdop18::merge(const Kdop18& o)
{
  for (int k = 0; k < 9; ++k) {
    lo[k] = std::min(lo[k], o.lo[k]);
    hi[k] = std::max(hi[k], o.hi[k]);
  }
}

void Kdop18::inflate(double distance)
{
  if (distance <= 0) return;
  for (int k = 0; k < 9; ++k) {
    const double grow = k < 3 ? distance : up(distance * sqrt2_up);
    lo[k] = down(lo[k] - grow);
    hi[k] = up(hi[k] + grow);
  }
}

bool Kdop18::overlaps(const Kdop18& o) const
{
  for (int k = 0; k < 9; ++k)
    if (lo[k] > o.hi[k] || o.lo[k] > hi[k]) return false;
  return true;
}

Vec3 Kdop18::centre() const { return Vec3(lo[0] + hi[0], lo[1] + hi[1], lo[2] + hi[2]) * 0.5; }

Kdop18 swept_kdop(const Vec3* x0, const Vec3* x1, const std::uint32_t* vertices, int count, double separation)
{
  Kdop18 box = Kdop18::empty();
  for (int i = 0; i < count; ++i) {
    box.add(x0[vertices[i]]);
    box.add(x1[vertices[i]]);
  }
  box.inflate(separation);
  return box;
}

SweptBounds swept_bounds(const Topology& t, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, double separation)
{
  SweptBounds b;
  b.faces.resize(t.faces.size());
  b.edges.resize(t.edges.size());
  b.vertices.resize(t.vertex_count);
  for (std::size_t f = 0; f < t.faces.size(); ++f) b.faces[f] = swept_kdop(x0.data(), x1.data(), t.faces[f].data(), 3, separation);
  for (std::size_t e = 0; e < t.edges.size(); ++e) b.edges[e] = swept_kdop(x0.data(), x1.data(), t.edges[e].data(), 2, separation);
  for (std::uint32_t v = 0; v < t.vertex_count; ++v) b.vertices[v] = swept_kdop(x0.data(), x1.data(), &v, 1, separation);
  return b;
}

void Bvh::refit(const std::vector<Kdop18>& face_boxes)
{
  for (std::size_t i = nodes.size(); i-- > 0;) {
    const BvhNode& n = nodes[i];
    if (n.left < 0) {
      boxes[i] = face_boxes[std::size_t(n.face)];
    } else {
      boxes[i] = boxes[std::size_t(n.left)];
      boxes[i].merge(boxes[std::size_t(n.left) + 1]);
    }
  }
}

Bvh build_bvh(const std::vector<Kdop18>& face_boxes)
{
  Bvh bvh;
  if (face_boxes.empty()) return bvh;
  std::vector<std::uint32_t> order(face_boxes.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<Vec3> centres(face_boxes.size());
  for (std::size_t f = 0; f < face_boxes.size(); ++f) centres[f] = face_boxes[f].centre();

  struct Range {
    std::uint32_t begin, end;
  };
  std::vector<Range> ranges{{0, std::uint32_t(order.size())}};
  bvh.nodes.emplace_back();
  bvh.level_offsets = {0};
  // Breadth-first: ranges[i] belongs to nodes[i]; a level ends where the next began.
  std::size_t level_end = 1;
  for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
    if (i == level_end) {
      bvh.level_offsets.push_back(std::uint32_t(i));
      level_end = bvh.nodes.size();
    }
    const Range r = ranges[i];
    if (r.end - r.begin == 1) {
      bvh.nodes[i].face = std::int32_t(order[r.begin]);
      continue;
    }
    Vec3 lo = Vec3::Constant(inf), hi = Vec3::Constant(-inf);
    for (std::uint32_t j = r.begin; j < r.end; ++j) {
      lo = lo.cwiseMin(centres[order[j]]);
      hi = hi.cwiseMax(centres[order[j]]);
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const std::uint32_t mid = r.begin + (r.end - r.begin) / 2;
    std::nth_element(order.begin() + r.begin, order.begin() + mid, order.begin() + r.end,
                     [&](std::uint32_t a, std::uint32_t b) {
                       return centres[a][axis] != centres[b][axis] ? centres[a][axis] < centres[b][axis] : a < b;
                     });
    bvh.nodes[i].left = std::int32_t(bvh.nodes.size());
    for (const Range child : {Range{r.begin, mid}, Range{mid, r.end}}) {
      BvhNode node;
      node.parent = std::int32_t(i);
      bvh.nodes.push_back(node);
      ranges.push_back(child);
    }
  }
  bvh.level_offsets.push_back(std::uint32_t(bvh.nodes.size()));
  bvh.boxes.resize(bvh.nodes.size());
  bvh.refit(face_boxes);
  return bvh;
}

}  // namespace cstreams
