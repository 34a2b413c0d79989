// The path a plan step sends and the camera trajectory along it (X eq. 7-8 over the next
// lookahead of the path, the sent part being its first sub-steps).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "plugins/tensorfield/gain.h"
#include "plugins/tensorfield/planner.h"

namespace voxplan::tensorfield {

void RobotPlanner::EmitLine(const std::vector<Eigen::Vector2d>& line,
                            const std::vector<float>& speeds, const RobotInput& robot,
                            const ViewGain& gain, StepOutput* out) {
  const auto t0 = std::chrono::steady_clock::now();
  if (line.empty()) return;
  // Arc length and time at every point (the speed of point i is that of the piece ending there).
  std::vector<double> arc(line.size(), 0.0), time(line.size(), 0.0);
  for (std::size_t i = 1; i < line.size(); ++i) {
    const double ds = (line[i] - line[i - 1]).norm();
    arc[i] = arc[i - 1] + ds;
    time[i] = time[i - 1] + ds / std::max(0.05, double(speeds[i]));
  }
  auto heading_at = [&](std::size_t i) {
    // Direction of the segment leaving i (arriving, for the last point); the robot's heading
    // when the line has no length there.
    for (std::size_t j = i; j + 1 < line.size(); ++j)
      if ((line[j + 1] - line[j]).norm() > 1e-6) {
        const Eigen::Vector2d d = line[j + 1] - line[j];
        return std::atan2(d.y(), d.x());
      }
    for (std::size_t j = std::min(i, line.size() - 1); j > 0; --j)
      if ((line[j] - line[j - 1]).norm() > 1e-6) {
        const Eigen::Vector2d d = line[j] - line[j - 1];
        return std::atan2(d.y(), d.x());
      }
    return robot.heading_rad;
  };
  // The sent part: the first sent_substeps sub-steps of it (X4), cut at that arc length.
  const double sent_m = options_.sent_substeps * options_.substep_s * options_.speed_mps;
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (arc[i] <= sent_m + 1e-9) {
      out->path.push_back(line[i]);
      out->speeds_mps.push_back(std::max(0.05f, speeds[i]));
      out->headings_rad.push_back(heading_at(i));
      continue;
    }
    const double f = (sent_m - arc[i - 1]) / std::max(1e-9, arc[i] - arc[i - 1]);
    if (f > 1e-3) {
      out->path.push_back(line[i - 1] + f * (line[i] - line[i - 1]));
      out->speeds_mps.push_back(std::max(0.05f, speeds[i]));
      out->headings_rad.push_back(heading_at(i - 1));
    }
    break;
  }
  out->lookahead = line;

  // Camera base samples every camera_sample_m along the whole line.
  std::vector<CameraBaseSample> base;
  std::size_t seg = 0;
  for (double s = 0.0; s <= arc.back() + 1e-9; s += options_.camera_sample_m) {
    while (seg + 2 < line.size() && arc[seg + 1] < s) ++seg;
    const std::size_t j = std::min(seg + 1, line.size() - 1);
    const double f =
        arc[j] > arc[seg] ? std::clamp((s - arc[seg]) / (arc[j] - arc[seg]), 0.0, 1.0) : 0.0;
    CameraBaseSample b;
    b.xy_m = (line[seg] + f * (line[j] - line[seg])).cast<float>();
    b.heading_rad = static_cast<float>(heading_at(seg));
    b.arc_length_m = static_cast<float>(s);
    base.push_back(b);
  }
  auto time_at = [&](double s) {
    const auto it = std::lower_bound(arc.begin(), arc.end(), s);
    if (it == arc.begin()) return time.front();
    if (it == arc.end()) return time.back();
    const std::size_t j = static_cast<std::size_t>(it - arc.begin());
    const double f = arc[j] > arc[j - 1] ? (s - arc[j - 1]) / (arc[j] - arc[j - 1]) : 1.0;
    return time[j - 1] + f * (time[j] - time[j - 1]);
  };
  const float height = static_cast<float>(robot.camera_height_m);
  if (base.size() < 2) {
    const float yaw = static_cast<float>(heading_at(0));
    out->camera.push_back(
        {0.f, Eigen::Vector3f(float(line[0].x()), float(line[0].y()), height), yaw, 0.f});
  } else {
    CameraPathParams cp;
    cp.mode = options_.camera;
    CameraWorkspace ws = robot.workspace;
    if (!robot.arm) {
      // A head: the camera over the base centre, turning on its yaw joint (the candidates'
      // bearings only say which way they look).
      ws.height_min_m = ws.height_max_m = height;
      ws.reach_min_m = 0.01f;
      ws.reach_max_m = 0.02f;
      ws.bearing_half_angle_rad = 1.5707963f;
      cp.fixed_forward_m = 0.f;
      cp.fixed_height_m = height;
    }
    cp.candidates.workspace = ws;
    cp.candidates.floor_z_m = static_cast<float>(robot.floor_z_m);
    cp.selection.base_speed_mps = static_cast<float>(options_.speed_mps);
    cp.output_step_m = 0.1f;
    const double half_fov = 0.5 * robot.fov_rad;
    const CameraScoreFn score = [&](const Eigen::Vector3f& cam, const CameraBaseSample& b) {
      const Eigen::Vector2f off = cam.head<2>() - b.xy_m;
      const double bearing =
          off.norm() > 1e-5f ? std::atan2(double(off.y()), double(off.x())) : double(b.heading_rad);
      const ViewChoice v = gain.Best(cam.head<2>().cast<double>(), bearing, half_fov);
      CameraViewScore s;
      s.yaw_rad = static_cast<float>(v.yaw_rad);
      s.pitch_rad = 0.f;
      s.gain = static_cast<float>(v.gain);
      return s;
    };
    const CameraPathResult r = PlanCameraPath(base, cp, {}, score);
    for (const CameraPathSample& s : r.trajectory.samples)
      out->camera.push_back(
          {static_cast<float>(time_at(s.arc_length_m)), s.position_W, s.yaw_rad,
           std::clamp(s.pitch_rad, float(robot.min_pitch_rad), float(robot.max_pitch_rad))});
  }
  out->diag.traj_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace voxplan::tensorfield
