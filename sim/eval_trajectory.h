#pragma once
// Trajectory accuracy in the TUM RGB-D benchmark's terms (Sturm et al. 2012): TUM trajectory
// files, association by nearest timestamp, SE(3) alignment (Umeyama, no scale), absolute
// trajectory error and relative pose error between consecutive associated poses.
#include <cstddef>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/status.h"

namespace voxplan {

struct TumTrajectory {
  std::vector<double> timestamps_s;
  std::vector<Pose3d> T_W_C;  // one per timestamp, camera-to-world
  std::string source;         // the file it came from, for messages; may be empty
};

// Reads `t tx ty tz qx qy qz qw` lines; blank lines and `#` comments are skipped, CRLF line
// ends accepted. A malformed line is refused with `path:line: ...`; a file without poses too.
Result<TumTrajectory> ReadTumTrajectory(const std::string& path);

// Writes `t tx ty tz qx qy qz qw` lines (timestamps with 6 decimals), temporary file then
// rename. Refuses vectors of different lengths.
Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3d>& T_W_C);
Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3f>& T_W_C);

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
