// One OMT planning pass (Dong et al. 2019, Fig. 2): task views (§3.2) → OMT assignment
// (§3.3–3.4) → per-robot open TSP, eq. 5 path optimisation and camera yaw (§3.5). Flags
// reproduce the paper's ablations (Table 1).
#pragma once

#include <functional>
#include <vector>

#include "plugins/omt/assignment.h"
#include "plugins/omt/geodesic.h"
#include "plugins/omt/smoothing.h"
#include "plugins/omt/task_views.h"
#include "plugins/omt/tsp.h"
#include "plugins/omt/types.h"

namespace voxplan::omt {

struct RobotState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;    // current camera yaw
  double speed_mps = 0.3;  // §4
};

struct PlannerOptions {
  int kappa = 6;  // κ: at most κR task views per pass
  double robot_radius_m = 0.18;
  double geodesic_cell_m = 0.2;       // node spacing of the geodesic grid
  double importance_threshold = 1.5;  // §4 termination
  TaskViewParams views;  // max_views and robot_radius_m are set from kappa and robot_radius_m
  AssignmentParams assignment;  // refine is set from the flag below
  TspParams tsp;
  SmoothingParams smoothing;  // min_clearance_m is set to robot_radius_m
  // Ablations of Table 1 (false reproduces NoTV, NoTSP, NoRefine, NoPO).
  bool use_task_views = true;
  bool use_tsp = true;
  bool refine = true;
  bool optimize_paths = true;
  int num_threads =
      2;  // geodesics and per-robot paths run in parallel; results do not depend on it
};

struct RobotPlan {
  std::vector<int> tasks;       // task-view indices in visiting order
  std::vector<PathPoint> path;  // starts at the robot
  std::vector<double> yaw_rad;  // camera yaw per path point
  double length_m = 0.0;
};

struct PlanResult {
  std::vector<TaskView> views;  // accessible task views (the assignment's tasks)
  Assignment assignment;
  std::vector<RobotPlan> robots;  // one per input robot; empty plan = no task this pass
  bool terminated = false;        // no accessible view with importance above the threshold
  // Robots joined to the internal geodesic grid. With none, no view can be accessible and
  // `terminated` says nothing about the scene (e.g. too little known free space around them).
  int anchored_robots = 0;
};

// External geodesics (e.g. the host's distance_matrix / shortest_path queries) to use instead
// of the internal grid. Either member may be empty. Called only from PlanOmt's thread.
struct GeodesicProvider {
  // Distances (metres, +inf when unreachable) between all points, points.size() square.
  std::function<bool(const std::vector<Eigen::Vector2d>& points, DistanceMatrix* out)>
      distance_matrix;
  // Collision-free polyline from a to b inclusive; false when there is none.
  std::function<bool(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                     std::vector<Eigen::Vector2d>* out)>
      shortest_path;
};

// The accessible task views of one pass (§3.2, at most κR) and the internal geodesic grid they
// were checked on: PlanOmt's first stage, exposed so the baselines (GRD, SEG of §4) plan over
// exactly the same views. kappa, robot_radius_m, views and use_task_views apply as in PlanOmt.
struct ViewSet {
  GeodesicGrid grid;
  std::vector<Anchor> anchors;          // one per robot, then one per view
  std::vector<std::uint8_t> reachable;  // grid nodes some robot reaches
  std::vector<TaskView> views;          // only views whose anchor is reachable
};
ViewSet ExtractAccessibleViews(const OccupancyRaster& raster, const ClearanceRaster& clearance,
                               const std::vector<RobotState>& robots,
                               const PlannerOptions& options);

// clearance may be null: it is then computed from the raster (unknown counts as obstacle).
// Views are still restricted to cells the internal grid reaches from some robot.
Status PlanOmt(const OccupancyRaster& raster, const ClearanceRaster* clearance,
               const std::vector<RobotState>& robots, const PlannerOptions& options,
               PlanResult* result, const GeodesicProvider* provider = nullptr);

}  // namespace voxplan::omt
