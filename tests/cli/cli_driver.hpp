#pragma once
// Drives the command line in-process, as the program would: parsing alone (the errors
// it gives before any work) or parsing and running.
#include "../support/benchmark_data.hpp"
#include "../support/scratch.hpp"

#include <commands.hpp>
#include <cstreams/errors.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace {

// Parses `args` (after the program name); returns the error text, empty if accepted.
// `ran` tells whether a command was produced.
std::string parse(std::vector<std::string> args, bool* ran = nullptr)
{
  auto cli = cstreams::cli::make_command_line();
  args.insert(args.begin(), "cstreams");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::string error;
  try {
    cli->app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    error = e.get_name() + ": " + e.what();
  } catch (const cstreams::InputError& e) {
    error = e.what();
  }
  if (ran) *ran = bool(cli->command);
  if (error.empty() && !cli->command) error = "no command";
  return error;
}

std::string funnel_frame(const char* name)
{
  return cstreams::test::benchmark_path(std::string("scalable-ccd-sample/cloth-funnel/frames/") + name);
}

std::filesystem::path fresh_dir(const char* name) { return cstreams::test::fresh_scratch(name); }

// Parses and runs a command line as the program would.
void execute(std::vector<std::string> args)
{
  auto cli = cstreams::cli::make_command_line();
  args.insert(args.begin(), "cstreams");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  cli->app.parse(int(argv.size()), argv.data());
  cli->command();
}

}  // namespace
