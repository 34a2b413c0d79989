// Validation of what a plugin's plan() returned: tasks, paths, camera trajectories,
// diagnostics and drawings that cannot be used are dropped one by one and logged as rejections.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "plugins/host/host_internal.h"

namespace voxplan::internal {
namespace {

// Why a task cannot be executed, or "" when it can. `field` is the robot's geodesic field (may
// be empty when the world could not compute one).
std::string TaskProblem(const PlannerTask& t, const PlannerRobot& robot, const PlannerMapInfo& map,
                        const PlannerFloor& floor, const std::vector<float>& field,
                        const PlanValidation& v) {
  const auto fmt = [](float x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", double(x));
    return std::string(buf);
  };
  if (!AllFinite({t.position_m.x(), t.position_m.y(), t.theta_rad, t.camera_yaw_rad,
                  t.camera_pitch_rad, t.dwell_s})) {
    return "non-finite number";
  }
  if (t.dwell_s < 0.f || t.dwell_s > v.max_dwell_s) {
    return "dwell " + fmt(t.dwell_s) + " s outside [0, " + fmt(v.max_dwell_s) + "]";
  }
  const size_t modes = std::max<size_t>(robot.modes.size(), 1);
  if (t.mode < 0 || size_t(t.mode) >= modes) {
    return "mode " + std::to_string(t.mode) + " unknown (robot has " + std::to_string(modes) + ")";
  }
  // The mode's own pitch range (an arm tilts further than a head).
  const ScanMode* mode = robot.modes.empty() ? nullptr : &robot.modes[size_t(t.mode)];
  const float min_pitch = mode ? mode->min_pitch_rad : robot.min_pitch_rad;
  const float max_pitch = mode ? mode->max_pitch_rad : robot.max_pitch_rad;
  if (t.camera_pitch_rad < min_pitch || t.camera_pitch_rad > max_pitch) {
    return "camera pitch " + fmt(t.camera_pitch_rad) + " rad outside the mode's limits";
  }
  const std::string at = " at (" + fmt(t.position_m.x()) + ", " + fmt(t.position_m.y()) + ")";
  if ((t.position_m.array() < map.bounds_min.head<2>().array()).any() ||
      (t.position_m.array() > map.bounds_max.head<2>().array()).any()) {
    return "outside the map bounds" + at;
  }
  const Eigen::Vector2i c = floor.CellOf(t.position_m);
  if (!floor.Contains(c.x(), c.y())) return "outside the floor raster" + at;
  const size_t i = floor.Linear(c.x(), c.y());
  if (floor.cells[i] == FloorCell::kObstacle) return "inside an obstacle" + at;
  if (floor.cells[i] == FloorCell::kUnknown) return "in unknown space" + at;
  const float needed = robot.radius_m + v.clearance_margin_m;
  if (floor.clearance_m[i] < needed) {
    return "too close to an obstacle" + at + " (clearance " + fmt(floor.clearance_m[i]) + " m < " +
           fmt(needed) + " m)";
  }
  if (field.size() != floor.cells.size() || !std::isfinite(field[i])) {
    return "unreachable from the robot" + at;
  }
  return "";
}

// The camera part of a task (vp.task): "" when the mode can take it.
std::string TaskCameraProblem(const PlannerTask& t, const PlannerRobot& robot,
                              const PlannerWorld& world) {
  const TaskCamera& c = t.camera;
  const auto fmt = [](float x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", double(x));
    return std::string(buf);
  };
  constexpr float kSlack = 1e-4f;  // float round trips
  constexpr int kMaxSweepSteps = 64;
  if (c.look_at && !c.look_at_W.allFinite()) return "look-at point is not finite";
  if (!AllFinite({c.sweep_pitch_min_rad, c.sweep_pitch_max_rad, c.sweep_pitch_step_rad}))
    return "pitch sweep is not finite";
  const ScanMode* mode = robot.modes.empty() ? nullptr : &robot.modes[size_t(t.mode)];
  if (c.Sweeps()) {
    const float lo = mode ? mode->min_pitch_rad : robot.min_pitch_rad;
    const float hi = mode ? mode->max_pitch_rad : robot.max_pitch_rad;
    if (c.sweep_pitch_min_rad > c.sweep_pitch_max_rad || c.sweep_pitch_min_rad < lo - kSlack ||
        c.sweep_pitch_max_rad > hi + kSlack)
      return "pitch sweep [" + fmt(c.sweep_pitch_min_rad) + ", " + fmt(c.sweep_pitch_max_rad) +
             "] rad outside the mode's limits";
    if ((c.sweep_pitch_max_rad - c.sweep_pitch_min_rad) / c.sweep_pitch_step_rad > kMaxSweepSteps)
      return "pitch sweep has more than " + std::to_string(kMaxSweepSteps) + " steps";
  } else if (c.sweep_pitch_step_rad < 0.f) {
    return "pitch sweep step is negative";
  }
  if (!c.ArmSet()) return "";
  if (!mode || mode->mount != CameraMount::kArm)
    return "camera height or offset given for a mode without an arm";
  const float height = c.HeightSet() ? c.height_m
                                     : std::clamp(robot.camera_height_m, mode->camera_height_min_m,
                                                  mode->camera_height_max_m);
  const Eigen::Vector2f offset =
      c.OffsetSet() ? c.offset_m : Eigen::Vector2f(mode->reach_min_m, 0.f);
  if (!std::isfinite(height) || !offset.allFinite()) return "camera height or offset is not finite";
  if (height < mode->camera_height_min_m - kSlack || height > mode->camera_height_max_m + kSlack)
    return "camera height " + fmt(height) + " m outside the arm's [" +
           fmt(mode->camera_height_min_m) + ", " + fmt(mode->camera_height_max_m) + "] m";
  const float reach = offset.norm();
  if (reach < mode->reach_min_m - kSlack || reach > mode->reach_max_m + kSlack)
    return "camera reach " + fmt(reach) + " m outside the arm's [" + fmt(mode->reach_min_m) + ", " +
           fmt(mode->reach_max_m) + "] m";
  const float bearing = reach > 0.f ? std::atan2(offset.y(), offset.x()) : 0.f;
  if (std::abs(bearing) > mode->reach_half_angle_rad + kSlack)
    return "camera bearing " + fmt(bearing) + " rad beyond the arm's +-" +
           fmt(mode->reach_half_angle_rad) + " rad";
  // Where the camera will be: in observed free space, not in a wall or in the unknown.
  const float cs = std::cos(t.theta_rad), sn = std::sin(t.theta_rad);
  const Eigen::Vector3f camera_W(t.position_m.x() + cs * offset.x() - sn * offset.y(),
                                 t.position_m.y() + sn * offset.x() + cs * offset.y(), height);
  VoxelState state = VoxelState::kUnobserved;
  world.VoxelStates(std::span<const Eigen::Vector3f>(&camera_W, 1),
                    std::span<VoxelState>(&state, 1));
  if (state != VoxelState::kFree)
    return std::string("camera position ") +
           (state == VoxelState::kOccupied ? "inside a surface" : "in unobserved space") + " at (" +
           fmt(camera_W.x()) + ", " + fmt(camera_W.y()) + ", " + fmt(camera_W.z()) + ")";
  return "";
}

void Reject(PlanResult& result, const std::string& planner, int32_t robot, int32_t task,
            const std::string& reason) {
  result.rejections.push_back({robot, task, reason});
  std::string where = robot >= 0 ? "robot " + std::to_string(robot) + " " : "";
  if (task >= 0) where += "task " + std::to_string(task) + " ";
  result.log.push_back(
      {VP_LOG_WARNING, "planner " + planner + ": " + where + "rejected: " + reason});
}

}  // namespace

void Validate(const PlannerWorld& world, const std::vector<PlannerRobot>& robots,
              const PlanValidation& v, const std::string& planner, PlanResult& result) {
  const PlannerMapInfo map = world.MapInfo();
  const PlannerFloor& floor = world.Floor();
  for (size_t r = 0; r < result.robots.size(); ++r) {
    RobotPlan& plan = result.robots[r];
    const PlannerRobot& robot = robots[r];
    std::vector<float> field;
    if (!plan.tasks.empty()) {
      Result<std::vector<float>> f =
          world.GeodesicField(robot.position_m, robot.radius_m + v.clearance_margin_m);
      if (f.ok()) field = std::move(f).value();
    }
    std::vector<PlannerTask> kept;
    for (size_t t = 0; t < plan.tasks.size(); ++t) {
      std::string problem = TaskProblem(plan.tasks[t], robot, map, floor, field, v);
      if (problem.empty()) problem = TaskCameraProblem(plan.tasks[t], robot, world);
      if (problem.empty()) {
        kept.push_back(plan.tasks[t]);
      } else {
        Reject(result, planner, int32_t(r), int32_t(t), problem);
      }
    }
    plan.tasks = std::move(kept);
    for (size_t i = 0; i < plan.path.size(); ++i) {
      const PathPoint& p = plan.path[i];
      if (!p.position_m.allFinite() || !std::isfinite(p.theta_rad)) {
        Reject(result, planner, int32_t(r), -1,
               "path dropped: point " + std::to_string(i) + " is not finite");
        plan.path.clear();
        plan.path_speed_mps.clear();
        plan.path_continuous = false;
        break;
      }
    }
    if (!plan.path_speed_mps.empty()) {
      // vp.motion speeds: one per point, each a positive speed a robot could have.
      constexpr float kMaxSpeed_mps = 10.f;
      bool ok = plan.path_speed_mps.size() == plan.path.size();
      for (const float speed : plan.path_speed_mps)
        ok = ok && speed > 0.f && speed <= kMaxSpeed_mps;
      if (!ok) {
        Reject(result, planner, int32_t(r), -1,
               "path dropped: its speeds must be one per point, each in (0, 10] m/s");
        plan.path.clear();
        plan.path_speed_mps.clear();
        plan.path_continuous = false;
      }
    }
    for (size_t i = 0; i < plan.camera_trajectory.size(); ++i) {
      const CameraSample& s = plan.camera_trajectory[i];
      // A NaN position is "none" (vp_camera_sample): only infinities are refused there.
      const bool finite =
          !s.position_m.array().isInf().any() && AllFinite({s.t_s, s.yaw_rad, s.pitch_rad});
      if (!finite || (i > 0 && s.t_s < plan.camera_trajectory[i - 1].t_s)) {
        Reject(result, planner, int32_t(r), -1,
               "camera trajectory dropped: sample " + std::to_string(i) +
                   (finite ? " goes back in time" : " is not finite"));
        plan.camera_trajectory.clear();
        break;
      }
    }
  }
  std::vector<std::pair<std::string, double>> diagnostics;
  for (auto& [name, value] : result.diagnostics) {
    if (std::isfinite(value)) {
      diagnostics.emplace_back(std::move(name), value);
    } else {
      Reject(result, planner, -1, -1, "diagnostic '" + name + "' is not finite");
    }
  }
  result.diagnostics = std::move(diagnostics);
  std::vector<DebugDrawing> drawings;
  for (DebugDrawing& d : result.drawings) {
    bool finite = true;
    for (const Eigen::Vector3f& p : d.points) finite = finite && p.allFinite();
    if (finite) {
      drawings.push_back(std::move(d));
    } else {
      Reject(result, planner, -1, -1, "debug drawing in layer '" + d.layer + "' is not finite");
    }
  }
  result.drawings = std::move(drawings);
}

}  // namespace voxplan::internal
