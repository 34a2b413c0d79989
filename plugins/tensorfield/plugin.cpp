// The tensor-field planner (Xu et al. 2017) as a plugin: every call steps each robot's own
// field-guided plan by one sub-step (planner.h) and sends it as a continuous path (vp.motion)
// with a camera trajectory, asking to be called again one sub-step later (vp.schedule). Config
// keys and what is not done: plugins/tensorfield/README.md.
#include <algorithm>
#include <cmath>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "plugins/common/world_input.h"
#include "plugins/planner_cpp.h"
#include "plugins/tensorfield/planner.h"

namespace voxplan::tensorfield {
namespace {

constexpr uint32_t kPathColor = 0xe15759ffu, kLookaheadColor = 0xf28e2bffu;
constexpr uint32_t kPointColor = 0x59a14fffu, kSkeletonColor = 0xb07aa1ffu;
constexpr uint32_t kFieldColor = 0xb0b0b0ffu;

PlannerOptions ReadOptions(const std::string& json_text) {
  planners::JsonOptions json("tensorfield", json_text);
  PlannerOptions o;
  o.substep_s = json.Number("substep_s", o.substep_s, 0.05, 10.0);
  o.frames_k = json.Integer("frames_k", o.frames_k, 2, 100);
  o.substeps_per_keyframe =
      json.Integer("substeps_per_keyframe", o.substeps_per_keyframe, 1, o.frames_k);
  o.speed_mps = json.Number("speed_mps", o.speed_mps, 0.05, 2.0);
  o.window_m = json.Number("window_m", o.window_m, 3.0, 30.0);
  o.interp_window_m = json.Number("interp_window_m", o.interp_window_m, 0.5, 30.0);
  const std::string method = json.Choice("method", "tensor", {"tensor", "harmonic", "potential"});
  o.method = method == "harmonic"    ? Method::kHarmonic
             : method == "potential" ? Method::kPotential
                                     : Method::kTensor;
  o.interp = json.Choice("interp", "spacetime", {"spacetime", "linear"}) == "linear"
                 ? InterpolationMode::kLinear
                 : InterpolationMode::kSpaceTime;
  o.topology_routing = json.Flag("topology_routing", o.topology_routing);
  o.topology_control = json.Flag("topology_control", o.topology_control);
  const std::string camera =
      json.Choice("camera", "optimized", {"optimized", "fixed", "no_linear", "no_angular"});
  o.camera = camera == "fixed"        ? CameraMode::kFixed
             : camera == "no_linear"  ? CameraMode::kNoLinear
             : camera == "no_angular" ? CameraMode::kNoAngular
                                      : CameraMode::kOptimized;
  o.lookat = json.Flag("lookat", o.lookat);
  o.lookat_m = json.Number("lookat_m", o.lookat_m, 0.1, 10.0);
  o.lookat_weight = json.Number("lookat_weight", o.lookat_weight, 0.0, 100.0);
  const std::string connect = json.Choice("connect", "spline", {"spline", "selection", "off"});
  o.connect = connect == "off"         ? CameraConnect::kOff
              : connect == "selection" ? CameraConnect::kInSelection
                                       : CameraConnect::kSpline;
  o.pitch = json.Choice("pitch", "level", {"level", "aim"}) == "aim" ? CameraPitch::kAim
                                                                     : CameraPitch::kLevel;
  o.gain_threshold = json.Number("gain_threshold", o.gain_threshold, 0.0, 1.0);
  o.surface_depth_m = json.Number("surface_depth_m", o.surface_depth_m, 0.0, 10.0);
  o.band_m = json.Number("band_m", o.band_m, 0.1, 10.0);
  const std::string field =
      json.Choice("field", "tensor", {"tensor", "vector_normal", "vector_tangent"});
  o.field = field == "vector_normal"    ? FieldKind::kVectorNormal
            : field == "vector_tangent" ? FieldKind::kVectorTangent
                                        : FieldKind::kTensor;
  if (o.field != FieldKind::kTensor && o.method != Method::kTensor)
    throw vp::Error(VP_ERROR_INVALID_ARGUMENT,
                    "tensorfield: field \"" + field + "\" needs method \"tensor\" (the method \"" +
                        method + "\" has its own potential and no field)");
  o.clearance_margin_m = json.Number("clearance_margin_m", o.clearance_margin_m, 0.0, 1.0);
  o.lookahead_m = json.Number("lookahead_m", o.lookahead_m, 0.3, 10.0);
  o.fill.enabled = json.Flag("fill", o.fill.enabled);
  json.RejectUnknownKeys();
  return o;
}

FloorInput ReadFloor(const vp::FloorView& f) {
  FloorInput floor;
  floor.geometry.width = f.width();
  floor.geometry.height = f.height();
  floor.geometry.resolution_m = f.cell_size_m();
  floor.geometry.origin_m = {f.raw().origin_x_m, f.raw().origin_y_m};
  floor.cells.assign(f.cells().begin(), f.cells().end());
  floor.clearance_m.assign(f.clearance_m().begin(), f.clearance_m().end());
  return floor;
}

// The surface voxels from the floor up to band_m over the floor's cells: each cell's largest
// uncertainty and its voxels' summed normals in the plane (unit; zero when they cancel or none
// has a normal).
SurfaceCells ReadSurface(std::span<const vp_surface_voxel> voxels,
                         const omt::RasterGeometry& geometry, float floor_z_m, double band_m) {
  SurfaceCells s;
  const std::size_t n = static_cast<std::size_t>(geometry.NumCells());
  s.uncertainty.assign(n, 0.f);
  s.normal.assign(n, Eigen::Vector2f::Zero());
  for (const vp_surface_voxel& v : voxels) {
    const float z = v.position[2] - floor_z_m;
    if (!(z >= 0.f && z <= float(band_m)) || !std::isfinite(v.uncertainty) ||
        !std::isfinite(v.position[0]) || !std::isfinite(v.position[1]))
      continue;
    const int c = geometry.IndexOf(Eigen::Vector2d(v.position[0], v.position[1]));
    if (c < 0) continue;
    const std::size_t i = static_cast<std::size_t>(c);
    s.uncertainty[i] = std::max(s.uncertainty[i], std::clamp(v.uncertainty, 0.f, 1.f));
    if (std::isfinite(v.normal[0]) && std::isfinite(v.normal[1]))
      s.normal[i] += Eigen::Vector2f(v.normal[0], v.normal[1]);
  }
  for (Eigen::Vector2f& v : s.normal)
    v = v.norm() > 1e-3f ? v.normalized() : Eigen::Vector2f::Zero();
  return s;
}

RobotInput ReadRobot(const vp::WorldView& world, uint32_t r, const vp_map_info& map) {
  const vp_robot robot = world.Robot(r);
  const vp_mode_params mode = world.Mode(r, uint32_t(robot.mode));
  RobotInput in;
  in.position_m = {robot.x_m, robot.y_m};
  in.heading_rad = robot.theta_rad;
  in.radius_m = robot.radius_m;
  in.camera_height_m = robot.camera_height_m;
  in.fov_rad = mode.horizontal_fov_rad > 0.f ? mode.horizontal_fov_rad : 1.5707963f;
  in.min_range_m = mode.min_range_m;
  in.max_range_m = mode.max_range_m > 0.f ? mode.max_range_m : 5.f;
  in.max_speed_mps = mode.max_speed_mps;
  in.floor_z_m = map.floor_z_m;
  in.min_pitch_rad = robot.min_pitch_rad;
  in.max_pitch_rad = robot.max_pitch_rad;
  in.camera_yaw_rad = double(robot.theta_rad) + double(robot.camera_yaw_rad);
  in.camera_pitch_rad = robot.camera_pitch_rad;
  // a_m: the slower camera joint (the mode says so; else the robot's joint rates).
  const float joints = std::min(robot.camera_yaw_rate_radps, robot.camera_pitch_rate_radps);
  if (mode.camera_turn_rate_radps > 0.f) {
    in.camera_limits.angular_radps = mode.camera_turn_rate_radps;
  } else if (joints > 0.f) {
    in.camera_limits.angular_radps = joints;
  }
  if (mode.max_turn_rate_radps > 0.f) in.turn_rate_radps = mode.max_turn_rate_radps;
  in.arm = mode.mount == VP_MOUNT_ARM;
  // v_m: the arm's speed on its mount (a head moves with the base: the paper's v_m).
  if (in.arm && mode.camera_speed_mps > 0.f) in.camera_limits.linear_mps = mode.camera_speed_mps;
  if (in.arm) {
    in.workspace.height_min_m = mode.camera_height_min_m;
    in.workspace.height_max_m = mode.camera_height_max_m;
    in.workspace.reach_min_m = mode.reach_min_m;
    in.workspace.reach_max_m = mode.reach_max_m;
    in.workspace.bearing_half_angle_rad = mode.reach_half_angle_rad;
    in.min_pitch_rad = mode.min_pitch_rad;
    in.max_pitch_rad = mode.max_pitch_rad;
  }
  return in;
}

std::vector<float> Xyz(const std::vector<Eigen::Vector2d>& xy, float z) {
  std::vector<float> out;
  out.reserve(xy.size() * 3);
  for (const Eigen::Vector2d& p : xy) out.insert(out.end(), {float(p.x()), float(p.y()), z});
  return out;
}

class TensorfieldPlanner : public vp::Planner {
 public:
  explicit TensorfieldPlanner(const vp::Config& config) : options_(ReadOptions(config.json)) {}

  void Plan(const vp::WorldView& world, vp::PlanOutput& out) override {
    vp::StageTimer total(world, out, "plan");
    const uint32_t robots = world.RobotCount();
    if (robots == 0) return;
    const vp_map_info map = world.MapInfo();
    const vp::FloorView floor_view = world.Floor();
    if (floor_view.width() <= 0 || floor_view.height() <= 0) return;
    FloorInput floor = ReadFloor(floor_view);
    if (options_.surface_depth_m > 0.0)
      floor.surface =
          ReadSurface(world.SurfaceVoxels(), floor.geometry, map.floor_z_m, options_.band_m);
    RouteServices services;
    services.geodesic = [&](const Eigen::Vector2d& from, double clearance) {
      const std::span<const float> f =
          world.GeodesicField(float(from.x()), float(from.y()), float(clearance));
      return std::vector<float>(f.begin(), f.end());
    };
    services.shortest_path = [&](const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                                 double clearance) -> std::optional<std::vector<Eigen::Vector2d>> {
      const std::optional<std::vector<float>> xy = world.ShortestPath(
          float(from.x()), float(from.y()), float(to.x()), float(to.y()), float(clearance));
      if (!xy) return std::nullopt;
      std::vector<Eigen::Vector2d> path;
      for (size_t i = 0; i + 1 < xy->size(); i += 2) path.push_back({(*xy)[i], (*xy)[i + 1]});
      return path;
    };
    const double t_s = world.call().sim_time_s;
    bool all_done = true;
    double wakeup = std::numeric_limits<double>::infinity();
    for (uint32_t r = 0; r < robots; ++r) {
      const RobotInput robot = ReadRobot(world, r, map);
      auto [it, added] = planners_.try_emplace(r, options_);
      const StepOutput step = it->second.Step(floor, robot, t_s, services);
      all_done = all_done && step.done;
      wakeup = std::min(wakeup, step.wakeup_t_s);
      Emit(r, robot, step, map, robots > 1, out);
    }
    if (all_done) {
      out.SetDone(true);
      return;
    }
    out.RequestCall(wakeup);
  }

 private:
  void Emit(uint32_t r, const RobotInput& robot, const StepOutput& step, const vp_map_info& map,
            bool suffix, vp::PlanOutput& out) {
    std::string s;  // per-robot names only with several robots
    if (suffix) {
      s = "_";
      s += std::to_string(r);
    }
    const StepDiagnostics& d = step.diag;
    if (d.keyframe) {
      out.Diagnostic("field_ms" + s, d.field_ms);
      out.Diagnostic("interp_ms" + s, d.interp_ms);
      out.Diagnostic("census_ms" + s, d.census_ms);
      if (options_.topology_control) out.Diagnostic("control_ms" + s, d.control_ms);
      out.Diagnostic("census_degenerate" + s, d.census_degenerate);
      out.Diagnostic("census_vector" + s, d.census_vector);
      if (options_.topology_control) {
        out.Diagnostic("control_points_before" + s, d.control_points_before);
        out.Diagnostic("control_points_after" + s, d.control_points_after);
      }
    }
    out.Diagnostic("keyframe" + s, d.keyframe ? 1.0 : 0.0);
    out.Diagnostic("topology_ms" + s, d.topology_ms);
    out.Diagnostic("advect_ms" + s, d.advect_ms);
    out.Diagnostic("traj_ms" + s, d.traj_ms);
    out.Diagnostic("substep" + s, d.substep);
    out.Diagnostic("degenerate_points" + s, d.degenerate_points);
    out.Diagnostic("wedges" + s, d.wedges);
    out.Diagnostic("trisectors" + s, d.trisectors);
    out.Diagnostic("skeleton_edges" + s, d.skeleton_edges);
    out.Diagnostic("max_edge_gain" + s, d.max_edge_gain);
    out.Diagnostic("lookahead_gain" + s, d.lookahead_gain);
    out.Diagnostic("fallback_routes" + s, d.fallback_routes);
    out.Diagnostic("blocked" + s, d.blocked);
    out.Diagnostic("pathlines" + s, d.pathlines);
    out.Diagnostic("branch_choices" + s, d.branch_choices);
    out.Diagnostic("skeleton_routes" + s, d.skeleton_routes);
    if (options_.topology_control) {
      out.Diagnostic("cancelled_pairs" + s, d.cancelled_pairs);
      out.Diagnostic("corner_wedges" + s, d.corner_wedges);
      out.Diagnostic("retracted_wedges" + s, d.retracted_wedges);
      out.Diagnostic("moved_trisectors" + s, d.moved_trisectors);
    }
    out.Diagnostic("settled_goals" + s, d.settled_goals);
    if (options_.lookat && options_.camera != CameraMode::kFixed) {
      out.Diagnostic("lookat_samples" + s, d.lookat_samples);
      out.Diagnostic("lookat_seen" + s, d.lookat_seen);
      out.Diagnostic("lookat_changed" + s, d.lookat_changed);
      out.Diagnostic("lookat_m" + s, d.lookat_m);
    }
    if (options_.camera != CameraMode::kFixed) {
      out.Diagnostic("camera_stop" + s, d.camera_stop ? 1.0 : 0.0);
      out.Diagnostic("camera_stops" + s, d.camera_stops);
      out.Diagnostic("camera_jump_deg" + s, d.camera_jump_deg);
      out.Diagnostic("camera_radps_before" + s, d.camera_radps_before);
      out.Diagnostic("camera_radps_after" + s, d.camera_radps_after);
      out.Diagnostic("camera_connect_s" + s, d.camera_connect_s);
    }
    out.Diagnostic("mode" + s, double(d.mode));
    out.Diagnostic("stop" + s, d.stop);
    const float z = float(robot.camera_height_m) + map.floor_z_m;
    if (!step.degenerate_xy.empty())
      out.DebugPoints("tensorfield_degenerate", Xyz(step.degenerate_xy, z), kPointColor);
    for (const auto& e : step.skeleton_edges)
      if (e.size() >= 2) out.DebugPolyline("tensorfield_skeleton", Xyz(e, z), kSkeletonColor);
    for (const auto& glyph : step.field_glyphs)
      out.DebugPolyline("tensorfield_field", Xyz({glyph[0], glyph[1]}, z), kFieldColor);
    if (step.lookahead.size() >= 2)
      out.DebugPolyline("tensorfield_lookahead", Xyz(step.lookahead, z), kLookaheadColor);
    if (step.path.size() < 2) return;
    out.DebugPolyline("tensorfield_path", Xyz(step.path, z), kPathColor);
    std::vector<vp_path_point> points;
    for (size_t i = 0; i < step.path.size(); ++i)
      points.push_back(
          {float(step.path[i].x()), float(step.path[i].y()), float(step.headings_rad[i])});
    out.ReplaceTasks(r);
    out.SetContinuousPath(r, points, step.speeds_mps);
    std::vector<vp_camera_sample> camera;
    for (const CameraOut& c : step.camera) {
      vp_camera_sample sample{};
      sample.t_s = c.t_s;
      for (int k = 0; k < 3; ++k) sample.position[k] = c.position_m[k];
      sample.yaw_rad = c.yaw_rad;
      sample.pitch_rad = c.pitch_rad;
      camera.push_back(sample);
    }
    if (!camera.empty()) out.SetCameraTrajectory(r, camera);
  }

  PlannerOptions options_;
  std::map<uint32_t, RobotPlanner> planners_;
};

}  // namespace
}  // namespace voxplan::tensorfield

VP_PLANNER_EXPORT(voxplan::tensorfield::TensorfieldPlanner, "tensorfield", "1.0.0")
