#pragma once
// The robot of an exploration run as a file (`voxplan explore --robot-config robot.json`), and the
// named profiles that set the simulator the way a paper ran it (`--profile guo2022`).
//
// The file is one JSON object; every key is optional and a missing one keeps the base's value
// (the built-in defaults, or the profile's). Unknown keys, wrong types and values out of their
// bounds are refused with the key's name:
//   {"radius_m": 0.2, "camera_height_m": 1.2, "camera_yaw_rate_radps": 1.5,
//    "camera_pitch_rate_radps": 1.0, "max_abs_pitch_deg": 60, "dwell_s": 0.2,
//    "explorer": MODE, "reconstructor": MODE}
//   MODE = {"max_speed_mps": .., "max_turn_rate_radps": .., "horizontal_fov_deg": ..,
//           "min_range_m": .., "max_range_m": .., "capture_hz": .., "switch_s": ..,
//           "mount": "head" | "arm",
//           "arm": {"height_min_m", "height_max_m", "reach_min_m", "reach_max_m",
//                   "reach_half_angle_deg", "max_abs_pitch_deg", "speed_mps"}}
#include <string>

#include "core/status.h"
#include "explore/explore.h"
#include "sim/robot.h"

namespace voxplan {

// Guo 2022's robot as voxplan models it. The paper names the sensors (a head Primesense, a hand
// RealSense, G L219) but gives no speed, range, workspace or switch cost, so these are chosen:
//   explorer:      0.5 m/s, 1 rad/s, 90 deg, 0.35-5 m, head camera at 1.2 m tilting +-60 deg
//                  (a Primesense's near limit is 0.35 m);
//   reconstructor: 0.2 m/s, 0.5 rad/s, 58 deg, 0.2-2.5 m (a D435's), an arm camera 0.4-1.5 m
//                  high, 0.3-0.8 m from the base centre within +-90 deg of the heading, pitch
//                  +-90 deg (the paper's phi range), moving at 0.25 m/s;
//   both capture at 2 Hz while driving and dwelling ("scans continuously along the route");
//   switching into either mode takes 2 s (stowing or unstowing the arm: "extra costs", G L188).
RobotParams Guo2022RobotParams();

// Xu 2017's robot as voxplan models it (a Fetch; the paper gives speed and camera limits only):
//   one mode, the explorer: 0.3 m/s (X L304), a Kinect v1's 58 deg and 0.5-4 m, 5 Hz capture
//   while moving (design G.3), camera yaw and pitch at a_m = 40 deg/s (X L306). The paper's
//   camera rides an arm; the head camera here turns in yaw and pitch only.
RobotParams Xu2017RobotParams();

// The JSON text over `base`; errors name `source` (a file path) and the key.
Result<RobotParams> ParseRobotConfig(const std::string& json_text, const RobotParams& base,
                                     const std::string& source = "robot config");
// The file at `path` (at most 1 MiB) over `base`.
Result<RobotParams> ReadRobotConfig(const std::string& path, const RobotParams& base);
// Every key, pretty-printed: what ParseRobotConfig reads back to the same params.
std::string RobotConfigJson(const RobotParams& params);

// A profile's simulator settings over `params` (robot, capture, reconstruction volume, detector):
//   "guo2022": Guo2022RobotParams(), a 2 cm reconstruction volume weighing depth by 1/z² (as
//              Voxblox, Guo's fusion, does), the detector's noise on.
//   "xu2017":  Xu2017RobotParams(), a 2 cm reconstruction volume, a 0.1 s loop step for the
//              planner's sub-steps. Poses stay true: with this 58 deg camera the tracker drifts
//              off in a room (greedy on apartment R seed 2: ATE 1.7 m, half the frames lost;
//              with the default 90 deg camera 3 cm), so --poses tracked is asked for apart.
// NotFound for an unknown name.
Status ApplyExploreProfile(const std::string& name, ExploreParams* params);
// The profile names, for usage text.
const char* ExploreProfileNames();

}  // namespace voxplan
