// SEG, the segmentation baseline of Dong et al. 2019 §4, as a plugin: the OMT pass's task views
// are split by a geodesic Voronoi partition of the robots (each view goes to the robot nearest
// to it, ties to the lower index), and each robot this call plans visits its own region nearest
// first, tasks_per_call views at a time. Done when no robot can reach a view above the threshold.
#include <cmath>
#include <string>
#include <vector>

#include "plugins/common/baseline.h"
#include "plugins/planner_cpp.h"

namespace voxplan::planners {
namespace {

class VoronoiPlanner : public vp::Planner {
 public:
  explicit VoronoiPlanner(const vp::Config& config) {
    JsonOptions json("voronoi", config.json);
    options_ = ReadCommonOptions(json);
    tasks_per_call_ = json.Integer("tasks_per_call", tasks_per_call_, 1, 1000);
    failed_radius_m_ = json.Number("failed_radius_m", failed_radius_m_, 0.0, 100.0);
    json.RejectUnknownKeys();
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    BaselineWorld b;
    if (!BeginPass(world, out, options_, &settled_, "voronoi_views", &b)) return;
    // The partition: every robot's region, also of robots this call leaves alone.
    const size_t robots = b.input.robots.size();
    std::vector<int> owner(b.views.size(), -1);
    for (size_t v = 0; v < b.views.size(); ++v) {
      for (size_t r = 0; r < robots; ++r) {
        const float d = b.robot_view_m[r][v];
        if (std::isfinite(d) && (owner[v] < 0 || d < b.robot_view_m[size_t(owner[v])][v])) {
          owner[v] = int(r);
        }
      }
    }
    const std::vector<uint8_t> planned = RobotsToPlan(world, b);
    int tasks = 0;
    for (uint32_t r = 0; r < robots; ++r) {
      int region = 0;  // the views above the threshold it owns
      for (size_t v = 0; v < owner.size(); ++v) region += owner[v] == int(r) && b.important[v];
      out.Diagnostic("region_views_" + std::to_string(r), region);
      if (!planned[r]) continue;
      std::vector<uint8_t> allowed = AllowedViews(world, b, r, failed_radius_m_);
      for (size_t v = 0; v < allowed.size(); ++v) allowed[v] &= owner[v] == int(r);
      // Nearest first: from the robot, then from each chosen view.
      std::vector<int> chosen;
      std::vector<float> dist = b.robot_view_m[r];
      while (int(chosen.size()) < tasks_per_call_) {
        const int k = NearestView(dist, allowed);
        if (k < 0) break;
        chosen.push_back(k);
        allowed[size_t(k)] = 0;
        if (int(chosen.size()) < tasks_per_call_) {
          const omt::TaskView& at = b.views[size_t(k)];
          dist = DistancesToViews(world, b, float(at.position_m.x()), float(at.position_m.y()));
        }
      }
      if (chosen.empty()) {
        // Its region is explored: stop rather than finish a stale task.
        EmitViews(world, out, b, r, {}, options_.dwell_s, "voronoi_paths", &settled_);
        continue;
      }
      EmitViews(world, out, b, r, chosen, options_.dwell_s, "voronoi_paths", &settled_);
      tasks += int(chosen.size());
    }
    ReportViews(out, b, tasks, settled_);
  }

 private:
  CommonOptions options_;
  SettledCells settled_;  // cells looked at in vain, across calls
  int tasks_per_call_ = 1;
  double failed_radius_m_ = 0.5;  // views this close to a failed task are not retried at once
};

}  // namespace
}  // namespace voxplan::planners

VP_PLANNER_EXPORT(voxplan::planners::VoronoiPlanner, "voronoi", "1.0.0")
