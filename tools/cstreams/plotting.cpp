#include "plotting.hpp"

#include <cstreams/errors.hpp>
#include <cstreams/io/file_output.hpp>

#include <cstdio>
#include <cstdlib>
#include <ostream>

namespace cstreams::cli {

void draw_plot(const char* script, const nlohmann::json& data, const std::string& target)
{
  const std::string data_path = target + ".json", script_path = target + ".py";
  write_file_atomically(data_path, [&](std::ostream& out) { out << data.dump() << "\n"; });
  write_file_atomically(script_path, [&](std::ostream& out) { out << script; });
  // The first python3 on PATH may be a private one without the system's matplotlib.
  int status = -1;
  std::string command;
  for (const char* python : {"python3", "/usr/bin/python3"}) {
    command = std::string(python) + " '" + script_path + "' '" + data_path + "' '" + target + "' 2>/dev/null";
    status = std::system(command.c_str());
    if (status == 0) break;
  }
  std::remove(script_path.c_str());
  std::remove(data_path.c_str());
  if (status != 0) throw Error("plotting failed (needs python3 with matplotlib): " + command);
}

}  // namespace cstreams::cli
