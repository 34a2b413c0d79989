// The path a plan step sends and the camera trajectory along it (X eq. 7-8 over the next
// lookahead of the path, the sent part being its first sub-steps).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "plugins/tensorfield/gain.h"
#include "plugins/tensorfield/planner.h"

namespace voxplan::tensorfield {

namespace {

constexpr double kPi = 3.14159265358979323846;

double Wrap(double a) { return std::remainder(a, 2.0 * kPi); }

// The arc length of the point of a polyline nearest p, and its distance.
std::pair<double, double> Project(const std::vector<Eigen::Vector2d>& line,
                                  const std::vector<double>& arc, const Eigen::Vector2d& p) {
  double best_d = (line.front() - p).norm(), best_s = 0.0;
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Eigen::Vector2d a = line[i - 1], d = line[i] - a;
    const double len2 = d.squaredNorm();
    const double f = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (a + f * d - p).norm();
    if (dist < best_d) {
      best_d = dist;
      best_s = arc[i - 1] + f * (arc[i] - arc[i - 1]);
    }
  }
  return {best_s, best_d};
}

// Linear interpolation of ys over increasing xs at x, held outside.
double Interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  const auto it = std::lower_bound(xs.begin(), xs.end(), x);
  if (it == xs.begin()) return ys.front();
  if (it == xs.end()) return ys.back();
  const std::size_t j = static_cast<std::size_t>(it - xs.begin());
  const double f = xs[j] > xs[j - 1] ? (x - xs[j - 1]) / (xs[j] - xs[j - 1]) : 1.0;
  return ys[j - 1] + f * (ys[j] - ys[j - 1]);
}

}  // namespace

// X12: the cells of the window the robot's body would touch along the line that are unknown.
std::vector<CameraLookAtTarget> RobotPlanner::LookAtTargets(
    const std::vector<Eigen::Vector2d>& line, const RobotInput& robot) const {
  const omt::RasterGeometry& g = window_.geometry;
  std::vector<Eigen::Vector2f> xy;
  for (const Eigen::Vector2d& p : line) xy.push_back(p.cast<float>());
  const NearestUnknownFn nearest = [&](const Eigen::Vector2f& p,
                                       float within_m) -> std::optional<Eigen::Vector2f> {
    const Eigen::Vector2d q = (p.cast<double>() - g.origin_m) / g.resolution_m;
    const int cx = static_cast<int>(std::floor(q.x())), cy = static_cast<int>(std::floor(q.y()));
    const int r = static_cast<int>(std::ceil(within_m / g.resolution_m)) + 1;
    double best = within_m;
    std::optional<Eigen::Vector2f> out;
    for (int y = cy - r; y <= cy + r; ++y)
      for (int x = cx - r; x <= cx + r; ++x) {
        if (!g.InBounds(x, y) ||
            window_.codes[static_cast<std::size_t>(g.Index(x, y))] != kFloorUnknown)
          continue;
        const Eigen::Vector2d c = g.Center(x, y);
        const double d = (c - p.cast<double>()).norm();
        if (d <= best) {
          best = d;
          out = c.cast<float>();
        }
      }
    return out;
  };
  return FindLookAtTargets(xy, static_cast<float>(robot.radius_m + options_.clearance_margin_m),
                           static_cast<float>(0.5 * g.resolution_m),
                           static_cast<float>(robot.floor_z_m + robot.camera_height_m), nearest);
}

Eigen::Vector3f RobotPlanner::ArmCameraNow(const RobotInput& robot) const {
  constexpr double kOffPathM = 0.5;  // farther from the path last sent: not known
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  if (sent_path_.size() < 2 || sent_camera_.empty()) return none;
  const auto [s, d] = Project(sent_path_, sent_arc_, robot.position_m);
  if (d > kOffPathM) return none;
  // The host keys the arm's positions by the path's time for the distance driven.
  const double t = Interpolate(sent_arc_, sent_time_, s);
  const std::vector<CameraOut>& c = sent_camera_;
  if (t <= c.front().t_s) return c.front().position_m;
  for (std::size_t i = 1; i < c.size(); ++i) {
    if (t > c[i].t_s) continue;
    const double span = c[i].t_s - c[i - 1].t_s;
    const float f = span > 0.0 ? static_cast<float>((t - c[i - 1].t_s) / span) : 1.0f;
    return c[i - 1].position_m + f * (c[i].position_m - c[i - 1].position_m);
  }
  return c.back().position_m;
}

void RobotPlanner::EmitLine(const std::vector<Eigen::Vector2d>& line,
                            const std::vector<float>& speeds, const RobotInput& robot,
                            const ViewGain& route_gain, bool stop, StepOutput* out) {
  const auto t0 = std::chrono::steady_clock::now();
  if (line.empty()) return;
  // The camera's views weigh surface uncertainty too, when the options ask for it.
  std::optional<ViewGain> surface_gain;
  if (options_.surface_depth_m > 0.0 && !window_.surface.empty())
    surface_gain.emplace(GainModel(robot, true));
  const ViewGain& gain = surface_gain ? *surface_gain : route_gain;
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
  // X5: is this call a stop? The caller's kinds, a new kind of path (or one after none), and a
  // first piece more than a right angle off the heading, which the host turns the base in place
  // for (carrying the camera round with it) before it drives.
  const double first_turn = Wrap(heading_at(0) - robot.heading_rad);
  const bool turn_in_place = std::abs(first_turn) > 0.5 * kPi;
  stop = stop || out->diag.mode != prev_mode_ || turn_in_place;
  emitted_mode_ = out->diag.mode;
  camera_stops_ += stop ? 1 : 0;
  out->diag.camera_stop = stop;
  out->diag.camera_stops = camera_stops_;

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
    cp.selection.limits = robot.camera_limits;
    cp.selection.weight_lookat = options_.lookat_weight;
    cp.output_step_m = 0.1f;
    const double half_fov = 0.5 * robot.fov_rad;
    // X12: the unknown space the path runs into, looked at from the samples within lookat_m.
    CameraLookAt lookat;
    if (options_.lookat && options_.camera != CameraMode::kFixed) {
      lookat.targets = LookAtTargets(line, robot);
      lookat.params.range_m = static_cast<float>(options_.lookat_m);
      lookat.params.half_fov_rad = static_cast<float>(half_fov);
      lookat.gain = [&](const Eigen::Vector3f& cam, float yaw, float, const CameraBaseSample&) {
        return static_cast<float>(gain.GainAt(cam.head<2>().cast<double>(), yaw));
      };
      for (const CameraLookAtTarget& t : lookat.targets) {
        const double d = (t.point_W.head<2>().cast<double>() - robot.position_m).norm();
        if (out->diag.lookat_m < 0.0 || d < out->diag.lookat_m) out->diag.lookat_m = d;
      }
    }
    const CameraScoreFn score = [&](const Eigen::Vector3f& cam, const CameraBaseSample& b) {
      const Eigen::Vector2f off = cam.head<2>() - b.xy_m;
      const double bearing =
          off.norm() > 1e-5f ? std::atan2(double(off.y()), double(off.x())) : double(b.heading_rad);
      const ViewChoice v = gain.Best(cam.head<2>().cast<double>(), bearing, half_fov,
                                     options_.pitch == CameraPitch::kAim);
      CameraViewScore s;
      s.yaw_rad = static_cast<float>(v.yaw_rad);
      if (options_.pitch == CameraPitch::kAim && v.distance_m > 0.0) {
        const double pitch =
            AimPitch(double(cam.z()) - robot.floor_z_m, v.distance_m, options_.band_m);
        s.pitch_rad =
            static_cast<float>(std::clamp(pitch, robot.min_pitch_rad, robot.max_pitch_rad));
      }
      s.gain = static_cast<float>(v.gain);
      return s;
    };
    // X5: where the camera is. A first piece the base turns in place for carries the camera
    // round by the part of the turn beyond a right angle (the host turns in place until the
    // piece is within one, then turns while it drives), for that turn's time.
    const double drag = turn_in_place ? first_turn - std::copysign(0.5 * kPi, first_turn) : 0.0;
    CameraPose from;
    from.yaw_rad = static_cast<float>(Wrap(robot.camera_yaw_rad + drag));
    from.pitch_rad = static_cast<float>(robot.camera_pitch_rad);
    if (robot.arm) from.position_W = ArmCameraNow(robot);
    if (options_.connect == CameraConnect::kInSelection) {
      cp.start_from_camera = true;
      cp.start_position_W = from.position_W;
      cp.start_yaw_rad = from.yaw_rad;
      cp.start_pitch_rad = from.pitch_rad;
    }
    CameraPathResult r = PlanCameraPath(base, cp, {}, score, lookat);
    out->diag.lookat_samples = r.lookat_samples;
    out->diag.lookat_seen = r.lookat_seen;
    out->diag.lookat_changed = r.lookat_changed;
    // In the time the host executes it: along the path at its speed profile.
    for (CameraPathSample& s : r.trajectory.samples)
      s.time_s = static_cast<float>(time_at(s.arc_length_m));
    // X5: joined from where the camera is.
    if (options_.camera != CameraMode::kFixed) {
      CameraConnectParams kp;
      kp.workspace = ws;
      kp.limits = robot.camera_limits;
      kp.floor_z_m = static_cast<float>(robot.floor_z_m);
      kp.hold_s = static_cast<float>(std::abs(drag) / std::max(1e-3, robot.turn_rate_radps));
      CameraTrajectory connected = r.trajectory;
      const CameraConnection c = ConnectCameraTrajectory(from, kp, &connected);
      out->diag.camera_jump_deg = c.jump_rad * 180.0 / kPi;
      out->diag.camera_radps_before = c.max_radps_before;
      const bool connect = options_.connect != CameraConnect::kOff;
      out->diag.camera_radps_after = connect ? c.max_radps_after : c.max_radps_before;
      if (connect) {
        r.trajectory = std::move(connected);
        out->diag.camera_connect_s = c.connected ? c.duration_s : 0.0;
      }
    }
    for (const CameraPathSample& s : r.trajectory.samples)
      out->camera.push_back(
          {s.time_s, s.position_W, s.yaw_rad,
           std::clamp(s.pitch_rad, float(robot.min_pitch_rad), float(robot.max_pitch_rad))});
  }
  // What was sent, for where the arm camera is at the next call.
  sent_path_ = out->path;
  sent_arc_.assign(1, 0.0);
  sent_time_.assign(1, 0.0);
  for (std::size_t i = 1; i < sent_path_.size(); ++i) {
    const double ds = (sent_path_[i] - sent_path_[i - 1]).norm();
    sent_arc_.push_back(sent_arc_.back() + ds);
    sent_time_.push_back(time_at(sent_arc_.back()));
  }
  sent_camera_ = out->camera;
  out->diag.traj_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace voxplan::tensorfield
