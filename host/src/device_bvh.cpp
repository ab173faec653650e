#include <cstreams/device_bvh.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/narrow_phase.hpp>
#include <cstreams/runtime/context.hpp>

#include <cfloat>
#include <cmath>
#include <limits>

namespace cstreams {

namespace {

// Must match cl_kernels/ccd/bounds.h operation for operation.
float fdown(float x) { return x - (std::fabs(x) * 0x1p-23f + FLT_MIN); }
float fup(float x) { return x + (std::fabs(x) * 0x1p-23f + FLT_MIN); }

Kdop18f empty_dop()
{
  Kdop18f d;
  d.lo.fill(std::numeric_limits<float>::infinity());
  d.hi.fill(-std::numeric_limits<float>::infinity());
  return d;
}

void add(Kdop18f& d, float x, float y, float z)
{
  const float xl = fdown(x), xh = fup(x), yl = fdown(y), yh = fup(y), zl = fdown(z), zh = fup(z);
  const float l[9] = {xl, yl, zl, fdown(xl + yl), fdown(xl - yh), fdown(yl + zl), fdown(yl - zh), fdown(zl + xl),
                      fdown(zl - xh)};
  const float h[9] = {xh, yh, zh, fup(xh + yh), fup(xh - yl), fup(yh + zh), fup(yh - zl), fup(zh + xh), fup(zh - xl)};
  for (int k = 0; k < 9; ++k) {
    d.lo[std::size_t(k)] = std::fmin(d.lo[std::size_t(k)], l[k]);
    d.hi[std::size_t(k)] = std::fmax(d.hi[std::size_t(k)], h[k]);
  }
}

void inflate(Kdop18f& d, float separation)
{
  if (separation <= 0) return;
  const float diagonal = fup(separation * 1.41421366f);
  for (std::size_t k = 0; k < 9; ++k) {
    const float grow = k < 3 ? separation : diagonal;
    d.lo[k] = fdown(d.lo[k] - grow);
    d.hi[k] = fup(d.hi[k] + grow);
  }
}

}  // namespace

std::vector<float> to_float_positions(const std::vector<Vec3>& x)
{
  std::vector<float> out(3 * x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(x[i][k]) || std::fabs(x[i][k]) > double(FLT_MAX))
        throw InputError("vertex " + std::to_string(i) + " has a coordinate that is not a finite float");
      out[3 * i + std::size_t(k)] = static_cast<float>(x[i][k]);
    }
  return out;
}

namespace {

Kdop18f swept(const std::vector<float>& x0, const std::vector<float>& x1, const std::uint32_t* v, int count,
              float separation)
{
  Kdop18f d = empty_dop();
  for (int i = 0; i < count; ++i) {
    add(d, x0[3 * v[i]], x0[3 * v[i] + 1], x0[3 * v[i] + 2]);
    add(d, x1[3 * v[i]], x1[3 * v[i] + 1], x1[3 * v[i] + 2]);
  }
  inflate(d, separation);
  return d;
}

}  // namespace

std::vector<Kdop18f> unpack_dops(const std::vector<float>& flat)
{
  std::vector<Kdop18f> out(flat.size() / 18);
  for (std::size_t i = 0; i < out.size(); ++i)
    for (std::size_t k = 0; k < 9; ++k) {
      out[i].lo[k] = flat[18 * i + k];
      out[i].hi[k] = flat[18 * i + 9 + k];
    }
  return out;
}

bool Kdop18f::contains(const Kdop18& exact) const
{
  for (std::size_t k = 0; k < 9; ++k)
    if (double(lo[k]) > exact.lo[k] || double(hi[k]) < exact.hi[k]) return false;
  return true;
}

bool Kdop18f::overlaps(const Kdop18f& o) const
{
  for (std::size_t k = 0; k < 9; ++k)
    if (lo[k] > o.hi[k] || o.lo[k] > hi[k]) return false;
  return true;
}

FloatBounds float_bounds(const Topology& t, const Bvh& bvh, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1,
                         float separation)
{
  const auto f0 = to_float_positions(x0), f1 = to_float_positions(x1);
  FloatBounds b;
  for (const Face& f : t.faces) b.faces.push_back(swept(f0, f1, f.data(), 3, separation));
  for (const Edge& e : t.edges) b.edges.push_back(swept(f0, f1, e.data(), 2, separation));
  for (std::uint32_t v = 0; v < t.vertex_count; ++v) b.vertices.push_back(swept(f0, f1, &v, 1, separation));
  b.nodes.resize(bvh.nodes.size());
  for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
    const BvhNode& n = bvh.nodes[i];
    if (n.left < 0) {
      b.nodes[i] = b.faces[std::size_t(n.face)];
      continue;
    }
    const Kdop18f &l = b.nodes[std::size_t(n.left)], &r = b.nodes[std::size_t(n.left) + 1];
    for (std::size_t k = 0; k < 9; ++k) {
      b.nodes[i].lo[k] = std::fmin(l.lo[k], r.lo[k]);
      b.nodes[i].hi[k] = std::fmax(l.hi[k], r.hi[k]);
    }
  }
  return b;
}

BoundsStreams add_bounds_passes(runtime::StreamGraph& g, const Topology& t, const Bvh& bvh, float separation)
{
  using namespace runtime;
  if (separation < 0) throw InputError("minimum separation must not be negative");
  const char* program = "ccd/bounds.cl";
  BoundsStreams s;
  s.x0 = g.fixed("x0", 12, t.vertex_count);
  s.x1 = g.fixed("x1", 12, t.vertex_count);
  s.faces = g.fixed("faces", 12, t.faces.size());
  s.edges = g.fixed("edges", 8, t.edges.size());
  s.nodes = g.fixed("bvh nodes", 12, bvh.nodes.size());
  s.face_boxes = g.fixed("face bounds", 72, t.faces.size());
  s.edge_boxes = g.fixed("edge bounds", 72, t.edges.size());
  s.vertex_boxes = g.fixed("vertex bounds", 72, t.vertex_count);
  s.node_boxes = g.fixed("bvh bounds", 72, bvh.nodes.size());
  auto bounds = [&](const char* name, StreamId primitives, cl_uint corners, std::size_t n, StreamId out) {
    g.pass(name, {program, "cs_primitive_bounds"})
        .launch_items(n)
        .write(out)
        .arg(buffer_of(s.x0))
        .arg(buffer_of(s.x1))
        .arg(buffer_of(primitives))
        .arg(value_of(corners))
        .arg(value_of(cl_uint(n)))
        .arg(value_of(separation))
        .arg(buffer_of(out));
  };
  bounds("face bounds", s.faces, 3, t.faces.size(), s.face_boxes);
  bounds("edge bounds", s.edges, 2, t.edges.size(), s.edge_boxes);
  // A vertex is its own primitive: the kernel does not read the primitive buffer then.
  bounds("vertex bounds", s.faces, 1, t.vertex_count, s.vertex_boxes);
  // Deepest level first; each level reads the one below, written by the previous pass.
  for (std::size_t level = bvh.depth(); level-- > 0;) {
    const cl_uint first = bvh.level_offsets[level], count = bvh.level_offsets[level + 1] - first;
    g.pass("refit level " + std::to_string(level), {program, "cs_refit_level"})
        .launch_items(count)
        .update(s.node_boxes)
        .read(s.face_boxes)
        .arg(buffer_of(s.nodes))
        .arg(buffer_of(s.face_boxes))
        .arg(value_of(first))
        .arg(value_of(count))
        .arg(buffer_of(s.node_boxes));
  }
  return s;
}

void upload_topology(runtime::Scheduler& scheduler, const BoundsStreams& s, const Topology& t, const Bvh& bvh)
{
  scheduler.upload(s.faces, t.faces);
  scheduler.upload(s.edges, t.edges);
  std::vector<std::int32_t> nodes;
  for (const BvhNode& n : bvh.nodes) nodes.insert(nodes.end(), {n.left, n.face, n.parent});
  scheduler.upload(s.nodes, nodes.data(), bvh.nodes.size());
}

DeviceBvh::DeviceBvh(runtime::Context& context, const Topology& t, const Bvh& bvh, float separation)
    : vertex_count_(t.vertex_count)
{
  using namespace runtime;
  context.programs().add_sources(ccd_kernel_sources());
  StreamGraph g;
  streams_ = add_bounds_passes(g, t, bvh, separation);
  scheduler_ = std::make_unique<Scheduler>(context, std::move(g), SchedulerOptions{Registration::segmented_lock, true});
  upload_topology(*scheduler_, streams_, t, bvh);
}

DeviceBvh::~DeviceBvh() = default;

void upload_positions(runtime::Scheduler& scheduler, const BoundsStreams& s, const std::vector<Vec3>& x0,
                      const std::vector<Vec3>& x1, std::size_t vertex_count)
{
  if (x0.size() != vertex_count || x1.size() != vertex_count)
    throw InputError("positions for " + std::to_string(x0.size()) + " and " + std::to_string(x1.size()) +
                     " vertices given to a mesh of " + std::to_string(vertex_count));
  const auto f0 = to_float_positions(x0), f1 = to_float_positions(x1);
  scheduler.upload(s.x0, f0.data(), vertex_count);
  scheduler.upload(s.x1, f1.data(), vertex_count);
}

void DeviceBvh::refit(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1)
{
  upload_positions(*scheduler_, streams_, x0, x1, vertex_count_);
  scheduler_->run();
}

FloatBounds DeviceBvh::download() const
{
  const BoundsStreams& s = streams_;
  auto get = [&](runtime::StreamId id) {
    std::vector<float> flat(scheduler_->count(id) * 18);
    scheduler_->download(id, flat.data(), scheduler_->count(id));
    return unpack_dops(flat);
  };
  return {get(s.face_boxes), get(s.edge_boxes), get(s.vertex_boxes), get(s.node_boxes)};
}

const runtime::RunStats& DeviceBvh::stats() const { return scheduler_->stats(); }

}  // namespace cstreams
