#pragma once
#include <cstreams/scene/scene.hpp>

#include <CLI/CLI.hpp>

#include <string>
#include <utility>
#include <vector>

namespace cstreams::cli {

// Each command registers its subcommand and its callback. Callbacks throw on error;
// main() turns the exception into one line on stderr and exit status 1.
void add_devices_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_generate_command(CLI::App& app);
void add_reference_command(CLI::App& app);
void add_accuracy_command(CLI::App& app);
void add_run_command(CLI::App& app);

// A manifest or mesh file, or several mesh files as the frames of one mesh.
Scene open_scene(const std::vector<std::string>& paths, bool split);
// "A:B" steps from frame A up to (not including) B; "A" one step; empty: every step.
std::pair<std::size_t, std::size_t> step_range(const std::string& text, std::size_t frame_count);

}  // namespace cstreams::cli
