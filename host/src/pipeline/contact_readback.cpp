#include "contact_readback.hpp"
#include "stream_args.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <type_traits>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace cstreams {

namespace {

// Bits that hold every value below n.
cl_uint bits_below(std::size_t n)
{
  cl_uint bits = 0;
  while (bits < 64 && (std::uint64_t(1) << bits) < n) ++bits;
  return bits;
}

// Pinned with the detector, not in its first step, for up to this many contacts a face:
// NVIDIA's driver takes about 0.45 ms a MB to pin (cloth-ball's first step: 2.4 ms for
// 113,859 contacts), and the real steps report 0.01 to 1.2 contacts a face. A step with
// more grows the memory then, up to the most the detector pins.
constexpr std::size_t reserved_contacts_a_face = 2;

// Contacts past the pinned memory go through at least this much of it (or all it may
// have), so that a burst takes few chunks however little the scene reserved.
constexpr std::size_t least_chunked_pinned_bytes = std::size_t(16) << 20;

// Pages of ordinary memory are given in huge pages where the kernel has them: a burst's
// fresh memory then faults in 2 MiB at a time.
constexpr std::size_t page_run_bytes = std::size_t(2) << 20;

// cs_store_contact writes Contacts word by word; the host reads them in place.
static_assert(std::is_trivially_copyable_v<Contact> && std::is_standard_layout_v<Contact>);
static_assert(sizeof(ContactKind) == 1 && sizeof(Contact) == 40 && offsetof(Contact, object_a) == 4 &&
                  offsetof(Contact, object_b) == 8 && offsetof(Contact, v) == 12 && offsetof(Contact, toi) == 32,
              "Contact's layout is the one cs_store_contact writes");

}  // namespace

ContactRecord ContactRecord::of(const SceneDescription& scene, Precision precision)
{
  ContactRecord r;
  std::size_t vertices = 0;
  for (const auto& object : scene.objects) vertices = std::max(vertices, object.positions.size());
  r.object_bits = bits_below(scene.objects.size());
  r.vertex_bits = bits_below(vertices);
  const std::size_t bits = 1 + 2 * r.object_bits + 4 * r.vertex_bits + (precision == Precision::double_ ? 64 : 32);
  r.words = (bits + 31) / 32;
  return r;
}

std::string ContactRecord::build_options() const { return "-DCS_SORT_WORDS=" + std::to_string(words); }

void ContactPages::Free::operator()(std::byte* p) const noexcept { std::free(p); }

void ContactPages::fit(std::size_t bytes)
{
  if (bytes_ >= bytes && bytes_ / 4 <= bytes) return;
  data_.reset();
  bytes_ = 0;
  if (bytes == 0) return;
  // A quarter more, so that a burst that goes on growing takes fresh pages less often.
  const std::size_t want = (bytes + bytes / 4 + page_run_bytes - 1) / page_run_bytes * page_run_bytes;
  auto* p = static_cast<std::byte*>(std::aligned_alloc(page_run_bytes, want));
  if (!p) throw std::bad_alloc();
#ifdef __linux__
  madvise(p, want, MADV_HUGEPAGE);  // advice: without huge pages the memory serves as it is
#endif
  data_.reset(p);
  bytes_ = want;
}

ContactReadback::ContactReadback(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                                 Precision precision, std::size_t most_pinned_bytes)
    : context_(context),
      double_time_(precision == Precision::double_),
      record_(ContactRecord::of(scene, precision)),
      sort_blocks_(context.programs().kernel("ccd/contacts.cl", "cs_contact_sort_blocks", record_.build_options())),
      merge_last_(context.programs().kernel("ccd/contacts.cl", "cs_contacts_merged", record_.build_options())),
      sorter_(context, record_.words),
      most_pinned_(std::max(most_pinned_bytes, 2 * sizeof(Contact)))
{
  std::vector<cl_uint> first_vertex(scene.objects.size());
  for (std::size_t o = 0; o < first_vertex.size(); ++o) first_vertex[o] = layout.slots[layout.slot_of[o]].first_vertex;
  first_vertex_ = runtime::Buffer(context, first_vertex.size() * sizeof(cl_uint), "first vertex of each object");
  context.write(first_vertex_, first_vertex.data(), first_vertex.size() * sizeof(cl_uint));
  const std::size_t faces = layout.topology.faces.size();
  runtime::ensure_capacity(context, staging_, std::min(most_pinned_, reserved_contacts_a_face * faces * sizeof(Contact)),
                           "contacts");
}

ContactSpan ContactReadback::read(runtime::Scheduler& scheduler, const CcdStreams& streams, bool profile,
                                  runtime::PassStats& stats, std::vector<runtime::Timeline::Entry>& commands,
                                  const std::function<void()>& meanwhile)
{
  stats = runtime::PassStats{};
  stats.name = "canonical contacts";
  std::size_t n = 0;
  for (const auto& found : streams.contacts) n += scheduler.count(found.first);
  if (n == 0) {
    meanwhile();
    return {};
  }
  const std::size_t record_bytes = n * record_.words * sizeof(cl_uint), sort_bytes = sorter_.scratch_bytes_for(n),
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
  sorter_.check_sortable(sort_scratch, n, stats.name.c_str());
  unsigned a = 0;
  bind_four_streams(streams.contacts, "contact records", [&](runtime::StreamId stream, bool used, cl_uint vertex_face) {
    sort_blocks_.set_arg(a++, scheduler.buffer(stream));
    sort_blocks_.set_arg(a++, cl_uint(used ? scheduler.count(stream) : 0));
    sort_blocks_.set_arg(a++, vertex_face);
  });
  sort_blocks_.set_arg(a++, cl_uint(double_time_));
  sort_blocks_.set_arg(a++, record_.object_bits);
  sort_blocks_.set_arg(a++, record_.vertex_bits);
  sort_blocks_.set_arg(a++, scheduler.buffer(streams.faces));
  sort_blocks_.set_arg(a++, scheduler.buffer(streams.edges));
  sort_blocks_.set_arg(a++, scheduler.buffer(streams.vertex_object));
  sort_blocks_.set_arg(a++, first_vertex_);
  sort_blocks_.set_arg(a++, cl_uint(n));
  sort_blocks_.set_arg(a++, cl_uint(sorter_.sorted_block(n)));
  sort_blocks_.set_arg(a++, records);
  sort_blocks_.set_arg(a++, contacts);
  sort_blocks_.set_local(a, sorter_.block_local_bytes());
  const std::size_t wg = context_.work_group_size(), groups = (n + sorter_.block() - 1) / sorter_.block();
  context_.launch(sort_blocks_, groups * wg, wg, events, stats.name);
  if (const std::size_t passes = sorter_.merge_passes(n)) {
    const runtime::Buffer& runs = sorter_.merge(records, sort_scratch, n, passes - 1, events, stats.name.c_str());
    merge_last_.set_args(runs, cl_uint(n), cl_uint(sorter_.block() << (passes - 1)), cl_uint(sorter_.tile()),
                         cl_uint(double_time_), record_.object_bits, record_.vertex_bits, contacts);
    merge_last_.set_local(8, sorter_.tile_local_bytes());
    context_.launch(merge_last_, sorter_.tiles(n) * wg, wg, events, stats.name);
  }
  stats.launches = unsigned(context_.kernel_launches() - launches);
  meanwhile();
  const Contact* landed = nullptr;
  if (contact_bytes <= most_pinned_) {
    runtime::ensure_capacity(context_, staging_, contact_bytes, "contacts");
    context_.read(contacts, staging_.data(), contact_bytes, 0, events);
    landed = static_cast<const Contact*>(staging_.data());
    pages_.fit(0);
  } else {
    landed = read_in_chunks(contacts, contact_bytes, events);
  }
  for (auto& e : timeline.resolve()) {
    if (e.label == stats.name) stats.device_ns += e.nanoseconds;
    commands.push_back(std::move(e));
  }
  // The read wrote Contacts' bytes into memory the host never constructed objects in:
  // Contact is trivially copyable, an implicit-lifetime type (P0593), so the read
  // creates them as memcpy would.
  return {landed, n};
}

// Pinning the whole of a burst cost more than its reading: the 1.5M-triangle sheet's
// surge step (6.42M contacts, 257 MB) took 100-150 ms of host time in NVIDIA's driver to
// pin the memory, and read into ordinary memory by the driver itself, 200 ms. In chunks,
// its read takes 7-10 ms (H200).
const Contact* ContactReadback::read_in_chunks(const runtime::Buffer& contacts, std::size_t bytes,
                                               runtime::Timeline* events)
{
  runtime::ensure_capacity(context_, staging_, std::min(most_pinned_, least_chunked_pinned_bytes), "contacts");
  pages_.fit(bytes);
  const std::size_t half = std::max(sizeof(Contact), staging_.bytes() / 2 / sizeof(Contact) * sizeof(Contact));
  const std::size_t chunks = (bytes + half - 1) / half;
  auto* pinned = static_cast<std::byte*>(staging_.data());
  std::vector<runtime::Handle<cl_event>> reads(chunks);
  const auto size = [&](std::size_t k) { return std::min(half, bytes - k * half); };
  const auto queue_read = [&](std::size_t k) {
    reads[k] = context_.read_started(contacts, pinned + k % 2 * half, size(k), k * half, events);
  };
  for (std::size_t k = 0; k < std::min<std::size_t>(2, chunks); ++k) queue_read(k);
  for (std::size_t k = 0; k < chunks; ++k) {
    context_.read_landed(reads[k]);
    const std::byte* from = pinned + k % 2 * half;
    std::byte* to = pages_.data() + k * half;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size(k), std::size_t(1) << 20),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        std::memcpy(to + r.begin(), from + r.begin(), r.size());
                      });
    // The half just copied out takes the chunk after the next.
    if (k + 2 < chunks) queue_read(k + 2);
  }
  return reinterpret_cast<const Contact*>(pages_.data());
}

}  // namespace cstreams
