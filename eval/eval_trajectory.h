#pragma once
// Trajectory accuracy in the TUM RGB-D benchmark's terms (Sturm et al. 2012), over TUM
// trajectories (io/tum_trajectory.h): association by nearest timestamp, SE(3) alignment (Umeyama,
// no scale), absolute trajectory error and relative pose error between consecutive associated
// poses.
#include <cstddef>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/status.h"
#include "io/tum_trajectory.h"

namespace voxplan {

struct TrajectoryEvalParams {
  double max_dt_s = 0.02;  // association: largest timestamp difference accepted
};

struct TrajectoryEvalResult {
  size_t pairs = 0;  // associated poses
  double ate_rmse_m = 0.0, ate_mean_m = 0.0, ate_median_m = 0.0, ate_max_m = 0.0;
  size_t rpe_pairs = 0;  // consecutive associated pairs (pairs - 1)
  double rpe_trans_rmse_m = 0.0, rpe_trans_mean_m = 0.0;
  double rpe_rot_rmse_deg = 0.0, rpe_rot_mean_deg = 0.0;
  Pose3d T_ref_est = Pose3d::Identity();  // the alignment: p_ref ~ T_ref_est * p_est
  std::vector<double> ate_errors_m;       // per pair, in estimate time order
};

// Associates each estimate pose with the nearest reference timestamp within max_dt_s (one to
// one, closest pairs first), aligns the estimate positions to the reference ones and scores.
// Refuses trajectories with fewer than 3 associated poses (no overlap: names both sources).
Result<TrajectoryEvalResult> EvaluateTrajectory(const TumTrajectory& estimate,
                                                const TumTrajectory& reference,
                                                const TrajectoryEvalParams& params = {});

}  // namespace voxplan
