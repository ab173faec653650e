#pragma once
#include <fstream>
#include <string>

namespace cstreams {

// Opens a file for reading, or throws InputError naming the path, what it was meant to
// be (`what`: "mesh file", "query file", ...) and why it cannot be read: missing, a
// directory, not a regular file (a device such as /dev/zero), not permitted. Streams
// opened on a directory would "succeed" and then fail on the first read with the C++
// library's own text.
std::ifstream open_input(const std::string& path, const std::string& what, bool binary = false);

}  // namespace cstreams
