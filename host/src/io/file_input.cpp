#include <cstreams/errors.hpp>
#include <cstreams/io/file_input.hpp>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace cstreams {

std::ifstream open_input(const std::string& path, const std::string& what, bool binary)
{
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) throw InputError(path + ": no such " + what);
  if (status.type() == fs::file_type::directory) throw InputError(path + ": is a directory, not a " + what);
  // A device or a pipe (/dev/zero) could be read forever.
  if (status.type() != fs::file_type::regular && status.type() != fs::file_type::unknown)
    throw InputError(path + ": is not a regular file, not a " + what);
  std::ifstream file(path, binary ? std::ios::in | std::ios::binary : std::ios::in);
  if (!file) throw InputError(path + ": cannot open " + what + ": " + std::strerror(errno));
  return file;
}

}  // namespace cstreams
