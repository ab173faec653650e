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

// Throws InputError naming `option` and `path` unless a file could be written there now:
// its folder exists and is writable, and `path` is not a folder. Run before long work, so
// that a bad output path fails at once rather than after it.
void check_output_path(const std::string& option, const std::string& path);

}  // namespace cstreams
