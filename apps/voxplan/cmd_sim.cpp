// voxplan sim: simulated worlds and sensors (scene generation, rendering datasets).
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Command AddSimCommand(CLI::App& app) {
  CLI::App* sim = app.add_subcommand("sim", "Simulated worlds and RGB-D sensors");
  sim->require_subcommand(1);
  std::vector<Command> subs = {AddSimSceneCommand(*sim), AddSimRenderCommand(*sim),
                               AddSimTourCommand(*sim)};
  return {sim, [subs] { return RunParsed(subs); }};
}

}  // namespace voxplan::cli
