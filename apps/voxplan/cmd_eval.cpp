// voxplan eval: scores against ground truth, one subcommand per kind (mesh, trajectory, objects,
// run), each in its own cmd_eval_*.cpp.
#include "apps/voxplan/cli_common.h"

namespace voxplan::cli {

Command AddEvalCommand(CLI::App& app) {
  CLI::App* eval = app.add_subcommand("eval", "Evaluate results against ground truth");
  eval->require_subcommand(1);
  std::vector<Command> subs = {AddEvalMeshCommand(*eval), AddEvalTrajectoryCommand(*eval),
                               AddEvalObjectsCommand(*eval), AddEvalRunCommand(*eval)};
  return {eval, [subs] { return RunParsed(subs); }};
}

}  // namespace voxplan::cli
