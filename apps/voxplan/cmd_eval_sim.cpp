// voxplan eval subcommands for simulated runs (being built; see the open issue).
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

std::vector<Command> AddEvalSimCommands(CLI::App& eval) { return {}; }

}  // namespace voxplan::cli
