// voxplan sim render (being built; see the open issue).
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Command AddSimRenderCommand(CLI::App& sim) {
  CLI::App* sub = sim.add_subcommand("render", "(being built)");
  return {sub, [] { return Fail("sim render is being built", kExitUsage); }};
}

}  // namespace voxplan::cli
