#include "inputs.hpp"

#include <commands.hpp>
#include <cstreams/errors.hpp>

#include <vector>

namespace cstreams::fuzz {

void command_line(std::string_view bytes)
{
  std::vector<std::string> args{"cstreams"};
  std::string current;
  for (char c : bytes) {
    if (c == '\0' || c == '\n') {
      args.push_back(current);
      current.clear();
    } else {
      current += c;
    }
    if (args.size() > 64) return;
  }
  args.push_back(current);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  const auto cli = cli::make_command_line();
  try {
    cli->app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError&) {
  } catch (const InputError&) {
  }
}

}  // namespace cstreams::fuzz
