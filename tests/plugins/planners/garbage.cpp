// Returns garbage next to one good task, for robot 0 of any world with a floor: a NaN, a task
// in an obstacle, one in unknown space, one too close to a wall, one in a free cell it cannot
// reach, one outside the bounds, a bad mode, a negative dwell; a path with an infinity, a NaN
// diagnostic and a NaN debug point; for robot 1 a continuous path with a zero speed. The host must
// keep only the good task (tag 1).
#include <cmath>
#include <limits>
#include <vector>

#include "plugins/planner_cpp.h"

namespace {

class Garbage : public vp::Planner {
 public:
  explicit Garbage(const vp::Config&) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const vp_robot robot = world.Robot(0);
    const vp::FloorView floor = world.Floor();
    const std::span<const float> field = world.GeodesicField(robot.x_m, robot.y_m, robot.radius_m);
    // First cell (in raster order) of each kind.
    int obstacle = -1, unknown = -1, close = -1, unreachable = -1, good = -1;
    for (size_t i = 0; i < floor.size(); ++i) {
      const uint8_t c = floor.cells()[i];
      const float clearance = floor.clearance_m()[i];
      if (c == VP_FLOOR_OBSTACLE && obstacle < 0) obstacle = int(i);
      if (c == VP_FLOOR_UNKNOWN && unknown < 0) unknown = int(i);
      if (c == VP_FLOOR_FREE && clearance < robot.radius_m && close < 0) close = int(i);
      if (c == VP_FLOOR_FREE && clearance >= robot.radius_m) {
        if (!std::isfinite(field[i]) && unreachable < 0) unreachable = int(i);
        if (std::isfinite(field[i]) && field[i] > 0.f && good < 0) good = int(i);
      }
    }
    const auto at = [&](int cell, uint32_t tag) {
      const auto [x, y] = floor.CellCenter(cell % floor.width(), cell / floor.width());
      return vp_task{x, y, 0.f, 0.f, 0.f, 1.f, VP_MODE_EXPLORER, tag};
    };
    vp_task nan_task = at(good, 0);
    nan_task.x_m = nan;
    vp_task far = at(good, 6);
    far.x_m = 1e6f;
    vp_task bad_mode = at(good, 7);
    bad_mode.mode = 7;
    vp_task bad_dwell = at(good, 8);
    bad_dwell.dwell_s = -1.f;
    out.ReplaceTasks(0);
    for (const vp_task& t : {nan_task, at(good, 1), at(obstacle, 2), at(unknown, 3), at(close, 4),
                             at(unreachable, 5), far, bad_mode, bad_dwell}) {
      out.AddTask(0, t);
    }
    const vp_path_point path[2] = {{robot.x_m, robot.y_m, 0.f},
                                   {std::numeric_limits<float>::infinity(), 0.f, 0.f}};
    out.SetPath(0, path);
    // Robot 1 (vp.motion): a continuous path with a speed of zero, dropped whole.
    if (world.RobotCount() > 1) {
      const vp_robot r1 = world.Robot(1);
      const vp_path_point slow[2] = {{r1.x_m, r1.y_m, 0.f}, {r1.x_m + 0.1f, r1.y_m, 0.f}};
      const float speeds[2] = {0.3f, 0.f};
      out.SetContinuousPath(1, slow, speeds);
    }
    out.Diagnostic("energy", std::nan(""));
    out.Diagnostic("iterations", 3.0);
    const float points[6] = {0.f, 0.f, 0.f, nan, 1.f, 1.f};
    out.DebugPoints("junk", points, 0xff0000ffu);
  }
};

}  // namespace

VP_PLANNER_EXPORT(Garbage, "garbage", "0.0.1")
