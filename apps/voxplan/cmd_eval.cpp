// voxplan eval mesh: accuracy and completeness of a reconstruction against ground truth.
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "io/mesh_io.h"
#include "sim/eval_mesh.h"
#include "sim/eval_trajectory.h"

namespace voxplan::cli {

namespace {

struct EvalMeshOptions {
  std::string reconstruction;
  std::string ground_truth;
  double threshold_m = 0.05;
  double samples_per_m2 = 10000.0;
  uint64_t seed = 1;
  std::string gt_up = "z";
  double gt_scale = 1.0;
  int threads = 0;
};

int RunEvalMesh(const EvalMeshOptions& o) {
  std::error_code ec;
  for (const std::string& path : {o.reconstruction, o.ground_truth}) {
    if (!std::filesystem::is_regular_file(path, ec)) return Fail("mesh file not found: " + path);
  }
  ThreadLimit thread_limit(o.threads);
  Result<Mesh> reconstruction = ReadMesh(o.reconstruction);
  if (!reconstruction.ok()) return Fail(MessageNaming(reconstruction.status(), o.reconstruction));
  MeshReadOptions gt_options;
  gt_options.up = o.gt_up == "y" ? UpAxis::kY : UpAxis::kZ;
  gt_options.scale = float(o.gt_scale);
  Result<Mesh> ground_truth = ReadMesh(o.ground_truth, gt_options);
  if (!ground_truth.ok()) return Fail(MessageNaming(ground_truth.status(), o.ground_truth));

  MeshEvalParams params;
  params.threshold_m = float(o.threshold_m);
  params.samples_per_m2 = float(o.samples_per_m2);
  params.seed = o.seed;
  const Stopwatch clock;
  Result<MeshEvalResult> result = EvaluateMesh(*reconstruction, *ground_truth, params);
  if (!result.ok()) return Fail("evaluation failed: " + result.status().message());
  const MeshEvalResult& r = *result;

  std::cerr << "accuracy: mean " << r.accuracy_mean_m * 1000 << " mm, RMS "
            << r.accuracy_rms_m * 1000 << " mm, median " << r.accuracy_median_m * 1000 << " mm ("
            << r.reconstruction_samples << " samples)\n"
            << "completeness: " << r.completeness * 100 << " % within " << o.threshold_m << " m ("
            << r.ground_truth_samples << " samples)\n";
  nlohmann::json j;
  j["command"] = "eval mesh";
  j["reconstruction"] = o.reconstruction;
  j["ground_truth"] = o.ground_truth;
  j["accuracy_mean_m"] = r.accuracy_mean_m;
  j["accuracy_rms_m"] = r.accuracy_rms_m;
  j["accuracy_median_m"] = r.accuracy_median_m;
  j["completeness"] = r.completeness;
  j["completeness_percent"] = RoundTo(100.0 * r.completeness, 3);
  j["threshold_m"] = o.threshold_m;
  j["samples_per_m2"] = o.samples_per_m2;
  j["seed"] = o.seed;
  j["reconstruction_samples"] = r.reconstruction_samples;
  j["ground_truth_samples"] = r.ground_truth_samples;
  j["reconstruction_area_m2"] = r.reconstruction_area_m2;
  j["ground_truth_area_m2"] = r.ground_truth_area_m2;
  j["eval_ms"] = RoundTo(clock.ElapsedMs(), 3);
  PrintJsonLine(j);
  return kExitOk;
}

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

Command AddEvalCommand(CLI::App& app) {
  CLI::App* eval = app.add_subcommand("eval", "Evaluate results against ground truth");
  eval->require_subcommand(1);
  auto o = std::make_shared<EvalMeshOptions>();
  CLI::App* sub = eval->add_subcommand("mesh", "Accuracy and completeness of a mesh");
  sub->add_option("reconstruction", o->reconstruction, "Reconstructed mesh")->required();
  sub->add_option("ground-truth", o->ground_truth, "Ground-truth mesh")->required();
  sub->add_option("--threshold", o->threshold_m, "Completeness distance threshold (m)")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--samples-per-m2", o->samples_per_m2, "Surface samples per square metre")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--seed", o->seed, "Sampling seed")->capture_default_str();
  sub->add_option("--gt-up", o->gt_up, "Up axis of the ground-truth file (y rotates to Z-up)")
      ->check(CLI::IsMember({"y", "z"}))
      ->capture_default_str();
  sub->add_option("--gt-scale", o->gt_scale, "Scale applied to the ground truth")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(NonNegative())
      ->capture_default_str();

  auto t = std::make_shared<EvalTrajectoryOptions>();
  CLI::App* traj =
      eval->add_subcommand("trajectory", "ATE and RPE of a TUM trajectory against a reference");
  traj->add_option("estimate", t->estimate, "Estimated trajectory (TUM: t tx ty tz qx qy qz qw)")
      ->required();
  traj->add_option("reference", t->reference, "Reference trajectory (TUM format)")->required();
  traj->add_option("--max-dt", t->max_dt_s, "Largest timestamp difference to associate (s)")
      ->check(NonNegative())
      ->capture_default_str();
  const std::vector<Command> sim_evals = AddEvalSimCommands(*eval);
  return {eval, [traj, o, t, sim_evals] {
            for (const Command& c : sim_evals) {
              if (c.app->parsed()) return c.run();
            }
            if (traj->parsed()) return RunEvalTrajectory(*t);
            return RunEvalMesh(*o);
          }};
}

}  // namespace voxplan::cli
