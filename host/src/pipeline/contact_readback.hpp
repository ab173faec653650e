#pragma once
// The step's contacts as the user gets them, made on the device: every found pair
// mapped to its objects and object-local vertex ids (ccd/contacts.cl), all kinds
// sorted together into canonical order (runtime::Sorter), and read in one transfer
// of exactly the contacts.
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <vector>

namespace cstreams {

class ContactReadback {
public:
  ContactReadback(runtime::Context& context, const SceneLayout& layout, const SceneDescription& scene,
                  Precision precision);

  // Replaces `contacts` with those of the scheduler's last run, in canonical order.
  // `stats` receives the device time (with `profile`) and the launches it took. Host
  // memory is kept from step to step (`contacts` only shrinks or grows by the change
  // in count), and the records are turned into contacts on every core: on one core
  // that had cost more than the transfer on cloth-ball. Short of device memory for its
  // records, it has the scheduler give back its idle scratch.
  void read(runtime::Scheduler& scheduler, const CcdStreams& streams, bool profile, runtime::PassStats& stats,
            std::vector<Contact>& contacts);
  std::size_t scratch_bytes() const { return records_.bytes() + sorter_.scratch_bytes(); }

private:
  runtime::Context& context_;
  bool double_time_;
  runtime::Kernel make_records_;
  runtime::Sorter sorter_;
  runtime::Buffer first_vertex_;  // per object
  runtime::Buffer records_;
  runtime::HostStaging staging_;  // the sorted records as read
};

}  // namespace cstreams
