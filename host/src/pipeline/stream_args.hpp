#pragma once
// The (items, count, kind) triples that kernels over every candidate or contact stream
// of a step take (cl_kernels/ccd/streams.h): four of them, the unused ones counting 0.
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

}  // namespace cstreams
