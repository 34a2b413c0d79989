// A planner for the exploration loop's host tests: sends robot 0 to one goal ("x", "y" in the
// JSON config, read naively), again after every failure, without a path (the host routes it);
// done once the robot stands there. Reports the explorer camera it was shown as diagnostics.
// Optional keys give the task a mode ("mode"), a dwell ("dwell") and a camera part (vp.task):
// "height", "offset_x"/"offset_y" (arm), "look_x"/"look_y"/"look_z", "sweep_min"/"sweep_max"/
// "sweep_step" (radians). vp.motion and vp.schedule: "continuous": 1 sends a straight path to the
// goal (points every 0.2 m, no tasks) to be driven without stopping, at "speed" (m/s) when given;
// "wakeup": dt asks to be called dt seconds after every call. "camera_position": 1 with
// "continuous" adds a camera trajectory that looks along the path and holds the camera at
// "height" and "offset_x"/"offset_y" from the base at each path point (NaN positions without a
// "height"), timed at the path's speed.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "plugins/planner_cpp.h"

namespace {

float OptionalNumber(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\"");
  if (at == std::string::npos) return std::numeric_limits<float>::quiet_NaN();
  const size_t colon = json.find(':', at);
  if (colon == std::string::npos) throw vp::Error(VP_ERROR_INVALID_ARGUMENT, "goto: bad " + key);
  return std::strtof(json.c_str() + colon + 1, nullptr);
}

float NumberOption(const std::string& json, const std::string& key) {
  const float v = OptionalNumber(json, key);
  if (std::isnan(v)) throw vp::Error(VP_ERROR_INVALID_ARGUMENT, "goto needs " + key);
  return v;
}

class Goto : public vp::Planner {
 public:
  explicit Goto(const vp::Config& config)
      : x_m_(NumberOption(config.json, "x")), y_m_(NumberOption(config.json, "y")) {
    const std::string& j = config.json;
    const float mode = OptionalNumber(j, "mode"), dwell = OptionalNumber(j, "dwell");
    mode_ = std::isnan(mode) ? VP_MODE_EXPLORER : int32_t(mode);
    dwell_s_ = std::isnan(dwell) ? 0.f : dwell;
    ext_ = vp::DefaultTaskExt();
    ext_.camera_height_m = OptionalNumber(j, "height");
    ext_.camera_offset_m[0] = OptionalNumber(j, "offset_x");
    ext_.camera_offset_m[1] = OptionalNumber(j, "offset_y");
    const float look[3] = {OptionalNumber(j, "look_x"), OptionalNumber(j, "look_y"),
                           OptionalNumber(j, "look_z")};
    ext_.look_at = std::isnan(look[0]) ? 0 : 1;
    for (int k = 0; k < 3; ++k) ext_.look_at_W[k] = ext_.look_at ? look[k] : 0.f;
    const float step = OptionalNumber(j, "sweep_step");
    if (!std::isnan(step)) {
      ext_.sweep_pitch_min_rad = OptionalNumber(j, "sweep_min");
      ext_.sweep_pitch_max_rad = OptionalNumber(j, "sweep_max");
      ext_.sweep_pitch_step_rad = step;
    }
    with_ext_ = !std::isnan(ext_.camera_height_m) || !std::isnan(ext_.camera_offset_m[0]) ||
                ext_.look_at || ext_.sweep_pitch_step_rad != 0.f;
    continuous_ = OptionalNumber(j, "continuous") == 1.f;
    speed_mps_ = OptionalNumber(j, "speed");
    wakeup_s_ = OptionalNumber(j, "wakeup");
    camera_position_ = OptionalNumber(j, "camera_position") == 1.f;
  }

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    const vp_mode_params camera = world.Mode(0, VP_MODE_EXPLORER);
    out.Diagnostic("explorer_fov_rad", camera.horizontal_fov_rad);
    out.Diagnostic("explorer_max_range_m", camera.max_range_m);
    if (!std::isnan(wakeup_s_)) out.RequestCall(world.call().sim_time_s + wakeup_s_);
    const vp_robot robot = world.Robot(0);
    if (robot.status != VP_ROBOT_IDLE) return;
    if (std::hypot(robot.x_m - x_m_, robot.y_m - y_m_) < 1e-3f) {
      out.SetDone(true);
      return;
    }
    const vp_task task{
        x_m_, y_m_, std::atan2(y_m_ - robot.y_m, x_m_ - robot.x_m), 0.f, 0.f, dwell_s_, mode_, 0};
    out.ReplaceTasks(0);
    if (continuous_) {
      const float dx = x_m_ - robot.x_m, dy = y_m_ - robot.y_m;
      const int n = std::max(1, int(std::ceil(std::hypot(dx, dy) / 0.2f)));
      std::vector<vp_path_point> points;
      for (int k = 1; k <= n; ++k)
        points.push_back({robot.x_m + dx * float(k) / float(n),
                          robot.y_m + dy * float(k) / float(n), task.theta_rad});
      const std::vector<float> speeds(std::isnan(speed_mps_) ? 0 : points.size(), speed_mps_);
      out.SetContinuousPath(0, points, speeds);
      if (camera_position_) {
        const float speed =
            std::isnan(speed_mps_)
                ? world.Mode(0, VP_MODE_EXPLORER).max_speed_mps
                : std::min(speed_mps_, world.Mode(0, VP_MODE_EXPLORER).max_speed_mps);
        const float c = std::cos(task.theta_rad), sn = std::sin(task.theta_rad);
        const float ox = ext_.camera_offset_m[0], oy = ext_.camera_offset_m[1];
        std::vector<vp_camera_sample> samples;
        float t_s = 0.f, x = robot.x_m, y = robot.y_m;
        for (size_t k = 0; k <= points.size(); ++k) {
          if (k > 0) {
            t_s += std::hypot(points[k - 1].x_m - x, points[k - 1].y_m - y) / speed;
            x = points[k - 1].x_m;
            y = points[k - 1].y_m;
          }
          samples.push_back({t_s,
                             {x + c * ox - sn * oy, y + sn * ox + c * oy, ext_.camera_height_m},
                             task.theta_rad,
                             0.f});
        }
        out.SetCameraTrajectory(0, samples);
      }
      return;
    }
    if (with_ext_) {
      out.AddTask(0, task, ext_);
    } else {
      out.AddTask(0, task);
    }
  }

 private:
  float x_m_, y_m_;
  int32_t mode_ = VP_MODE_EXPLORER;
  float dwell_s_ = 0.f;
  vp_task_ext ext_{};
  bool with_ext_ = false;
  bool continuous_ = false, camera_position_ = false;
  float speed_mps_ = 0.f, wakeup_s_ = 0.f;  // NaN: not asked for
};

}  // namespace

VP_PLANNER_EXPORT(Goto, "goto", "1.0.0")
