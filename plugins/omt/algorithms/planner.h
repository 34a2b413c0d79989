// One OMT planning pass (Dong et al. 2019, Fig. 2): task views (§3.2) → OMT assignment
// (§3.3–3.4) → per-robot open TSP, eq. 5 path optimisation and camera yaw (§3.5). Flags
// reproduce the paper's ablations (Table 1).
#pragma once

#include <functional>
#include <vector>

#include "plugins/omt/algorithms/assignment.h"
#include "plugins/omt/algorithms/geodesic.h"
#include "plugins/omt/algorithms/smoothing.h"
#include "plugins/omt/algorithms/task_views.h"
#include "plugins/omt/algorithms/tsp.h"
#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

struct RobotState {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;    // current camera yaw
  double speed_mps = 0.3;  // §4
  double driven_m = 0.0;   // distance driven so far (load balance, BalanceLoads)
};

struct PlannerOptions {
  int kappa = 6;  // κ: at most κR task views per pass
  double robot_radius_m = 0.18;
  double geodesic_cell_m = 0.2;  // node spacing of the internal geodesic grid
  // Smoothed paths keep robot_radius_m + path_margin_m from obstacles (the views keep theirs).
  double path_margin_m = 0.0;
  double snap_radius_m = 0.5;  // a robot off accessible cells starts from the nearest within this
  // §4 termination, for the paper's sensor (SensorParams' defaults); a caller whose views see
  // more or less scales it by ViewCapacity (plugins/common PassOptions).
  double importance_threshold = 1.5;
  TaskViewParams views;  // max_views and robot_radius_m are set from kappa and robot_radius_m
  AssignmentParams assignment;  // refine is set from the flag below
  TspParams tsp;
  SmoothingParams smoothing;  // min_clearance_m is set to robot_radius_m + path_margin_m
  // Ablations of Table 1 (false reproduces NoTV, NoTSP, NoRefine, NoPO).
  bool use_task_views = true;
  bool use_tsp = true;
  bool refine = true;
  bool optimize_paths = true;
  // Views at or below importance_threshold go into the assignment too (the earlier behaviour);
  // by default they are dropped while a better one remains, as GRD and SEG drop them.
  bool assign_unimportant_views = false;
  // A robot the assignment leaves without a task takes the nearest cluster it left unassigned.
  bool hand_out_unassigned = true;
  // A robot more than reach_horizon_s of driving farther from the work than the nearest robot
  // gets no capacity and no handed-out cluster this pass: it stays still (ReachCapacities).
  // 0: C_r = K / R for every robot (§3.4).
  double reach_horizon_s = 15.0;
  // With K views, at most ⌈K / team_views_per_robot⌉ robots get capacity, those with the least
  // team_driven_weight × distance driven + distance to the nearest view; the others stay still
  // (TeamCapacities). 0: every robot.
  double team_views_per_robot = 3.0;
  double team_driven_weight = 3.0;
  // Task-set exchanges for load balance (BalanceLoads) that may cost eq. 4 this much; 0: none.
  double balance_tolerance_m = 1.0;
  int num_threads =
      2;  // geodesics and per-robot paths run in parallel; results do not depend on it
};

struct RobotPlan {
  std::vector<int> tasks;       // task-view indices in visiting order
  std::vector<PathPoint> path;  // starts at the robot
  std::vector<double> yaw_rad;  // camera yaw per path point
  double length_m = 0.0;
  double geodesic_length_m = 0.0;  // of the path before eq. 5 (equal to length_m under NoPO)
};

struct PlanResult {
  std::vector<TaskView> views;  // accessible task views (the assignment's tasks)
  int extracted_views = 0;      // views before those not above the threshold were dropped
  Assignment assignment;
  std::vector<RobotPlan> robots;  // one per input robot; empty plan = no task this pass
  bool terminated = false;        // no accessible view with importance above the threshold
  // Robots standing on (or within snap_radius_m of) a cell they can move from. With none, no
  // view can be accessible and `terminated` says nothing about the scene (e.g. too little known
  // free space around them).
  int anchored_robots = 0;
  int robots_held_back = 0;  // robots given no capacity (Reach / TeamCapacities): they stay still
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
  // Raster cells some robot reaches by these geodesics (one byte per cell, non-zero =
  // reachable), and how many robots reach any cell: where views may stand. Null: the planner's
  // own flood fill (AccessibleCells).
  const std::vector<std::uint8_t>* accessible_cells = nullptr;
  int anchored_robots = 0;
};

// Raster cells a robot of radius robot_radius_m can drive to: free cells with clearance >=
// robot_radius_m, 8-connected without cutting corners, flooded from each robot's cell (or, when
// it is not such a cell, the nearest one within snap_radius_m, as the host snaps robots standing
// on cells their camera never saw). *anchored counts the robots that seeded the flood. This is
// the host's own traversability rule at the raster's full resolution: a coarser grid would shut
// doorways barely wider than the robot.
std::vector<std::uint8_t> AccessibleCells(const OccupancyRaster& raster,
                                          const ClearanceRaster& clearance,
                                          const std::vector<RobotState>& robots,
                                          double robot_radius_m, double snap_radius_m = 0.5,
                                          int* anchored = nullptr);

// The accessible task views of one pass (§3.2, at most κR): PlanOmt's first stage, exposed so
// the baselines (GRD, SEG of §4) plan over exactly the same views. kappa, robot_radius_m, views
// and use_task_views apply as in PlanOmt. Views stand on accessible cells: accessible_cells when
// given (e.g. the host's geodesic fields), else AccessibleCells.
struct ViewSet {
  std::vector<std::uint8_t> accessible;  // raster cells some robot reaches
  int anchored_robots = 0;               // robots that reach any cell
  std::vector<TaskView> views;
};
ViewSet ExtractAccessibleViews(const OccupancyRaster& raster, const ClearanceRaster& clearance,
                               const std::vector<RobotState>& robots, const PlannerOptions& options,
                               const std::vector<std::uint8_t>* accessible_cells = nullptr,
                               int anchored_robots = 0);

// clearance may be null: it is then computed from the raster (unknown counts as obstacle).
// Without a provider's distances, geodesics run on the internal grid (geodesic_cell_m); a view
// the grid cannot join (a narrow passage between two coarse nodes) is then unreachable.
Status PlanOmt(const OccupancyRaster& raster, const ClearanceRaster* clearance,
               const std::vector<RobotState>& robots, const PlannerOptions& options,
               PlanResult* result, const GeodesicProvider* provider = nullptr);

}  // namespace voxplan::omt
