#include "commands.hpp"

namespace cstreams::cli {

std::unique_ptr<CommandLine> make_command_line()
{
  auto cli = std::make_unique<CommandLine>();
  cli->app.require_subcommand(1);
  add_devices_command(cli->app, cli->command);
  add_info_command(cli->app, cli->command);
  add_generate_command(cli->app, cli->command);
  add_reference_command(cli->app, cli->command);
  add_accuracy_command(cli->app, cli->command);
  add_run_command(cli->app, cli->command);
  add_compare_command(cli->app, cli->command);
  add_stepsize_command(cli->app, cli->command);
  add_proximity_command(cli->app, cli->command);
  return cli;
}

}  // namespace cstreams::cli
