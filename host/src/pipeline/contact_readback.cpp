#include "contact_readback.hpp"
#include "stream_args.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

namespace cstreams {

namespace {

constexpr std::size_t record_words = 8;  // cs_contact_records

// cs_contacts_as_host writes Contacts word by word; the host reads them in place.
static_assert(std::is_trivially_copyable_v<Contact> && std::is_standard_layout_v<Contact>);
static_assert(sizeof(ContactKind) == 1 && sizeof(Contact) == 40 && offsetof(Contact, object_a) == 4 &&
                  offsetof(Contact, object_b) == 8 && offsetof(Contact, v) == 12 && offsetof(Contact, toi) == 32,
              "Contact's layout is the one cs_contacts_as_host writes");

}  // namespace

ContactReadback::ContactReadback(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                                 Precision precision)
    : context_(context),
      double_time_(precision == Precision::double_),
      make_records_(context.programs().kernel("ccd/contacts.cl", "cs_contact_records")),
      as_host_(context.programs().kernel("ccd/contacts.cl", "cs_contacts_as_host")),
      sorter_(context, record_words)
{
  std::vector<cl_uint> first_vertex(scene.objects.size());
  for (std::size_t o = 0; o < first_vertex.size(); ++o) first_vertex[o] = layout.slots[layout.slot_of[o]].first_vertex;
  first_vertex_ = runtime::Buffer(context, first_vertex.size() * sizeof(cl_uint), "first vertex of each object");
  context.write(first_vertex_, first_vertex.data(), first_vertex.size() * sizeof(cl_uint));
}

ContactSpan ContactReadback::read(runtime::Scheduler& scheduler, const CcdStreams& streams, bool profile,
                                  runtime::PassStats& stats)
{
  stats = runtime::PassStats{};
  stats.name = "canonical contacts";
  std::size_t n = 0;
  for (const auto& found : streams.contacts) n += scheduler.count(found.first);
  if (n == 0) return {};
  const std::size_t record_bytes = n * record_words * sizeof(cl_uint), sort_bytes = sorter_.scratch_bytes_for(n),
                    contact_bytes = n * sizeof(Contact);
  // Lent by the step arena's free space between runs. Where it has none to lend, the
  // readback takes scratch of its own for this read alone: held from one step to the
  // next, it set the peak of the step after, whose front update ran beside it, and of
  // the first step with an arena (cloth-ball: 11.9 MB).
  std::vector<runtime::Buffer> scratch = scheduler.borrow_idle_scratch({record_bytes, sort_bytes, contact_bytes});
  if (scratch.empty())
    runtime::allocate_making_room(
        [&] {
          scratch.clear();
          scratch.emplace_back(context_, record_bytes, "contact records");
          scratch.emplace_back(context_, sort_bytes, "sort scratch");
          scratch.emplace_back(context_, contact_bytes, "contacts");
        },
        [&] { return scheduler.release_idle_scratch(); });
  const runtime::Buffer &records = scratch[0], &sort_scratch = scratch[1], &contacts = scratch[2];
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
  make_records_.set_arg(a++, records);
  context_.launch(make_records_, n, context_.work_group_size(), events, stats.name);
  const runtime::Buffer& sorted = sorter_.sort(records, sort_scratch, n, events, stats.name.c_str());
  as_host_.set_args(sorted, cl_uint(n), cl_uint(double_time_), contacts);
  context_.launch(as_host_, n, context_.work_group_size(), events, stats.name);
  stats.launches = unsigned(context_.kernel_launches() - launches);
  runtime::ensure_capacity(context_, staging_, contact_bytes, "contacts");
  context_.read(contacts, staging_.data(), contact_bytes);
  for (const auto& e : timeline.resolve()) stats.device_ns += e.nanoseconds;
  // The read wrote Contacts' bytes into memory the host never constructed objects in:
  // Contact is trivially copyable, an implicit-lifetime type (P0593), so the read
  // creates them as memcpy would.
  return {static_cast<const Contact*>(staging_.data()), n};
}

}  // namespace cstreams
