#include "plugins/common/world_input.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::planners {

// ---- JsonOptions. ------------------------------------------------------------------------

JsonOptions::JsonOptions(std::string planner, const std::string& json_text)
    : planner_(std::move(planner)) {
  try {
    json_ = nlohmann::json::parse(json_text.empty() ? std::string("{}") : json_text);
  } catch (const nlohmann::json::exception& e) {
    throw vp::Error(VP_ERROR_INVALID_ARGUMENT,
                    planner_ + ": config is not valid JSON: " + std::string(e.what()));
  }
  if (!json_.is_object()) {
    throw vp::Error(VP_ERROR_INVALID_ARGUMENT, planner_ + ": config must be a JSON object");
  }
}

void JsonOptions::Fail(const std::string& key, const std::string& why) const {
  throw vp::Error(VP_ERROR_INVALID_ARGUMENT, planner_ + ": config key '" + key + "' " + why);
}

const nlohmann::json* JsonOptions::Find(const std::string& key) {
  read_.insert(key);
  const auto it = json_.find(key);
  return it == json_.end() ? nullptr : &*it;
}

double JsonOptions::Number(const std::string& key, double fallback, double min, double max) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return fallback;
  if (!v->is_number()) Fail(key, "must be a number");
  const double x = v->get<double>();
  if (!std::isfinite(x) || x < min || x > max) {
    Fail(key, "must lie in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return x;
}

int JsonOptions::Integer(const std::string& key, int fallback, int min, int max) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return fallback;
  if (!v->is_number_integer()) Fail(key, "must be an integer");
  const long long x = v->get<long long>();
  if (x < min || x > max) {
    Fail(key, "must lie in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return int(x);
}

bool JsonOptions::Flag(const std::string& key, bool fallback) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return fallback;
  if (!v->is_boolean()) Fail(key, "must be true or false");
  return v->get<bool>();
}

std::string JsonOptions::Choice(const std::string& key, const std::string& fallback,
                                const std::vector<std::string>& allowed) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return fallback;
  std::string names;
  for (const std::string& a : allowed) names += (names.empty() ? "\"" : ", \"") + a + "\"";
  if (!v->is_string()) Fail(key, "must be one of " + names);
  const std::string s = v->get<std::string>();
  if (std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
    Fail(key, "must be one of " + names + ", not \"" + s + "\"");
  }
  return s;
}

void JsonOptions::RejectUnknownKeys() const {
  for (const auto& item : json_.items()) {
    if (!read_.count(item.key())) Fail(item.key(), "is unknown");
  }
}

CommonOptions ReadCommonOptions(JsonOptions& json) {
  CommonOptions o;
  o.omt.kappa = json.Integer("kappa", o.omt.kappa, 1, 1000);
  o.omt.importance_threshold =
      json.Number("importance_threshold", o.omt.importance_threshold, 0.0, 1e9);
  o.omt.geodesic_cell_m = json.Number("geodesic_cell_m", o.omt.geodesic_cell_m, 1e-3, 10.0);
  o.omt.num_threads = json.Integer("num_threads", o.omt.num_threads, 1, 256);
  o.robot_radius_m = json.Number("robot_radius_m", o.robot_radius_m, 0.0, 10.0);
  o.clearance_margin_m = json.Number("clearance_margin_m", o.clearance_margin_m, 0.0, 10.0);
  o.dwell_s = json.Number("dwell_s", o.dwell_s, 0.0, 600.0);
  o.surface_min_height_m =
      json.Number("surface_min_height_m", o.surface_min_height_m, -100.0, 100.0);
  o.omt.views.uncertainty.weight_scale =
      json.Number("weight_scale", o.omt.views.uncertainty.weight_scale, 1e-6, 1e9);
  o.geodesics = json.Choice("geodesics", o.geodesics, {"host", "internal"});
  o.fov_from_robot = json.Flag("fov_from_robot", o.fov_from_robot);
  return o;
}

// ---- The world as OMT inputs. ------------------------------------------------------------

WorldInput ReadWorld(const vp::WorldView& world, const CommonOptions& options) {
  WorldInput in;
  in.map = world.MapInfo();
  const vp::FloorView floor = world.Floor();
  if (floor.width() <= 0 || floor.height() <= 0 || !(floor.cell_size_m() > 0.f)) {
    throw vp::Error(VP_ERROR_NOT_AVAILABLE, "the world has no floor raster");
  }
  omt::RasterGeometry& g = in.raster.geometry;
  g.width = floor.width();
  g.height = floor.height();
  g.resolution_m = floor.cell_size_m();
  g.origin_m = {floor.raw().origin_x_m, floor.raw().origin_y_m};
  const size_t n = floor.size();
  in.raster.cells.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t c = floor.cells()[i];
    in.raster.cells[i] = c == VP_FLOOR_OBSTACLE                           ? omt::Cell::kOccupied
                         : (c == VP_FLOOR_FREE || c == VP_FLOOR_FRONTIER) ? omt::Cell::kFree
                                                                          : omt::Cell::kUnknown;
  }
  in.clearance.geometry = g;
  // +inf (no obstacle at all) would turn the path smoother's interpolation into NaN; nothing
  // is farther than the raster's diagonal anyway.
  const float max_clearance_m = float(std::hypot(g.width, g.height) * g.resolution_m);
  in.clearance.clearance_m.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float c = floor.clearance_m()[i];
    in.clearance.clearance_m[i] = std::isnan(c) ? 0.f : std::min(c, max_clearance_m);
  }

  // Surface weight per obstacle cell: mean over the surface voxels standing on it (floor voxels,
  // below surface_min_height_m, belong to the floor, not to the obstacle).
  std::vector<double> weight_sum(n, 0.0);
  std::vector<uint32_t> weight_count(n, 0);
  const float min_z = in.map.floor_z_m + float(options.surface_min_height_m);
  const double surface_start_s = world.ElapsedS();
  const std::span<const vp_surface_voxel> surface = world.SurfaceVoxels();
  in.surface_voxels_ms = (world.ElapsedS() - surface_start_s) * 1e3;
  for (const vp_surface_voxel& s : surface) {
    if (!(s.position[2] >= min_z) || !std::isfinite(s.weight)) continue;
    const auto [ix, iy] = floor.CellOf(s.position[0], s.position[1]);
    if (!floor.Contains(ix, iy)) continue;
    const size_t i = floor.Linear(ix, iy);
    if (in.raster.cells[i] != omt::Cell::kOccupied) continue;
    weight_sum[i] += std::max(0.f, s.weight);
    ++weight_count[i];
  }
  in.raster.tsdf_weight.assign(n, 0.f);
  for (size_t i = 0; i < n; ++i) {
    if (weight_count[i] > 0) in.raster.tsdf_weight[i] = float(weight_sum[i] / weight_count[i]);
  }

  float max_radius_m = 0.f;
  for (uint32_t r = 0; r < world.RobotCount(); ++r) {
    const vp_robot robot = world.Robot(r);
    omt::RobotState state;
    state.position_m = {robot.x_m, robot.y_m};
    state.yaw_rad = omt::WrapAngle(double(robot.theta_rad) + robot.camera_yaw_rad);
    if (robot.mode >= 0 && uint32_t(robot.mode) < robot.mode_count) {
      const vp_mode_params mode = world.Mode(r, uint32_t(robot.mode));
      if (std::isfinite(mode.max_speed_mps) && mode.max_speed_mps > 0.f) {
        state.speed_mps = mode.max_speed_mps;
      }
      // The narrowest field of view and the shortest range over the robots (0: none yet).
      auto keep_smallest = [](double* smallest, float value) {
        *smallest = *smallest > 0.0 ? std::min(*smallest, double(value)) : double(value);
      };
      if (std::isfinite(mode.horizontal_fov_rad) && mode.horizontal_fov_rad > 0.f &&
          mode.horizontal_fov_rad < float(2.0 * omt::kPi)) {
        keep_smallest(&in.fov_rad, mode.horizontal_fov_rad);
      }
      if (std::isfinite(mode.vertical_fov_rad) && mode.vertical_fov_rad > 0.f &&
          mode.vertical_fov_rad < float(omt::kPi)) {
        keep_smallest(&in.vfov_rad, mode.vertical_fov_rad);
      }
      if (std::isfinite(mode.max_range_m) && mode.max_range_m > 0.f) {
        keep_smallest(&in.range_m, mode.max_range_m);
      }
    }
    max_radius_m = std::max(max_radius_m, robot.radius_m);
    in.robots.push_back(robot);
    in.states.push_back(state);
  }
  in.robot_radius_m = options.robot_radius_m > 0.0 ? options.robot_radius_m : double(max_radius_m);
  in.min_clearance_m = float(in.robot_radius_m + options.clearance_margin_m);

  // The host's clearance ignores unknown space, but the algorithms' internal grid and path
  // smoothing only look at clearance: capped at (distance to unknown + radius) they never route
  // through unknown cells (which the host would not traverse), views keep half a radius from
  // unknown, and the cap stays 1-Lipschitz as the grid's edge test assumes.
  if (std::find(in.raster.cells.begin(), in.raster.cells.end(), omt::Cell::kUnknown) !=
      in.raster.cells.end()) {
    const omt::ClearanceRaster known =
        omt::ComputeClearance(in.raster, /*unknown_is_obstacle=*/true);
    for (size_t i = 0; i < n; ++i) {
      in.clearance.clearance_m[i] =
          std::min(in.clearance.clearance_m[i], known.clearance_m[i] + float(in.robot_radius_m));
    }
  }
  return in;
}

void ReadHostReach(const vp::WorldView& world, WorldInput* input) {
  const size_t n = input->raster.cells.size();
  input->accessible.assign(n, 0);
  input->robot_fields.clear();
  input->anchored_robots = 0;
  for (const vp_robot& robot : input->robots) {
    const std::span<const float> field =
        world.GeodesicField(robot.x_m, robot.y_m, input->min_clearance_m);
    // The floor's size, as the raster's (ReadWorld read the same floor).
    assert(field.size() == n);
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(field[i])) continue;
      input->accessible[i] = 1;
      any = true;
    }
    input->anchored_robots += any;
    input->robot_fields.push_back(field);
  }
}

void SettledCells::Update(const vp::WorldView& world, const WorldInput& input,
                          const omt::SensorParams& sensor,
                          const omt::UncertaintyParams& uncertainty) {
  const omt::OccupancyRaster& raster = input.raster;
  const omt::RasterGeometry& g = raster.geometry;
  if (g.NumCells() == 0) return;
  auto key = [&](int cell) { return KeyOf(g, cell); };
  // Rays half a cell apart at the far range reach every cell of the fan.
  const double step = 0.5 * g.resolution_m / sensor.d_max_m;
  const int rays = std::max(1, int(std::ceil(sensor.fov_rad / step)));
  const int32_t event_robot = world.call().event_robot;
  if (world.event() == VP_EVENT_TASK_FAILED && event_robot >= 0) stalled_.insert(event_robot);
  for (size_t r = 0; r < input.robots.size(); ++r) {
    if (input.robots[r].status != VP_ROBOT_IDLE) continue;
    const auto given = given_.find(uint32_t(r));
    if (!TookItsView(uint32_t(r), input.robots[r])) {
      if (given != given_.end()) given_.erase(given);  // its targets were not taken either
      continue;
    }
    bool repeated = false;  // r just took a view of a target it had taken before
    if (given != given_.end()) {
      for (const Key& k : given->second) {
        if (++taken_[k] >= kRepeatLimit) {
          repeated = true;
          cells_.insert(k);
        }
      }
      given_.erase(given);
    }
    const Eigen::Vector2d p = input.states[r].position_m;
    const int start = g.IndexOf(p);
    // Unknown floor was looked at only where the camera, at its pitch, saw the whole cell and
    // the low end of its column: a voxel 0.1 m up, seen from 1.2 m, lies on a ray that meets
    // the floor a tenth further on, so the far end keeps a tenth of the range to spare.
    constexpr double kColumnSeenFraction = 0.9;
    const FloorBand floor = VisibleFloor(input.robots[r].camera_height_m, input.vfov_rad,
                                         input.robots[r].camera_pitch_rad, sensor.d_max_m);
    const double floor_from_m = floor.near_m + 0.5 * g.resolution_m;
    const double floor_to_m = kColumnSeenFraction * floor.far_m - 0.5 * g.resolution_m;
    for (int k = 0; k <= rays; ++k) {
      const double yaw = input.states[r].yaw_rad - 0.5 * sensor.fov_rad + sensor.fov_rad * k / rays;
      const Eigen::Vector2d dir(std::cos(yaw), std::sin(yaw));
      omt::TraverseRay(g, p, dir, sensor.d_max_m, [&](int cell, double) {
        if (cell == start) return true;
        const omt::Cell c = raster.At(cell);
        if (c == omt::Cell::kFree) return true;
        const double d = (g.Center(cell) - p).norm();
        const bool in_range = d >= sensor.d_min_m && d <= sensor.d_max_m;
        if (c == omt::Cell::kOccupied) {
          const double u = omt::CellUncertainty(c, raster.WeightAt(cell), uncertainty);
          // A surface gains weight with every look; only one that stays unscanned is settled.
          if (in_range && (repeated || u >= uncertainty.unknown_uncertainty))
            cells_.insert(key(cell));
          return false;
        }
        if (in_range && d >= floor_from_m && d <= floor_to_m) cells_.insert(key(cell));
        return true;
      });
    }
  }
}

bool SettledCells::TookItsView(uint32_t r, const vp_robot& robot) const {
  // The host drives a robot exactly onto its task's position; a centimetre allows for rounding.
  constexpr float kAtGoalM = 0.01f;
  if (stalled_.count(r)) return false;
  const auto goal = goal_.find(r);
  return goal == goal_.end() ||
         (Eigen::Vector2f(robot.x_m, robot.y_m) - goal->second).norm() <= kAtGoalM;
}

void SettledCells::Sent(uint32_t r, std::span<const vp_task> tasks, const omt::RasterGeometry& g,
                        const std::vector<omt::TaskView>& views, const std::vector<int>& ids) {
  if (tasks.empty()) {
    goal_.erase(r);  // it stops and looks where it stands; a stalled robot stays stalled
  } else {
    goal_[r] = {tasks.back().x_m, tasks.back().y_m};
    stalled_.erase(r);
  }
  std::vector<Key>& keys = given_[r];
  keys.clear();
  for (int id : ids) {
    const int cell = views[size_t(id)].target_cell;
    if (cell >= 0 && cell < g.NumCells()) keys.push_back(KeyOf(g, cell));
  }
  if (keys.empty()) given_.erase(r);
}

SettledCells::Key SettledCells::KeyOf(const omt::RasterGeometry& g, int cell) const {
  const Eigen::Vector2d c = g.Center(cell) / g.resolution_m;
  return {long(std::floor(c.x())), long(std::floor(c.y()))};
}

void SettledCells::Apply(const vp::WorldView& world, const omt::PlannerOptions& options,
                         WorldInput* input) {
  Update(world, *input, options.views.sensor, options.views.uncertainty);
  input->raster.settled = Mask(input->raster.geometry);
}

std::vector<uint8_t> SettledCells::Mask(const omt::RasterGeometry& g) const {
  std::vector<uint8_t> mask;
  if (cells_.empty()) return mask;
  mask.assign(size_t(g.NumCells()), 0);
  const long x0 = long(std::lround(g.origin_m.x() / g.resolution_m));
  const long y0 = long(std::lround(g.origin_m.y() / g.resolution_m));
  for (const auto& [x, y] : cells_) {
    const long ix = x - x0, iy = y - y0;
    if (ix >= 0 && iy >= 0 && ix < g.width && iy < g.height)
      mask[size_t(g.Index(int(ix), int(iy)))] = 1;
  }
  return mask;
}

omt::PlannerOptions PassOptions(const CommonOptions& options, const WorldInput& input) {
  omt::PlannerOptions o = options.omt;
  o.robot_radius_m = input.robot_radius_m;
  o.path_margin_m = options.clearance_margin_m;
  omt::SensorParams& s = o.views.sensor;
  // The host's angles and ranges are floats: a camera equal to the sensor is not narrower.
  constexpr double kRounding = 1e-5;
  if (input.fov_rad > 0.0 &&
      (options.fov_from_robot || input.fov_rad < s.fov_rad * (1 - kRounding)))
    s.fov_rad = input.fov_rad;
  if (input.range_m > 0.0 && input.range_m < s.d_max_m * (1 - kRounding)) {
    // Nothing is seen past the camera's range, however good the sensor model is there.
    s.d_max_m = s.d_inf_m = input.range_m;
    s.d_min_m = std::min(s.d_min_m, input.range_m);
  }
  o.importance_threshold *= omt::ViewCapacity(s) / omt::ViewCapacity(options.omt.views.sensor);
  return o;
}

omt::GeodesicProvider HostGeodesics(const vp::WorldView& world, float min_clearance_m,
                                    double* host_ms) {
  using Clock = std::chrono::steady_clock;
  const auto add_ms = [host_ms](Clock::time_point start) {
    *host_ms += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  };
  omt::GeodesicProvider p;
  p.distance_matrix = [&world, min_clearance_m, add_ms](const std::vector<Eigen::Vector2d>& points,
                                                        omt::DistanceMatrix* out) {
    const auto start = Clock::now();
    std::vector<float> xy;
    for (const Eigen::Vector2d& q : points) xy.insert(xy.end(), {float(q.x()), float(q.y())});
    const std::span<const float> m = world.DistanceMatrix(xy, min_clearance_m);
    const int count = int(points.size());
    *out = omt::DistanceMatrix(count, count);
    for (size_t i = 0; i < m.size(); ++i) out->values[i] = double(m[i]);
    add_ms(start);
    return true;
  };
  p.shortest_path = [&world, min_clearance_m, add_ms](const Eigen::Vector2d& a,
                                                      const Eigen::Vector2d& b,
                                                      std::vector<Eigen::Vector2d>* out) {
    const auto start = Clock::now();
    const auto path =
        world.ShortestPath(float(a.x()), float(a.y()), float(b.x()), float(b.y()), min_clearance_m);
    out->clear();
    if (path) {
      for (size_t i = 0; i + 1 < path->size(); i += 2) {
        out->emplace_back((*path)[i], (*path)[i + 1]);
      }
    }
    add_ms(start);
    return !out->empty();
  };
  return p;
}

// ---- Output. -----------------------------------------------------------------------------

std::vector<vp_path_point> PathWithHeadings(const std::vector<Eigen::Vector2d>& points_m,
                                            double start_theta_rad) {
  // Steps shorter than this keep the previous heading (a direction from noise is meaningless).
  constexpr double kMinStepM = 1e-4;
  std::vector<vp_path_point> path;
  double theta = start_theta_rad;
  for (size_t i = 0; i < points_m.size(); ++i) {
    if (i > 0) {
      const Eigen::Vector2d step = points_m[i] - points_m[i - 1];
      if (step.norm() > kMinStepM) theta = std::atan2(step.y(), step.x());
    }
    path.push_back({float(points_m[i].x()), float(points_m[i].y()), float(theta)});
  }
  return path;
}

FloorBand VisibleFloor(double camera_height_m, double vfov_rad, double pitch_rad, double range_m) {
  FloorBand band{0.0, range_m};
  if (!(vfov_rad > 0.0) || !(camera_height_m > 0.0)) return band;
  // The field's lower and upper edges, as angles below the horizon.
  const double lower_rad = 0.5 * vfov_rad - pitch_rad, upper_rad = -0.5 * vfov_rad - pitch_rad;
  if (lower_rad <= 0.0) return {std::numeric_limits<double>::infinity(), 0.0};  // no floor
  if (lower_rad < 0.5 * omt::kPi) band.near_m = camera_height_m / std::tan(lower_rad);
  if (upper_rad > 0.0) band.far_m = std::min(range_m, camera_height_m / std::tan(upper_rad));
  return band;
}

float ViewPitch(const omt::TaskView& view, const vp_robot& robot, double vfov_rad) {
  double pitch = 0.0;
  if (view.target_unknown && vfov_rad > 0.0 && robot.camera_height_m > 0.f) {
    const double below_rad = std::atan2(double(robot.camera_height_m), view.target_near_m);
    pitch = std::min(0.0, 0.5 * vfov_rad - below_rad);
  }
  return std::clamp(float(pitch), robot.min_pitch_rad, robot.max_pitch_rad);
}

vp_task TaskFromView(const omt::TaskView& view, double theta_rad, const vp_robot& robot,
                     double vfov_rad, double dwell_s) {
  vp_task t{};
  t.x_m = float(view.position_m.x());
  t.y_m = float(view.position_m.y());
  t.theta_rad = float(omt::WrapAngle(theta_rad));
  t.camera_yaw_rad = float(omt::WrapAngle(view.yaw_rad - theta_rad));
  t.camera_pitch_rad = ViewPitch(view, robot, vfov_rad);
  t.dwell_s = float(dwell_s);
  t.mode = robot.mode >= 0 && uint32_t(robot.mode) < robot.mode_count ? robot.mode : 0;
  t.tag = uint32_t(std::max(view.target_cell, 0));
  return t;
}

std::vector<float> ViewPointsXyz(const std::vector<omt::TaskView>& views, float z_m) {
  std::vector<float> xyz;
  for (const omt::TaskView& v : views) {
    xyz.insert(xyz.end(), {float(v.position_m.x()), float(v.position_m.y()), z_m});
  }
  return xyz;
}

}  // namespace voxplan::planners
