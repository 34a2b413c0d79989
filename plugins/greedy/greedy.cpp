// GRD, the greedy baseline of Dong et al. 2019 §4, as a plugin, over the OMT pass's task views
// with importance above the threshold. Three policies ("policy"):
//  - "best_view" (default; the "each robot takes the best task view, nearest first"):
//    the views, best first, each go to the nearest robot that holds none yet, so the whole team
//    is dispatched to the best views at once (the paper's account of GRD: balanced, long drives).
//  - "best": the views, best first, are dealt out to the robot with the fewest so far (nearest
//    among those), and each planned robot takes the closest of its share: the paper's "assign
//    greedily, then the closest of a robot's tasks" with every view assigned, a stronger baseline.
//  - "nearest": each robot this call plans (robot index order) takes the nearest (geodesic) view
//    that no other robot holds, a nearest-frontier baseline.
// One task per robot per call either way; it plans again when the robot turns idle. Done when no
// robot can reach such a view.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "plugins/common/baseline.h"
#include "plugins/planner_cpp.h"

namespace voxplan::planners {
namespace {

class GreedyPlanner : public vp::Planner {
 public:
  explicit GreedyPlanner(const vp::Config& config) {
    JsonOptions json("greedy", config.json);
    options_ = ReadCommonOptions(json);
    claim_radius_m_ = json.Number("claim_radius_m", claim_radius_m_, 0.0, 100.0);
    const std::string policy = json.Choice("policy", "best_view", {"best_view", "best", "nearest"});
    policy_ = policy == "best_view" ? Policy::kBestView
              : policy == "best"    ? Policy::kBest
                                    : Policy::kNearest;
    json.RejectUnknownKeys();
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    BaselineWorld b;
    if (!BeginPass(world, out, options_, &settled_, "greedy_views", &b)) return;
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
    const int tasks = policy_ == Policy::kNearest
                          ? PlanNearest(world, out, b, planned, claimed)
                          : PlanBest(world, out, b, planned, claimed, policy_ == Policy::kBestView);
    ReportViews(out, b, tasks, settled_);
  }

 private:
  int PlanNearest(const vp::WorldView& world, vp::PlanOutput& out, const BaselineWorld& b,
                  const std::vector<uint8_t>& planned, std::vector<uint8_t> claimed) {
    int tasks = 0;
    for (uint32_t r = 0; r < planned.size(); ++r) {
      if (!planned[r]) continue;
      std::vector<uint8_t> allowed = AllowedViews(world, b, r, claim_radius_m_);
      for (size_t v = 0; v < allowed.size(); ++v) allowed[v] &= !claimed[v];
      const int k = NearestView(b.robot_view_m[r], allowed);
      if (k < 0) {
        // Nothing left for it: stop rather than finish a stale task.
        EmitViews(world, out, b, r, {}, options_.dwell_s, "greedy_paths", &settled_);
        continue;
      }
      claimed[size_t(k)] = 1;
      EmitViews(world, out, b, r, {k}, options_.dwell_s, "greedy_paths", &settled_);
      ++tasks;
    }
    return tasks;
  }

  // "best" and, with `one_each`, "best_view" (a robot holding a view takes no more).
  // The assignment runs over every robot, not only the planned ones, so that a robot's share of
  // the best views does not depend on which event triggered the call. A robot keeping its queue
  // (not planned) starts with its queued tasks counted, so an idle robot is served first instead
  // of losing the best remaining view to a busy one; the views in those queues are out of the
  // pool (claimed), and what a busy robot is assigned here is dropped (it keeps its queue).
  int PlanBest(const vp::WorldView& world, vp::PlanOutput& out, const BaselineWorld& b,
               const std::vector<uint8_t>& planned, const std::vector<uint8_t>& claimed,
               bool one_each) {
    const size_t robots = planned.size();
    std::vector<std::vector<uint8_t>> allowed(robots);  // per robot: important, not just failed
    std::vector<size_t> count(robots, 0);
    for (uint32_t r = 0; r < robots; ++r) {
      allowed[r] = AllowedViews(world, b, r, claim_radius_m_);
      if (!planned[r]) count[r] = world.Queue(r).size();
    }
    // Best first; stable, so equal importance keeps the lower index first.
    std::vector<size_t> order(b.views.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
      return b.views[x].importance > b.views[y].importance;
    });
    std::vector<std::vector<uint8_t>> assigned(robots, std::vector<uint8_t>(b.views.size(), 0));
    for (const size_t v : order) {
      if (claimed[v]) continue;
      int to = -1;
      for (uint32_t r = 0; r < robots; ++r) {
        if (!allowed[r][v] || !std::isfinite(b.robot_view_m[r][v])) continue;
        const size_t t = size_t(to);
        if (to < 0 || count[r] < count[t] ||
            (count[r] == count[t] && b.robot_view_m[r][v] < b.robot_view_m[t][v])) {
          to = int(r);
        }
      }
      if (to < 0) continue;                             // nobody may take it
      if (one_each && count[size_t(to)] > 0) continue;  // robots that may take it hold one
      assigned[size_t(to)][v] = 1;
      ++count[size_t(to)];
    }
    int tasks = 0;
    for (uint32_t r = 0; r < robots; ++r) {
      if (!planned[r]) continue;
      const int k = NearestView(b.robot_view_m[r], assigned[r]);
      if (k < 0) {
        // No view of its own: stop rather than finish a stale task.
        EmitViews(world, out, b, r, {}, options_.dwell_s, "greedy_paths", &settled_);
        continue;
      }
      EmitViews(world, out, b, r, {k}, options_.dwell_s, "greedy_paths", &settled_);
      ++tasks;
    }
    return tasks;
  }

  CommonOptions options_;
  SettledCells settled_;         // cells looked at in vain, across calls
  double claim_radius_m_ = 0.5;  // a view this close to another robot's queued task is its
  enum class Policy { kBestView, kBest, kNearest };  // "policy", see the top of the file
  Policy policy_ = Policy::kBestView;
};

}  // namespace
}  // namespace voxplan::planners

VP_PLANNER_EXPORT(voxplan::planners::GreedyPlanner, "greedy", "1.0.0")
