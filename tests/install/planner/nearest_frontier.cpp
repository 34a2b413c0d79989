// Sends every idle robot to the geodesically nearest reachable frontier cell of the floor map
// that no other robot was just sent to; done once no robot has one left. An out-of-tree planner:
// only planner_cpp.h, as an installed voxplan provides it.
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "plugins/planner_cpp.h"

namespace {

constexpr float kClaimRadiusM = 1.0f;  // targets of two robots at least this far apart
constexpr float kMinTravelM = 0.5f;    // a frontier under the robot shows nothing new

class NearestFrontier : public vp::Planner {
 public:
  explicit NearestFrontier(const vp::Config&) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    const vp::FloorView floor = world.Floor();
    std::vector<std::pair<float, float>> claimed;
    bool any_target = false;
    for (uint32_t r = 0; r < world.RobotCount(); ++r) {
      const vp_robot robot = world.Robot(r);
      if (robot.status != VP_ROBOT_IDLE) {
        any_target = true;
        continue;
      }
      const std::span<const float> distance =
          world.GeodesicField(robot.x_m, robot.y_m, robot.radius_m);
      float best = std::numeric_limits<float>::infinity();
      std::pair<float, float> target;
      for (int iy = 0; iy < floor.height(); ++iy) {
        for (int ix = 0; ix < floor.width(); ++ix) {
          const float d = distance[floor.Linear(ix, iy)];
          if (floor.Cell(ix, iy) != VP_FLOOR_FRONTIER || !(d < best) || d < kMinTravelM ||
              floor.Clearance(ix, iy) < robot.radius_m)
            continue;
          const auto [x, y] = floor.CellCenter(ix, iy);
          bool free = true;
          for (const auto& [cx, cy] : claimed)
            free = free && std::hypot(x - cx, y - cy) > kClaimRadiusM;
          if (!free) continue;
          best = d;
          target = {x, y};
        }
      }
      if (!std::isfinite(best)) continue;
      claimed.push_back(target);
      any_target = true;
      const float theta = std::atan2(target.second - robot.y_m, target.first - robot.x_m);
      out.ReplaceTasks(r);
      out.AddTask(r, {target.first, target.second, theta, 0.f, 0.f, 0.f, VP_MODE_EXPLORER, r});
    }
    out.Diagnostic("targets", double(claimed.size()));
    out.SetDone(!any_target);
  }
};

}  // namespace

VP_PLANNER_EXPORT(NearestFrontier, "nearest_frontier", "1.0.0")
