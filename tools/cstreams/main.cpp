#include "commands.hpp"

#include <cstdio>
#include <exception>

int main(int argc, char** argv)
{
  CLI::App app{"cstreams: continuous collision detection between deforming triangle meshes on OpenCL devices"};
  app.require_subcommand(1);
  cstreams::cli::add_devices_command(app);
  cstreams::cli::add_info_command(app);
  cstreams::cli::add_generate_command(app);
  cstreams::cli::add_reference_command(app);
  cstreams::cli::add_accuracy_command(app);
  cstreams::cli::add_run_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cstreams: %s\n", e.what());
    return 1;
  }
  return 0;
}
