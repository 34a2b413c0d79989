#pragma once
// How smoothly a robot moved (Xu 2017's path smoothness, X§7 Fig. 13-15), from its run log.
// Between two samples the explorer's motion has constant velocity (a straight piece, a turn in
// place, a pan or tilt), so the angular velocity is piecewise constant and its derivative is a
// train of impulses: the mean |angular acceleration| over the robot's time is the sum of the
// jumps |ω_{i+1} − ω_i| over that time, exactly, with the robot at rest before its first sample
// and after its last. Two bodies are measured:
//   base:   the heading (yaw);
//   camera: the view direction, pan about world z (yaw + cam_yaw) and tilt (cam_pitch) — two
//           orthogonal axes, so |ω| = hypot(ω_pan, ω_tilt).
#include <cstddef>
#include <numbers>

#include "eval/eval_run.h"

namespace voxplan {

struct SmoothnessParams {
  double sharp_turn_rad = std::numbers::pi / 4;  // a net heading change above this ...
  double window_m = 0.5;                         // ... within this much travel is a sharp turn
};

struct PathSmoothness {
  double time_s = 0.0;      // the track's span
  double distance_m = 0.0;  // planar base travel
  // Σ |ω_{i+1} − ω_i| (rad/s), ω = 0 at both ends; mean_abs_angular_accel = this / time_s.
  double angular_velocity_jumps_radps = 0.0;
  double mean_abs_angular_accel_radps2 = 0.0;
  // Σ |Δθ|: the curvature integral ∫|κ| ds of the base path, turns in place included (rad).
  double turning_rad = 0.0;
  double turning_per_m = 0.0;  // turning_rad / distance_m; 0 without travel
  // Windows of window_m travel (turns at a standstill join the window they fall in) whose net
  // heading change exceeds sharp_turn_rad.
  std::size_t sharp_turns = 0;
  double sharp_turns_per_10m = 0.0;  // 0 without travel
};

PathSmoothness BaseSmoothness(const RobotTrack& track, const SmoothnessParams& params = {});
PathSmoothness CameraSmoothness(const RobotTrack& track, const SmoothnessParams& params = {});

// Sums of tracks (their times and distances, jumps, turns), with the ratios recomputed: a team's
// smoothness weighted by each robot's time and travel.
PathSmoothness CombineSmoothness(const PathSmoothness& a, const PathSmoothness& b);

}  // namespace voxplan
