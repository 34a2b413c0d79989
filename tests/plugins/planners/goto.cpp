// A planner for the exploration loop's host tests: sends robot 0 to one goal ("x", "y" in the
// JSON config, read naively), again after every failure, without a path (the host routes it);
// done once the robot stands there. Reports the explorer camera it was shown as diagnostics.
#include <cmath>
#include <cstdlib>
#include <string>

#include "plugins/planner_cpp.h"

namespace {

float NumberOption(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\"");
  if (at == std::string::npos) throw vp::Error(VP_ERROR_INVALID_ARGUMENT, "goto needs " + key);
  const size_t colon = json.find(':', at);
  if (colon == std::string::npos) throw vp::Error(VP_ERROR_INVALID_ARGUMENT, "goto: bad " + key);
  return std::strtof(json.c_str() + colon + 1, nullptr);
}

class Goto : public vp::Planner {
 public:
  explicit Goto(const vp::Config& config)
      : x_m_(NumberOption(config.json, "x")), y_m_(NumberOption(config.json, "y")) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    const vp_mode_params camera = world.Mode(0, VP_MODE_EXPLORER);
    out.Diagnostic("explorer_fov_rad", camera.horizontal_fov_rad);
    out.Diagnostic("explorer_max_range_m", camera.max_range_m);
    const vp_robot robot = world.Robot(0);
    if (robot.status != VP_ROBOT_IDLE) return;
    if (std::hypot(robot.x_m - x_m_, robot.y_m - y_m_) < 1e-3f) {
      out.SetDone(true);
      return;
    }
    const vp_task task{
        x_m_, y_m_, std::atan2(y_m_ - robot.y_m, x_m_ - robot.x_m), 0.f, 0.f, 0.f, VP_MODE_EXPLORER,
        0};
    out.ReplaceTasks(0);
    out.AddTask(0, task);
  }

 private:
  float x_m_, y_m_;
};

}  // namespace

VP_PLANNER_EXPORT(Goto, "goto", "1.0.0")
