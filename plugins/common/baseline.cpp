#include "plugins/common/baseline.h"

#include <cmath>
#include <limits>
#include <utility>

namespace voxplan::planners {

BaselineWorld ReadBaselineWorld(const vp::WorldView& world, const CommonOptions& options,
                                SettledCells* settled) {
  BaselineWorld b;
  b.input = ReadWorld(world, options);
  if (b.input.robots.empty()) return b;
  const omt::PlannerOptions pass = PassOptions(options, b.input);
  settled->Apply(world, pass, &b.input);
  ReadHostReach(world, &b.input);
  omt::ViewSet set =
      omt::ExtractAccessibleViews(b.input.raster, b.input.clearance, b.input.states, pass,
                                  &b.input.accessible, b.input.anchored_robots);
  b.views = std::move(set.views);
  b.anchored_robots = set.anchored_robots;
  b.threshold = pass.importance_threshold;
  for (const omt::TaskView& v : b.views) {
    b.important.push_back(v.importance > b.threshold ? 1 : 0);
  }
  for (const std::span<const float> field : b.input.robot_fields) {
    b.robot_view_m.emplace_back();
    for (const omt::TaskView& v : b.views) {
      b.robot_view_m.back().push_back(v.cell >= 0 && size_t(v.cell) < field.size()
                                          ? field[size_t(v.cell)]
                                          : std::numeric_limits<float>::infinity());
    }
    for (size_t v = 0; v < b.views.size(); ++v) {
      if (b.important[v] && std::isfinite(b.robot_view_m.back()[v])) {
        b.any_important_reachable = true;
      }
    }
  }
  return b;
}

std::vector<float> DistancesToViews(const vp::WorldView& world, const BaselineWorld& b, float x_m,
                                    float y_m) {
  const std::span<const float> field = world.GeodesicField(x_m, y_m, b.input.min_clearance_m);
  std::vector<float> d;
  for (const omt::TaskView& v : b.views) {
    d.push_back(v.cell >= 0 && size_t(v.cell) < field.size()
                    ? field[size_t(v.cell)]
                    : std::numeric_limits<float>::infinity());
  }
  return d;
}

std::vector<uint8_t> RobotsToPlan(const vp::WorldView& world, const BaselineWorld& b) {
  const size_t count = b.input.robots.size();
  const int32_t event_robot = world.call().event_robot;
  const bool robot_event =
      (world.event() == VP_EVENT_ROBOT_IDLE || world.event() == VP_EVENT_TASK_FAILED) &&
      event_robot >= 0 && size_t(event_robot) < count;
  std::vector<uint8_t> plan(count, robot_event ? 0 : 1);
  if (robot_event) {
    for (size_t r = 0; r < count; ++r) {
      plan[r] = int32_t(r) == event_robot || b.input.robots[r].status == VP_ROBOT_IDLE;
    }
  }
  return plan;
}

bool SameView(const omt::TaskView& view, const vp_task& task, double radius_m) {
  if (view.target_cell >= 0 && uint32_t(view.target_cell) == task.tag) return true;
  return std::hypot(view.position_m.x() - task.x_m, view.position_m.y() - task.y_m) <= radius_m;
}

std::vector<uint8_t> AllowedViews(const vp::WorldView& world, const BaselineWorld& b, uint32_t r,
                                  double same_radius_m) {
  std::vector<uint8_t> allowed = b.important;
  if (world.event() == VP_EVENT_TASK_FAILED && world.call().event_robot == int32_t(r)) {
    for (size_t v = 0; v < b.views.size(); ++v) {
      if (SameView(b.views[v], world.call().failed_task, same_radius_m)) allowed[v] = 0;
    }
  }
  return allowed;
}

int NearestView(const std::vector<float>& dist, const std::vector<uint8_t>& allowed) {
  int best = -1;
  for (size_t v = 0; v < dist.size(); ++v) {
    if (!allowed[v] || !std::isfinite(dist[v])) continue;
    if (best < 0 || dist[v] < dist[size_t(best)]) best = int(v);
  }
  return best;
}

void EmitViews(const vp::WorldView& world, vp::PlanOutput& out, const BaselineWorld& b, uint32_t r,
               const std::vector<int>& view_ids, double dwell_s, const std::string& layer,
               SettledCells* settled) {
  out.ReplaceTasks(r);
  const vp_robot& robot = b.input.robots[r];
  std::vector<Eigen::Vector2d> points{{robot.x_m, robot.y_m}};
  std::vector<std::pair<int, size_t>> arrivals;  // (view, path point where the robot arrives)
  for (int k : view_ids) {
    const omt::TaskView& view = b.views[size_t(k)];
    const Eigen::Vector2d& from = points.back();
    const auto leg =
        world.ShortestPath(float(from.x()), float(from.y()), float(view.position_m.x()),
                           float(view.position_m.y()), b.input.min_clearance_m);
    if (!leg) continue;
    for (size_t i = 2; i + 1 < leg->size(); i += 2) points.emplace_back((*leg)[i], (*leg)[i + 1]);
    arrivals.emplace_back(k, points.size() - 1);
  }
  const std::vector<vp_path_point> path = PathWithHeadings(points, robot.theta_rad);
  std::vector<vp_task> tasks;
  for (const auto& [k, i] : arrivals) {
    tasks.push_back(
        TaskFromView(b.views[size_t(k)], path[i].theta_rad, robot, b.input.vfov_rad, dwell_s));
    out.AddTask(r, tasks.back());
  }
  std::vector<int> taken;
  for (const auto& [k, i] : arrivals) taken.push_back(k);
  settled->Sent(r, tasks, b.input.raster.geometry, b.views, taken);
  if (arrivals.empty()) return;
  if (path.size() < 2) return;  // already standing at its one view
  out.SetPath(r, path);
  std::vector<float> xyz;
  for (const vp_path_point& p : path) xyz.insert(xyz.end(), {p.x_m, p.y_m, b.input.map.floor_z_m});
  out.DebugPolyline(layer, xyz, 0x40ff40ffu);
}

void ReportViews(vp::PlanOutput& out, const BaselineWorld& b, int tasks,
                 const SettledCells& settled) {
  int important = 0;
  for (uint8_t i : b.important) important += i;
  out.Diagnostic("views", double(b.views.size()));
  out.Diagnostic("views_important", important);
  out.Diagnostic("tasks", tasks);
  out.Diagnostic("settled_cells", double(settled.size()));
}

bool BeginPass(const vp::WorldView& world, vp::PlanOutput& out, const CommonOptions& options,
               SettledCells* settled, const std::string& layer, BaselineWorld* b) {
  {
    vp::StageTimer timer(world, out, "views");
    *b = ReadBaselineWorld(world, options, settled);
  }
  out.DebugPoints(layer, ViewPointsXyz(b->views, b->input.map.floor_z_m), 0xffa000ffu);
  if (b->any_important_reachable) return true;
  ReportViews(out, *b, 0, *settled);
  out.SetDone(b->Done());
  return false;
}

}  // namespace voxplan::planners
