// voxplan sim scene (being built; see the open issue).
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Command AddSimSceneCommand(CLI::App& sim) {
  CLI::App* sub = sim.add_subcommand("scene", "(being built)");
  return {sub, [] { return Fail("sim scene is being built", kExitUsage); }};
}

}  // namespace voxplan::cli
