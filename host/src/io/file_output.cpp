#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace cstreams {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write, bool binary)
{
  const std::string temporary = path + ".partial";
  try {
    std::ofstream out(temporary, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) throw InputError(path + ": cannot create file");
    write(out);
    if (!out.flush()) throw InputError(path + ": write failed");
  } catch (...) {
    std::remove(temporary.c_str());
    throw;
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw InputError(path + ": cannot move the written file into place");
  }
}

void check_output_path(const std::string& option, const std::string& path)
{
  namespace fs = std::filesystem;
  const std::string where = option + " " + path + ": ";
  if (path.empty()) throw InputError(option + ": empty file name");
  std::error_code error;
  if (fs::is_directory(path, error)) throw InputError(where + "is a folder, not a file");
  fs::path folder = fs::path(path).parent_path();
  if (folder.empty()) folder = ".";
  if (!fs::exists(folder, error)) throw InputError(where + "folder " + folder.string() + " does not exist");
  if (!fs::is_directory(folder, error)) throw InputError(where + folder.string() + " is not a folder");
  if (::access(folder.c_str(), W_OK) != 0) throw InputError(where + "folder " + folder.string() + " is not writable");
}

}  // namespace cstreams
