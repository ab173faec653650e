#pragma once
// Scratch folders in the temporary directory, one per test process, so that two test
// runs on one machine (two devices, or a run beside CI) never share or wipe one; each
// goes when the process ends.
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace cstreams::test {

// An empty folder `cstreams-<name>-<process id>` in the temporary directory.
inline std::filesystem::path fresh_scratch(const std::string& name)
{
  static struct Made {
    std::vector<std::filesystem::path> folders;
    ~Made()
    {
      std::error_code ignored;
      for (const auto& f : folders) std::filesystem::remove_all(f, ignored);
    }
  } made;
  const auto dir = std::filesystem::temp_directory_path() / ("cstreams-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  made.folders.push_back(dir);
  return dir;
}

}  // namespace cstreams::test
