// The OMT multi-robot exploration planner (Dong et al. 2019) as a plugin. Each plan() call is one
// planning pass of plugins/omt over the host's floor raster (task views, OMT assignment, open TSP,
// eq. 5 path, Hermite camera yaw) and replaces every robot's queue: the paper re-plans the whole
// team at every event. Config keys: plugins/README.md.
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "plugins/common/world_input.h"
#include "plugins/omt/algorithms/planner.h"
#include "plugins/planner_cpp.h"

namespace voxplan::planners {
namespace {

constexpr uint32_t kViewColor = 0xffa000ffu;
constexpr uint32_t kPathColor = 0x00c0ffffu;

// Distance each robot has driven, summed over straight moves between plan calls: the host does
// not report it, and what a robot drives between two calls (at most one planning interval) is
// mostly straight.
class DrivenDistance {
 public:
  void Update(std::vector<omt::RobotState>* states) {
    if (last_m_.size() != states->size()) {  // first call
      last_m_.clear();
      for (const omt::RobotState& s : *states) last_m_.push_back(s.position_m);
      driven_m_.assign(states->size(), 0.0);
    }
    for (size_t r = 0; r < states->size(); ++r) {
      driven_m_[r] += ((*states)[r].position_m - last_m_[r]).norm();
      last_m_[r] = (*states)[r].position_m;
      (*states)[r].driven_m = driven_m_[r];
    }
  }

 private:
  std::vector<Eigen::Vector2d> last_m_;
  std::vector<double> driven_m_;
};

class OmtPlanner : public vp::Planner {
 public:
  explicit OmtPlanner(const vp::Config& config) {
    JsonOptions json("omt", config.json);
    options_ = ReadCommonOptions(json);
    omt::PlannerOptions& o = options_.omt;
    o.use_task_views = json.Flag("use_task_views", o.use_task_views);
    o.use_tsp = json.Flag("use_tsp", o.use_tsp);
    o.refine = json.Flag("refine", o.refine);
    o.optimize_paths = json.Flag("optimize_paths", o.optimize_paths);
    o.assign_unimportant_views = json.Flag("assign_unimportant_views", o.assign_unimportant_views);
    o.hand_out_unassigned = json.Flag("hand_out_unassigned", o.hand_out_unassigned);
    o.assignment.delta_m = json.Number("delta_m", o.assignment.delta_m, 0.0, 1e3);
    o.smoothing.eta_cap_m = json.Number("eta_cap_m", o.smoothing.eta_cap_m, 0.05, 1e9);
    o.reach_horizon_s = json.Number("reach_horizon_s", o.reach_horizon_s, 0.0, 1e6);
    o.balance_tolerance_m = json.Number("balance_tolerance_m", o.balance_tolerance_m, 0.0, 1e6);
    o.team_views_per_robot = json.Number("team_views_per_robot", o.team_views_per_robot, 0.0, 1e6);
    o.team_driven_weight = json.Number("team_driven_weight", o.team_driven_weight, 0.0, 1e6);
    json.RejectUnknownKeys();
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    WorldInput in;
    {
      vp::StageTimer timer(world, out, "input");
      in = ReadWorld(world, options_);
    }
    if (in.robots.empty()) return;  // nobody to plan for; not "done" either
    driven_.Update(&in.states);
    const omt::PlannerOptions pass = PassOptions(options_, in);
    settled_.Apply(world, pass, &in);
    out.Diagnostic("settled_cells", double(settled_.size()));
    out.Diagnostic("surface_voxels_ms", in.surface_voxels_ms);

    double host_ms = 0.0;
    omt::GeodesicProvider provider = HostGeodesics(world, in.min_clearance_m, &host_ms);
    if (options_.geodesics == "host") {
      vp::StageTimer timer(world, out, "reach");
      ReadHostReach(world, &in);
      provider.accessible_cells = &in.accessible;
      provider.anchored_robots = in.anchored_robots;
    }
    omt::PlanResult result;
    const double start_s = world.ElapsedS();
    const omt::Status status = omt::PlanOmt(in.raster, &in.clearance, in.states, pass, &result,
                                            options_.geodesics == "host" ? &provider : nullptr);
    out.Diagnostic("omt_ms", (world.ElapsedS() - start_s) * 1e3);
    out.Diagnostic("host_geodesics_ms", host_ms);
    if (!status.ok())
      throw vp::Error(VP_ERROR_PLUGIN, "omt: planning pass failed: " + status.message);
    Report(result, pass.importance_threshold, out);
    out.DebugPoints("omt_views", ViewPointsXyz(result.views, in.map.floor_z_m), kViewColor);
    if (result.terminated) {
      if (result.anchored_robots > 0) {
        out.SetDone(true);
      } else {
        world.Log(VP_LOG_WARNING,
                  "omt: no robot can reach any cell (too little known free space "
                  "around it?); not done, no tasks");
      }
      return;
    }
    vp::StageTimer timer(world, out, "output");
    for (uint32_t r = 0; r < in.robots.size(); ++r) {
      settled_.Sent(r, Emit(in, result, r, out), in.raster.geometry, result.views,
                    result.robots[r].tasks);
    }
  }

 private:
  void Report(const omt::PlanResult& result, double threshold, vp::PlanOutput& out) const {
    int important = 0, unassigned = 0;
    double max_importance = 0.0;
    for (const omt::TaskView& v : result.views) {
      important += v.importance > threshold;
      max_importance = std::max(max_importance, v.importance);
    }
    for (int robot : result.assignment.task_robot) unassigned += robot < 0;
    double length_m = 0.0;
    double geodesic_length_m = 0.0;
    int tasks = 0;
    for (const omt::RobotPlan& p : result.robots) {
      length_m += p.length_m;
      geodesic_length_m += p.geodesic_length_m;
      tasks += int(p.tasks.size());
    }
    out.Diagnostic("views", double(result.extracted_views));  // as the baselines count them
    out.Diagnostic("views_important", important);
    out.Diagnostic("max_importance", max_importance);
    out.Diagnostic("importance_threshold", threshold);
    out.Diagnostic("tasks", tasks);
    out.Diagnostic("views_unassigned", unassigned);
    out.Diagnostic("assignment_energy", result.assignment.cost);
    out.Diagnostic("assignment_iterations", result.assignment.iterations);
    out.Diagnostic("robots_held_back", result.robots_held_back);
    out.Diagnostic("load_exchanges", result.assignment.load_exchanges);
    out.Diagnostic("path_length_m", length_m);
    out.Diagnostic("geodesic_length_m", geodesic_length_m);  // the same paths before eq. 5
    out.Diagnostic("terminated", result.terminated ? 1.0 : 0.0);
    out.Diagnostic("anchored_robots", result.anchored_robots);
  }

  // Robot r's queue becomes its task views in TSP order, with the smoothed path and the camera
  // yaw along it; no task this pass stops the robot (its views went to others). Returns the
  // tasks.
  std::vector<vp_task> Emit(const WorldInput& in, const omt::PlanResult& result, uint32_t r,
                            vp::PlanOutput& out) const {
    out.ReplaceTasks(r);
    const omt::RobotPlan& plan = result.robots[r];
    std::vector<vp_task> tasks;
    if (plan.tasks.empty() || plan.path.empty()) return tasks;
    const vp_robot& robot = in.robots[r];
    std::vector<Eigen::Vector2d> points;
    std::map<int, size_t> task_point;  // view id -> path point standing for it
    for (size_t i = 0; i < plan.path.size(); ++i) {
      points.push_back(plan.path[i].p_m);
      if (plan.path[i].task >= 0) task_point.emplace(plan.path[i].task, i);
    }
    const std::vector<vp_path_point> path = PathWithHeadings(points, robot.theta_rad);
    for (int k : plan.tasks) {
      const omt::TaskView& view = result.views[size_t(k)];
      const auto it = task_point.find(k);
      // The base arrives along the path; the camera joint turns to the view's target.
      const double theta = it != task_point.end() ? path[it->second].theta_rad : view.yaw_rad;
      tasks.push_back(TaskFromView(view, theta, robot, in.vfov_rad, options_.dwell_s));
      out.AddTask(r, tasks.back());
    }
    out.SetPath(r, path);

    // Camera samples at the path points: time from the mode's speed, held for the dwell at views.
    const float z_m = in.map.floor_z_m + robot.camera_height_m;
    const float pitch = std::clamp(0.f, robot.min_pitch_rad, robot.max_pitch_rad);
    const double speed = in.states[r].speed_mps;
    std::vector<vp_camera_sample> samples;
    std::vector<float> xyz;
    double t_s = 0.0;
    for (size_t i = 0; i < plan.path.size(); ++i) {
      if (i > 0) t_s += (plan.path[i].p_m - plan.path[i - 1].p_m).norm() / speed;
      const vp_camera_sample s{
          float(t_s), {path[i].x_m, path[i].y_m, z_m}, float(plan.yaw_rad[i]), pitch};
      samples.push_back(s);
      if (plan.path[i].task >= 0 && options_.dwell_s > 0.0) {
        t_s += options_.dwell_s;
        samples.push_back(s);
        samples.back().t_s = float(t_s);
      }
      xyz.insert(xyz.end(), {path[i].x_m, path[i].y_m, in.map.floor_z_m});
    }
    out.SetCameraTrajectory(r, samples);
    out.DebugPolyline("omt_paths", xyz, kPathColor);
    return tasks;
  }

  CommonOptions options_;
  DrivenDistance driven_;  // across calls, for load balance
  SettledCells settled_;   // cells looked at in vain, across calls
};

}  // namespace
}  // namespace voxplan::planners

VP_PLANNER_EXPORT(voxplan::planners::OmtPlanner, "omt", "1.0.0")
