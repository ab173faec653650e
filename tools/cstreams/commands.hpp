#pragma once
#include <cstreams/scene/scene.hpp>

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cstreams::cli {

// The command line in two phases: parsing checks every option (names, numeric ranges,
// output paths) and does no work; the command it yields then runs. A bad option fails
// at once, before a scene is read or a device opened, and the fuzzer drives the first
// phase alone.
struct CommandLine {
  CLI::App app{"cstreams: continuous collision detection between deforming triangle meshes on OpenCL devices"};
  std::function<void()> command;  // set by the chosen subcommand once its options pass
};
std::unique_ptr<CommandLine> make_command_line();

// Each registers its subcommand; its callback checks the options (throwing InputError
// naming the flag) and sets `command`.
using Command = std::function<void()>;
void add_devices_command(CLI::App& app, Command& command);
void add_info_command(CLI::App& app, Command& command);
void add_generate_command(CLI::App& app, Command& command);
void add_reference_command(CLI::App& app, Command& command);
void add_accuracy_command(CLI::App& app, Command& command);
void add_run_command(CLI::App& app, Command& command);
void add_compare_command(CLI::App& app, Command& command);
void add_stepsize_command(CLI::App& app, Command& command);
void add_proximity_command(CLI::App& app, Command& command);

// A manifest or mesh file, or several mesh files as the frames of one mesh.
Scene open_scene(const std::vector<std::string>& paths, bool split);

// --frames: "A:B" steps from frame A up to (not including) B; "A" one step; empty: every
// step. Parsing checks the form, resolving checks it against the scene.
struct StepRange {
  bool all = true;
  std::size_t first = 0, last = 0;
};
StepRange parse_step_range(const std::string& text);
std::pair<std::size_t, std::size_t> resolve(const StepRange& range, std::size_t frame_count);

}  // namespace cstreams::cli
