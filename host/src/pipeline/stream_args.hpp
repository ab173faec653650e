#pragma once
// The (items, count, kind) triples that kernels over every candidate or contact stream
// of a step take (cl_kernels/ccd/streams.h): four of them, the unused ones counting 0.
// Shared by the scene's graph (ccd_graph.cpp) and its elementary tests
// (elementary_tests.cpp).
#include <cstreams/contacts.hpp>
#include <cstreams/runtime/error.hpp>
#include <cstreams/runtime/opencl.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <string>
#include <utility>
#include <vector>

namespace cstreams {

constexpr std::size_t streams_per_kernel = 4;  // CS_FOUR_STREAMS

// Calls bind(stream, used, vertex_face) for the four triples in order; an unused one
// names the first stream, and the kernel is to count it as empty.
template <class Bind>
void bind_four_streams(const std::vector<std::pair<runtime::StreamId, ContactKind>>& streams, const std::string& what,
                       Bind bind)
{
  if (streams.empty() || streams.size() > streams_per_kernel)
    throw runtime::Error(what + " takes 1 to " + std::to_string(streams_per_kernel) + " streams, not " +
                         std::to_string(streams.size()));
  for (std::size_t k = 0; k < streams_per_kernel; ++k) {
    const bool used = k < streams.size();
    const auto& [stream, kind] = streams[used ? k : 0];
    bind(stream, used, cl_uint(kind == ContactKind::vertex_face));
  }
}

using ContactStreams = std::vector<std::pair<runtime::StreamId, ContactKind>>;

// A pass over every candidate (or contact) stream of a step in one launch
// (cs_cubic_pairs, cs_screen_pairs, cs_earliest_toi) launches over them all and takes
// their triples as its first arguments.
inline void over_streams(runtime::PassSpec& pass, const ContactStreams& streams, const char* what)
{
  using namespace runtime;
  std::vector<StreamId> over;
  for (const auto& s : streams) over.push_back(s.first);
  bind_four_streams(streams, what, [&](StreamId stream, bool used, cl_uint vertex_face) {
    pass.arg(buffer_of(stream)).arg(used ? count_of(stream) : value_of(cl_uint(0))).arg(value_of(vertex_face));
  });
  pass.launch_over(over);
}

}  // namespace cstreams
