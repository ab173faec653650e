#pragma once
#include <CLI/CLI.hpp>

namespace cstreams::cli {

// Each command registers its subcommand and its callback. Callbacks throw on error;
// main() turns the exception into one line on stderr and exit status 1.
void add_devices_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_generate_command(CLI::App& app);
void add_reference_command(CLI::App& app);
void add_accuracy_command(CLI::App& app);

}  // namespace cstreams::cli
