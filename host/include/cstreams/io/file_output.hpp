#pragma once
#include <functional>
#include <iosfwd>
#include <string>

namespace cstreams {

// Writes a file through `path.partial`, renamed over `path` only once everything was
// written, so a failure (thrown by `write` or by the stream) leaves no half-written
// file behind. Throws InputError naming the path.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

}  // namespace cstreams
