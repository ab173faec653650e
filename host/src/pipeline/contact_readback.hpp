#pragma once
// The step's contacts as the user gets them, made on the device: every found pair
// mapped to its objects and object-local vertex ids, all kinds sorted together into
// canonical order (runtime::Sorter's passes, the first and last in ccd/contacts.cl),
// and read in one transfer of exactly the contacts, laid out as the host's Contact.
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cstreams {

// How a contact's fields pack into a record of the sort (ccd/contacts.cl): each id in
// the bits the scene's ids need, so that a record takes `words` words.
struct ContactRecord {
  cl_uint object_bits = 0, vertex_bits = 0, words = 0;
  static ContactRecord of(const SceneDescription& scene, Precision precision);
  std::string build_options() const;  // contacts.cl's, for records of `words` words
};

// Host memory the contacts of a step land in where they outgrow the pinned memory:
// ordinary pages, kept from step to step while steps need them.
class ContactPages {
public:
  // Holds at least `bytes`, what it held lost; gives back memory more than four times
  // what is asked (a burst of contacts that has passed).
  void fit(std::size_t bytes);
  std::byte* data() const noexcept { return data_.get(); }
  std::size_t bytes() const noexcept { return bytes_; }

private:
  struct Free {
    void operator()(std::byte* p) const noexcept;
  };
  std::unique_ptr<std::byte, Free> data_;
  std::size_t bytes_ = 0;
};

class ContactReadback {
public:
  // Pins at most `most_pinned_bytes` of host memory (DetectorOptions::pinned_contact_bytes).
  ContactReadback(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                  Precision precision, std::size_t most_pinned_bytes);

  // The contacts of the scheduler's last run, in canonical order, where the read put
  // them: valid until the next read. `stats` receives the device time (with `profile`)
  // and the launches it took, and `commands` gains its commands, the read included.
  // `meanwhile` runs once the sort is queued and before the read waits for it: host
  // work that then takes none of the step's time (it must queue nothing that the
  // device would do before the sort, nor touch the contact streams).
  // Its device scratch (records, the sort's, the Contacts) is lent by the scheduler's
  // step arena between runs; without one that holds it, the read takes scratch of its
  // own and gives it back, and short of device memory for it has the scheduler give
  // back its idle scratch.
  ContactSpan read(runtime::Scheduler& scheduler, const CcdStreams& streams, bool profile, runtime::PassStats& stats,
                   std::vector<runtime::Timeline::Entry>& commands, const std::function<void()>& meanwhile);

private:
  // Reads `bytes` of `contacts` into pages_ through the pinned memory, half of it at a
  // time: the device copies into one half while the host's threads copy the other out.
  const Contact* read_in_chunks(const runtime::Buffer& contacts, std::size_t bytes, runtime::Timeline* events);

  runtime::Context& context_;
  bool double_time_;
  ContactRecord record_;
  runtime::Kernel sort_blocks_;  // makes the records as it sorts them in blocks
  runtime::Kernel merge_last_;   // writes Contacts as it merges the last runs
  runtime::Sorter sorter_;
  runtime::Buffer first_vertex_;  // per object
  std::size_t most_pinned_;
  runtime::HostStaging staging_;  // the Contacts as read, handed out in place where they fit
  ContactPages pages_;            // where they do not
};

}  // namespace cstreams
