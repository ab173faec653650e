#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>

#include <cstdio>
#include <fstream>

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

}  // namespace cstreams
