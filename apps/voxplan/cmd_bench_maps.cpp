// voxplan bench maps (being built; see the open issue).
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Command AddBenchMapsCommand(CLI::App& bench) {
  CLI::App* sub = bench.add_subcommand("maps", "(being built)");
  return {sub, [] { return Fail("bench maps is being built", kExitUsage); }};
}

}  // namespace voxplan::cli
