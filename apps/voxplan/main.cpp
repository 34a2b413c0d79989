// voxplan: one CLI, one subcommand per task. Each cmd_*.cpp parses its flags, calls the
// libraries and prints; nothing here knows how fusion or I/O work.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <vector>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/cli_examples.h"
#include "apps/voxplan/signals.h"

int main(int argc, char** argv) {
  using namespace voxplan::cli;
  CLI::App app{"voxplan: CPU voxel-hashing TSDF mapping (fuse RGB-D, mesh, evaluate, demo)",
               "voxplan"};
  app.set_version_flag("--version", "voxplan " VOXPLAN_VERSION);
  app.require_subcommand(1);
  // Usage errors read like every other error; CLI11's own help hint follows.
  app.failure_message([](const CLI::App* a, const CLI::Error& e) {
    return "error: " + std::string(e.what()) + "\nRun with --help for more information.\n";
  });

  std::vector<Command> commands = {
      AddFuseCommand(app),    AddMeshCommand(app),   AddInfoCommand(app),  AddEvalCommand(app),
      AddDemoCommand(app),    AddRenderCommand(app), AddBenchCommand(app), AddSimCommand(app),
      AddExploreCommand(app), AddFarmCommand(app)};
  AddHelpExamples(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);  // prints through failure_message
    return kExitUsage;
  }

  // Under mpirun every rank runs the command: only fuse and farm know how to share the work.
  if (const char* ranks = std::getenv("OMPI_COMM_WORLD_SIZE"); ranks && std::atoi(ranks) > 1) {
    const std::string name = app.get_subcommands().front()->get_name();
    if (name != "fuse" && name != "farm")
      return Fail("voxplan " + name + " runs in one process: only fuse and farm run under mpirun",
                  kExitUsage);
  }
  InstallSignalHandlers();
  try {
    return RunParsed(commands);
  } catch (const std::exception& e) {
    // Libraries only throw on invalid construction; arguments are checked before that.
    return Fail(e.what());
  }
}
