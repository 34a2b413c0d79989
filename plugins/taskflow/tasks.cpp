#include "plugins/taskflow/tasks.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace voxplan::taskflow {

namespace {

omt::RasterGeometry GeometryOf(const vp::FloorView& floor) {
  omt::RasterGeometry g;
  g.width = floor.width();
  g.height = floor.height();
  g.resolution_m = floor.cell_size_m();
  g.origin_m = {floor.raw().origin_x_m, floor.raw().origin_y_m};
  return g;
}

// The reconstructor's camera and workspace as the host describes the mode.
ReconViewParams ViewParamsOf(const vp_mode_params& m, const vp_robot& robot, ReconViewParams p) {
  p.sensor.hfov_rad = m.horizontal_fov_rad;
  p.sensor.min_range_m = m.min_range_m;
  p.sensor.max_range_m = m.max_range_m;
  if (m.mount == VP_MOUNT_ARM) {
    p.arm.camera_height_min_m = m.camera_height_min_m;
    p.arm.camera_height_max_m = m.camera_height_max_m;
    p.arm.reach_min_m = m.reach_min_m;
    p.arm.reach_max_m = m.reach_max_m;
    p.arm.reach_half_angle_rad = m.reach_half_angle_rad;
  } else {  // a head: the camera over the base centre at its one height
    p.arm.camera_height_min_m = p.arm.camera_height_max_m = robot.camera_height_m;
    p.arm.reach_min_m = p.arm.reach_max_m = 0.f;
    p.arm.reach_half_angle_rad = 0.f;
  }
  p.arm.min_pitch_rad = m.min_pitch_rad;
  p.arm.max_pitch_rad = m.max_pitch_rad;
  return p;
}

}  // namespace

bool IsStructureLabel(const std::string& label) {
  static const std::array<const char*, 6> kStructure = {"wall", "floor",  "ceiling",
                                                        "door", "window", "structure"};
  return std::find(kStructure.begin(), kStructure.end(), label) != kStructure.end();
}

TaskGenerator::Key TaskGenerator::KeyOf(const Eigen::Vector2d& xy) const {
  return {long(std::floor(xy.x() / options_.frontier_key_m)),
          long(std::floor(xy.y() / options_.frontier_key_m))};
}

std::vector<Candidate> TaskGenerator::Generate(const vp::WorldView& world, float radius_m,
                                               const std::set<int>& queued_objects, uint64_t seed,
                                               GenerationStats* stats) {
  const float clearance = radius_m + float(options_.clearance_margin_m);
  std::vector<Candidate> out = Exploration(world, clearance, stats);
  if (options_.completion_on) {
    std::vector<Candidate> recon = Reconstruction(world, clearance, queued_objects, seed, stats);
    out.insert(out.end(), recon.begin(), recon.end());
  }
  return out;
}

std::vector<Candidate> TaskGenerator::Exploration(const vp::WorldView& world, float clearance_m,
                                                  GenerationStats* stats) {
  const double t0 = world.ElapsedS();
  const vp::FloorView floor = world.Floor();
  std::vector<Candidate> out;
  keys_.clear();
  if (floor.width() <= 0 || floor.height() <= 0) return out;
  const omt::RasterGeometry g = GeometryOf(floor);
  // Frontier cells covered by views sent often enough, still frontier: what the sensor cannot
  // resolve from there (a column the floor map never sees whole) is settled, so a round does not
  // offer it forever.
  std::vector<uint8_t> cells(floor.cells().begin(), floor.cells().end());
  for (int i = 0; i < g.NumCells(); ++i) {
    if (cells[size_t(i)] != VP_FLOOR_FRONTIER) continue;
    const auto it = frontier_tries_.find(KeyOf(g.Center(i)));
    if (it != frontier_tries_.end() && it->second >= options_.frontier_tries) {
      cells[size_t(i)] = VP_FLOOR_FREE;
      ++stats->settled_frontiers;
    }
  }
  ExploreInput in;
  in.floor = {g, cells, floor.clearance_m()};
  const uint32_t robots = world.RobotCount();
  for (uint32_t r = 0; r < robots; ++r) {
    const vp_robot robot = world.Robot(r);
    in.robots_xy_m.emplace_back(robot.x_m, robot.y_m);
    in.geodesic_m.push_back(world.GeodesicField(robot.x_m, robot.y_m, clearance_m));
  }
  const vp_mode_params explorer = world.Mode(0, VP_MODE_EXPLORER);
  in.camera = {explorer.horizontal_fov_rad, explorer.min_range_m, explorer.max_range_m};
  ExploreParams params = options_.explore;
  params.min_clearance_m = clearance_m;
  const ExploreResult result = GenerateExplorationTasks(in, params);
  if (!result.status.ok())
    throw vp::Error(VP_ERROR_PLUGIN, "taskflow: exploration tasks: " + result.status.message);
  for (int cell : result.frontier_samples) keys_.push_back(KeyOf(g.Center(cell)));
  for (const ExploreView& v : result.views) {
    Candidate c;
    c.xy_m = v.xy_m;
    c.theta_rad = float(v.theta_rad);
    c.covers = v.covered;
    out.push_back(std::move(c));
  }
  stats->frontier_samples = int(result.frontier_samples.size());
  stats->exploration_views = int(out.size());
  stats->explore_ms = (world.ElapsedS() - t0) * 1e3;
  return out;
}

std::vector<Candidate> TaskGenerator::Reconstruction(const vp::WorldView& world, float clearance_m,
                                                     const std::set<int>& queued_objects,
                                                     uint64_t seed, GenerationStats* stats) {
  double t0 = world.ElapsedS();
  const vp_map_info map = world.MapInfo();
  const vp::FloorView floor = world.Floor();
  const float floor_z = map.floor_z_m;
  const SpaceQuery space = [&](std::span<const Eigen::Vector3f> points, std::span<uint8_t> state) {
    std::vector<float> xyz;
    xyz.reserve(points.size() * 3);
    for (const Eigen::Vector3f& p : points) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    const std::vector<uint8_t> s = world.VoxelStates(xyz);
    std::copy(s.begin(), s.end(), state.begin());  // VP_VOXEL_* are SpaceState's values
  };
  // Which objects need views, most incomplete first.
  std::vector<std::pair<float, int>> incomplete;
  for (const vp_instance& instance : world.Instances()) {
    if (IsStructureLabel(instance.label ? instance.label : "")) continue;
    const std::span<const vp_surface_voxel> surface = world.InstanceSurface(instance.id);
    if (int(surface.size()) < options_.min_object_voxels) continue;
    ++stats->objects;
    const int id = int(instance.id);
    ObjectState& object = objects_[id];
    ObserveCompleteness(&history_, id, double(surface.size()), options_.history);
    const double change = std::abs(double(surface.size()) - double(object.voxels)) /
                          std::max(1.0, double(object.voxels));
    if (object.voxels == 0 || change >= options_.recomplete_share) {  // complete it again
      std::vector<Eigen::Vector3f> points, normals;
      for (const vp_surface_voxel& v : surface) {
        points.emplace_back(v.position[0], v.position[1], v.position[2]);
        normals.emplace_back(v.normal[0], v.normal[1], v.normal[2]);
      }
      object.completion =
          CompleteObject(points, normals, floor_z, space, options_.completion, seed ^ uint64_t(id));
      object.voxels = surface.size();
      ++stats->objects_completed;
    }
    stats->incompleteness.emplace_back(id, double(object.completion.mean_score));
    if (!object.completion.incomplete) continue;
    ++stats->objects_incomplete;
    if (!queued_objects.count(id)) incomplete.emplace_back(object.completion.incompleteness, id);
  }
  std::sort(incomplete.begin(), incomplete.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  stats->completion_ms = (world.ElapsedS() - t0) * 1e3;
  t0 = world.ElapsedS();

  // Where a base may stand: a known traversable cell some robot can reach.
  const uint32_t robots = world.RobotCount();
  std::vector<std::span<const float>> fields;
  for (uint32_t r = 0; r < robots; ++r) {
    const vp_robot robot = world.Robot(r);
    fields.push_back(world.GeodesicField(robot.x_m, robot.y_m, clearance_m));
  }
  const TraversableFn traversable = [&](const Eigen::Vector2f& xy) {
    const auto [ix, iy] = floor.CellOf(xy.x(), xy.y());
    const uint8_t c = floor.Cell(ix, iy);
    if ((c != VP_FLOOR_FREE && c != VP_FLOOR_FRONTIER) || floor.Clearance(ix, iy) < clearance_m)
      return false;
    for (const std::span<const float>& f : fields)
      if (std::isfinite(f[floor.Linear(ix, iy)])) return true;
    return false;
  };
  // Line of sight on the map: nothing occupied before the point (two voxels of slack, the
  // predicted point may sit on the surface it belongs to).
  const float slack = 2.f * map.voxel_size_m;
  const VisibilityFn visible = [&](const Eigen::Vector3f& camera,
                                   std::span<const Eigen::Vector3f> points,
                                   std::span<uint8_t> out) {
    std::vector<vp_ray> rays(points.size());
    std::vector<float> length(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3f d = points[i] - camera;
      length[i] = d.norm();
      const Eigen::Vector3f u =
          length[i] > 0.f ? Eigen::Vector3f(d / length[i]) : Eigen::Vector3f::UnitX();
      rays[i] = {{camera.x(), camera.y(), camera.z()}, {u.x(), u.y(), u.z()}, length[i]};
    }
    const std::vector<vp_ray_hit> hits = world.Raycast(rays);
    for (size_t i = 0; i < points.size(); ++i)
      out[i] = !(hits[i].result == VP_RAY_SURFACE && hits[i].distance_m < length[i] - slack);
  };
  const ReconViewParams params =
      ViewParamsOf(world.Mode(0, VP_MODE_RECONSTRUCTOR), world.Robot(0), options_.views);
  std::vector<Candidate> out;
  const size_t want = size_t(std::max(0, options_.recon_views_per_robot)) * robots;
  int tried = 0;
  for (const auto& [incompleteness, id] : incomplete) {
    if (out.size() >= want || tried >= options_.max_objects_per_round) break;
    ObjectState& object = objects_.at(id);
    if (object.no_views_at == object.voxels || object.rounds >= options_.max_rounds_per_object)
      continue;
    const double gained = double(object.voxels) / std::max(1.0, double(object.voxels_sent)) - 1.0;
    if (object.rounds > 0 && gained < options_.history.min_gain_rel) continue;
    ++tried;
    const ReconTarget target = TargetFromCompletion(id, floor_z, object.completion);
    const std::vector<ReconView> views = SelectReconViews(
        target, params, traversable, visible, FindHistory(history_, id), options_.history);
    // The camera must stand in observed free space (the host refuses anything else).
    std::vector<float> cameras;
    for (const ReconView& v : views)
      cameras.insert(cameras.end(), {v.camera_m.x(), v.camera_m.y(), v.camera_m.z()});
    const std::vector<uint8_t> states = world.VoxelStates(cameras);
    const size_t before = out.size();
    for (size_t i = 0; i < views.size(); ++i) {
      if (states[i] != VP_VOXEL_FREE) continue;
      const ReconView& v = views[i];
      Candidate c;
      c.xy_m = v.base_xy_m.cast<double>();
      c.theta_rad = v.base_yaw_rad;
      c.reconstruction = true;
      c.recon = v;
      out.push_back(std::move(c));
    }
    if (out.size() == before) object.no_views_at = object.voxels;
  }
  stats->reconstruction_views = int(out.size());
  stats->recon_ms = (world.ElapsedS() - t0) * 1e3;
  return out;
}

void TaskGenerator::Sent(const std::vector<Candidate>& sent) {
  for (const Candidate& c : sent) {
    if (c.reconstruction) continue;
    for (int sample : c.covers)
      if (sample >= 0 && size_t(sample) < keys_.size()) ++frontier_tries_[keys_[size_t(sample)]];
  }
}

void TaskGenerator::SentViews(int object_id, const std::vector<ReconView>& views) {
  const auto it = objects_.find(object_id);
  const double completeness = it == objects_.end() ? 0.0 : double(it->second.voxels);
  if (it != objects_.end()) {
    ++it->second.rounds;
    it->second.voxels_sent = it->second.voxels;
  }
  RecordViews(&history_, object_id, views, completeness);
}

}  // namespace voxplan::taskflow
