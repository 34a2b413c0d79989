// GRD, the greedy baseline of Dong et al. 2019 §4, as a plugin: over the OMT pass's task views,
// each robot this call plans (robot index order) takes the nearest (geodesic) view with
// importance above the threshold that no other robot holds; one task per robot per call, and it
// plans again when the robot turns idle. Done when no robot can reach such a view.
#include <string>
#include <vector>

#include "plugins/baselines/baseline.h"
#include "plugins/planner_cpp.h"

namespace voxplan::planners {
namespace {

class GreedyPlanner : public vp::Planner {
 public:
  explicit GreedyPlanner(const vp::Config& config) {
    JsonOptions json("greedy", config.json);
    options_ = ReadCommonOptions(json);
    claim_radius_m_ = json.Number("claim_radius_m", claim_radius_m_, 0.0, 100.0);
    json.RejectUnknownKeys();
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    BaselineWorld b;
    {
      vp::StageTimer timer(world, out, "views");
      b = ReadBaselineWorld(world, options_, &settled_);
    }
    out.DebugPoints("greedy_views", ViewPointsXyz(b.views, b.input.map.floor_z_m), 0xffa000ffu);
    if (!b.any_important_reachable) {
      ReportViews(out, b, 0);
      out.Diagnostic("settled_cells", double(settled_.size()));
      out.SetDone(b.Done());
      return;
    }
    const std::vector<uint8_t> planned = RobotsToPlan(world, b);
    // Views another robot still holds in its queue are taken.
    std::vector<uint8_t> claimed(b.views.size(), 0);
    for (uint32_t r = 0; r < planned.size(); ++r) {
      if (planned[r]) continue;
      for (const vp_task& t : world.Queue(r)) {
        for (size_t v = 0; v < b.views.size(); ++v) {
          claimed[v] |= SameView(b.views[v], t, claim_radius_m_);
        }
      }
    }
    int tasks = 0;
    for (uint32_t r = 0; r < planned.size(); ++r) {
      if (!planned[r]) continue;
      std::vector<uint8_t> allowed = AllowedViews(world, b, r, claim_radius_m_);
      for (size_t v = 0; v < allowed.size(); ++v) allowed[v] &= !claimed[v];
      const int k = NearestView(b.robot_view_m[r], allowed);
      if (k < 0) {
        out.ReplaceTasks(r);  // nothing left for it: stop rather than finish a stale task
        continue;
      }
      claimed[size_t(k)] = 1;
      EmitViews(world, out, b, r, {k}, options_.dwell_s, "greedy_paths");
      ++tasks;
    }
    ReportViews(out, b, tasks);
    out.Diagnostic("settled_cells", double(settled_.size()));
  }

 private:
  CommonOptions options_;
  SettledCells settled_;         // cells looked at in vain, across calls
  double claim_radius_m_ = 0.5;  // a view this close to another robot's queued task is its
};

}  // namespace
}  // namespace voxplan::planners

VP_PLANNER_EXPORT(voxplan::planners::GreedyPlanner, "greedy", "1.0.0")
