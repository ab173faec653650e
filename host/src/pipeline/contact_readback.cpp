#include "contact_readback.hpp"
#include "stream_args.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace cstreams {

namespace {

constexpr std::size_t record_words = 8;  // cs_contact_records

Contact from_record(const cl_uint* r, bool double_time)
{
  Contact c;
  c.kind = r[0] >> 31 ? ContactKind::edge_edge : ContactKind::vertex_face;
  c.object_a = r[0] & 0x7fffffffu;
  c.object_b = r[1];
  c.v = {r[2], r[3], r[4], r[5]};
  if (double_time) {
    const std::uint64_t bits = std::uint64_t(r[6]) << 32 | r[7];
    std::memcpy(&c.toi, &bits, sizeof bits);
  } else {
    float toi;
    std::memcpy(&toi, &r[6], sizeof toi);
    c.toi = toi;
  }
  return c;
}

}  // namespace

ContactReadback::ContactReadback(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                                 Precision precision)
    : context_(context),
      double_time_(precision == Precision::double_),
      make_records_(context.programs().kernel("ccd/contacts.cl", "cs_contact_records")),
      sorter_(context, record_words)
{
  std::vector<cl_uint> first_vertex(scene.objects.size());
  for (std::size_t o = 0; o < first_vertex.size(); ++o) first_vertex[o] = layout.slots[layout.slot_of[o]].first_vertex;
  first_vertex_ = runtime::Buffer(context, first_vertex.size() * sizeof(cl_uint), "first vertex of each object");
  context.write(first_vertex_, first_vertex.data(), first_vertex.size() * sizeof(cl_uint));
}

void ContactReadback::read(runtime::Scheduler& scheduler, const CcdStreams& streams, bool profile,
                           runtime::PassStats& stats, std::vector<Contact>& contacts)
{
  stats = runtime::PassStats{};
  stats.name = "canonical contacts";
  std::size_t n = 0;
  for (const auto& found : streams.contacts) n += scheduler.count(found.first);
  contacts.resize(n);
  if (n == 0) return;
  runtime::allocate_making_room(
      [&] {
        runtime::ensure_capacity(context_, records_, n * record_words * sizeof(cl_uint), "contact records");
        sorter_.reserve(n);
      },
      [&] { return scheduler.release_idle_scratch(); });
  runtime::Timeline timeline;
  runtime::Timeline* events = profile ? &timeline : nullptr;
  const std::uint64_t launches = context_.kernel_launches();
  unsigned a = 0;
  bind_four_streams(streams.contacts, "contact records", [&](runtime::StreamId stream, bool used, cl_uint vertex_face) {
    make_records_.set_arg(a++, scheduler.buffer(stream));
    make_records_.set_arg(a++, cl_uint(used ? scheduler.count(stream) : 0));
    make_records_.set_arg(a++, vertex_face);
  });
  make_records_.set_arg(a++, cl_uint(double_time_));
  make_records_.set_arg(a++, scheduler.buffer(streams.faces));
  make_records_.set_arg(a++, scheduler.buffer(streams.edges));
  make_records_.set_arg(a++, scheduler.buffer(streams.vertex_object));
  make_records_.set_arg(a++, first_vertex_);
  make_records_.set_arg(a++, records_);
  context_.launch(make_records_, n, context_.work_group_size(), events, stats.name);
  const runtime::Buffer& sorted = sorter_.sort(records_, n, events, stats.name.c_str());
  stats.launches = unsigned(context_.kernel_launches() - launches);
  const std::size_t bytes = n * record_words * sizeof(cl_uint);
  runtime::ensure_capacity(context_, staging_, bytes, "contact records");
  context_.read(sorted, staging_.data(), bytes);
  for (const auto& e : timeline.resolve()) stats.device_ns += e.nanoseconds;
  stats.scratch_bytes = scratch_bytes();

  const auto* words = static_cast<const cl_uint*>(staging_.data());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) contacts[i] = from_record(words + i * record_words, double_time_);
  });
}

}  // namespace cstreams
