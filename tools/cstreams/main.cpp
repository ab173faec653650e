#include "commands.hpp"

#include <cstdio>
#include <exception>

int main(int argc, char** argv)
{
  const auto cli = cstreams::cli::make_command_line();
  try {
    cli->app.parse(argc, argv);
    cli->command();
  } catch (const CLI::ParseError& e) {
    return cli->app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cstreams: %s\n", e.what());
    return 1;
  }
  return 0;
}
