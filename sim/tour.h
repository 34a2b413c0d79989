#pragma once
// A deterministic camera tour that sees every room of a world, planned on its true FloorPlan:
//  1. reachable cells: free cells where the robot's footprint fits, in the connected piece that
//     holds the most of them (or the start's piece when a start is given);
//  2. viewpoints: one per room (the reachable cell of the room nearest its centre, among those
//     with the most clearance), then a greedy cover: the candidate that sees the most reachable
//     cells not yet seen (within view_range_m, straight line of sight over the plan) is added
//     until min_coverage is reached or no candidate adds min_gain_cells;
//  3. order: nearest neighbour from the first viewpoint, then 2-opt, on grid path lengths;
//  4. motion: the robot drives collision-free grid paths (shortcut where the footprint passes)
//     with the camera looking along the path, and at each viewpoint spins the camera 360° once
//     per entry of spin_pitches_deg (level; `sim tour` adds up and down: a camera at robot
//     height sees neither the ceiling nor the floor near it when level), tilting between them.
// Frames are taken every frame_step_m of travel and every frame_step_deg of turning or tilting;
// their timestamps are the robot's simulation clock.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/status.h"
#include "sim/floor_plan.h"
#include "sim/robot.h"
#include "sim/world.h"

namespace voxplan {

struct TourParams {
  RobotParams robot;
  RobotMode mode = RobotMode::kExplorer;
  // A viewpoint "sees" reachable cells this close, in line of sight. Well inside a 3 m fusion
  // range: from 1.2 m up the floor and a 2.5 m ceiling are in range only ~2.7 m out, and walls
  // behind furniture need nearer views. In the AWS house 2 m sees 59 % of the surface, 3 m 51 %.
  float view_range_m = 2.0f;
  float candidate_spacing_m = 0.4f;  // viewpoint candidates on this grid of reachable cells
  float min_coverage = 0.97f;        // fraction of reachable cells seen before the cover stops
  int min_gain_cells = 20;
  float frame_step_m = 0.1f;
  float frame_step_deg = 10.0f;
  float camera_pitch_deg = 0.0f;  // pitch while driving; positive looks up
  // Pitch of each 360° spin at a viewpoint, in order; at least one. Level only by default (what a
  // robot without a pitch joint sees); `voxplan sim tour` asks for {0, 45, -45}: with a 49°
  // vertical field of view (fx 525 at 480 rows) that leaves no gap from -70° to +70°, so the
  // ceiling and the floor near the robot are seen too.
  std::vector<float> spin_pitches_deg = {0.0f};
  std::optional<Eigen::Vector2f> start_W;  // default: the first viewpoint
  int two_opt_rounds = 50;

  Status Validate() const;
};

struct Tour {
  std::vector<Eigen::Vector2f> viewpoints_W;  // in visiting order
  std::vector<int> viewpoint_room;            // room index per viewpoint, -1 for cover ones
  std::vector<double> timestamps_s;           // one per frame, strictly increasing
  std::vector<Pose3f> T_W_C;                  // one per frame, OpenCV camera axes
  double length_m = 0.0;
  double duration_s = 0.0;
  size_t reachable_cells = 0;
  double coverage = 0.0;               // fraction of reachable cells seen from some viewpoint
  std::vector<int> unreachable_rooms;  // room indices with no reachable cell (not visited)
};

// `rooms` may be empty (loaded scenes): the cover alone then picks the viewpoints.
Result<Tour> PlanTour(const FloorPlan& plan, const std::vector<Room>& rooms,
                      const TourParams& params = {});

}  // namespace voxplan
