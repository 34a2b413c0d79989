// What the two baselines of Dong 2019 §4 share, GRD (greedy) and SEG (Voronoi segmentation):
// the same task views the OMT pass extracts (only assignment and ordering differ, so comparisons
// are fair), geodesic distances from each robot by the host's own fields (what it validates
// tasks with), which robots a call plans, and the output of a robot's chosen views.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "plugins/common/world_input.h"

namespace voxplan::planners {

struct BaselineWorld {
  WorldInput input;
  std::vector<omt::TaskView> views;  // accessible task views (omt::ExtractAccessibleViews)
  std::vector<uint8_t> important;    // per view: importance above the threshold
  double threshold = 0.0;            // the importance threshold for this world's camera
  // robot_view_m[r][v]: host geodesic distance from robot r to view v, +inf when unreachable.
  std::vector<std::vector<float>> robot_view_m;
  bool any_important_reachable = false;
  // Robots joined to the internal geodesic grid (omt::PlanResult::anchored_robots).
  int anchored_robots = 0;
  // No view worth it is left for anyone; false while no robot could be judged at all.
  bool Done() const { return !any_important_reachable && anchored_robots > 0; }
};
// settled: the planner's memory of cells looked at in vain (updated here).
BaselineWorld ReadBaselineWorld(const vp::WorldView& world, const CommonOptions& options,
                                SettledCells* settled);

// Host geodesic distance from a point to every view (+inf when unreachable).
std::vector<float> DistancesToViews(const vp::WorldView& world, const BaselineWorld& b, float x_m,
                                    float y_m);

// The robots this call gives tasks: on a robot-idle or task-failed event only the event robot and
// any other idle robot (executing robots keep their queues); on start and interval all of them.
std::vector<uint8_t> RobotsToPlan(const vp::WorldView& world, const BaselineWorld& b);

// Views robot r may take (1) by importance, minus the failed task on a task-failed event of r.
std::vector<uint8_t> AllowedViews(const vp::WorldView& world, const BaselineWorld& b, uint32_t r,
                                  double same_radius_m);

// Whether a view repeats a task: the same target cell (the task's tag) or within radius_m of it.
bool SameView(const omt::TaskView& view, const vp_task& task, double radius_m);

// Nearest view by dist among allowed ones (ties to the lower index); -1 when none is reachable.
int NearestView(const std::vector<float>& dist, const std::vector<uint8_t>& allowed);

// Replaces robot r's queue by the views in order, with the host's shortest path through them; a
// view the path cannot reach is left out, and with none r stops. Tells `settled` what r was sent.
void EmitViews(const vp::WorldView& world, vp::PlanOutput& out, const BaselineWorld& b, uint32_t r,
               const std::vector<int>& view_ids, double dwell_s, const std::string& layer,
               SettledCells* settled);

// Diagnostics both baselines report: views, views_important, tasks, settled_cells.
void ReportViews(vp::PlanOutput& out, const BaselineWorld& b, int tasks,
                 const SettledCells& settled);

// The start of a baseline pass: reads the world (timed as stage "views"), draws its views in
// `layer`; when no robot can reach an important view, reports that (done when nothing is left)
// and returns false: the pass ends there.
bool BeginPass(const vp::WorldView& world, vp::PlanOutput& out, const CommonOptions& options,
               SettledCells* settled, const std::string& layer, BaselineWorld* b);

}  // namespace voxplan::planners
