// voxplan eval trajectory: ATE and RPE of an estimated TUM trajectory against a reference.
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "eval/eval_trajectory.h"
#include "io/tum_trajectory.h"

namespace voxplan::cli {

namespace {

struct EvalTrajectoryOptions {
  std::string estimate;
  std::string reference;
  double max_dt_s = 0.02;
};

int RunEvalTrajectory(const EvalTrajectoryOptions& o) {
  std::error_code ec;
  for (const std::string& path : {o.estimate, o.reference}) {
    if (!std::filesystem::is_regular_file(path, ec))
      return Fail("trajectory file not found: " + path);
  }
  Result<TumTrajectory> estimate = ReadTumTrajectory(o.estimate);
  if (!estimate.ok()) return Fail(MessageNaming(estimate.status(), o.estimate));
  Result<TumTrajectory> reference = ReadTumTrajectory(o.reference);
  if (!reference.ok()) return Fail(MessageNaming(reference.status(), o.reference));
  TrajectoryEvalParams params;
  params.max_dt_s = o.max_dt_s;
  Result<TrajectoryEvalResult> result = EvaluateTrajectory(*estimate, *reference, params);
  if (!result.ok()) return Fail(result.status().message());
  const TrajectoryEvalResult& r = *result;

  std::cerr << "associated " << r.pairs << " of " << estimate->T_W_C.size() << " estimate poses ("
            << reference->T_W_C.size() << " reference) within " << o.max_dt_s << " s\n"
            << "ATE: RMSE " << r.ate_rmse_m * 1000 << " mm, mean " << r.ate_mean_m * 1000
            << " mm, median " << r.ate_median_m * 1000 << " mm, max " << r.ate_max_m * 1000
            << " mm\n"
            << "RPE (1 frame): translation RMSE " << r.rpe_trans_rmse_m * 1000
            << " mm, rotation RMSE " << r.rpe_rot_rmse_deg << " deg\n";
  nlohmann::json j;
  j["command"] = "eval trajectory";
  j["estimate"] = o.estimate;
  j["reference"] = o.reference;
  j["max_dt_s"] = o.max_dt_s;
  j["pairs"] = r.pairs;
  j["estimate_poses"] = estimate->T_W_C.size();
  j["reference_poses"] = reference->T_W_C.size();
  j["ate_rmse_m"] = r.ate_rmse_m;
  j["ate_mean_m"] = r.ate_mean_m;
  j["ate_median_m"] = r.ate_median_m;
  j["ate_max_m"] = r.ate_max_m;
  j["rpe_pairs"] = r.rpe_pairs;
  j["rpe_trans_rmse_m"] = r.rpe_trans_rmse_m;
  j["rpe_trans_mean_m"] = r.rpe_trans_mean_m;
  j["rpe_rot_rmse_deg"] = r.rpe_rot_rmse_deg;
  j["rpe_rot_mean_deg"] = r.rpe_rot_mean_deg;
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddEvalTrajectoryCommand(CLI::App& eval) {
  auto t = std::make_shared<EvalTrajectoryOptions>();
  CLI::App* traj =
      eval.add_subcommand("trajectory", "ATE and RPE of a TUM trajectory against a reference");
  traj->add_option("estimate", t->estimate, "Estimated trajectory (TUM: t tx ty tz qx qy qz qw)")
      ->required();
  traj->add_option("reference", t->reference, "Reference trajectory (TUM format)")->required();
  traj->add_option("--max-dt", t->max_dt_s, "Largest timestamp difference to associate (s)")
      ->check(InRange(0.0, 1e6, "s"))
      ->capture_default_str();
  return {traj, [t] { return RunEvalTrajectory(*t); }};
}

}  // namespace voxplan::cli
