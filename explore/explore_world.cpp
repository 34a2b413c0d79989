#include "explore/explore_world.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.h"

namespace voxplan {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
}  // namespace

ExploreWorld::ExploreWorld(const PlanningMap& map, const FloorMap& floor,
                           const ExploreWorldParams& params)
    : map_(&map), floor_map_(&floor), params_(params) {}

void ExploreWorld::MarkFootprint(const Eigen::Vector2f& p_W, float radius_m) {
  const float cell = floor_map_->cell_size_m() > 0.f
                         ? floor_map_->cell_size_m()
                         : map_->volume().voxel_size_m() * float(floor_map_->params().cell_voxels);
  const int x0 = int(std::floor((p_W.x() - radius_m) / cell));
  const int x1 = int(std::floor((p_W.x() + radius_m) / cell));
  const int y0 = int(std::floor((p_W.y() - radius_m) / cell));
  const int y1 = int(std::floor((p_W.y() + radius_m) / cell));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2f c((float(x) + 0.5f) * cell, (float(y) + 0.5f) * cell);
      if ((c - p_W).norm() > radius_m) continue;
      footprint_changed_ |= footprint_cells_.insert({x, y}).second;
    }
}

void ExploreWorld::Refresh() {
  const FloorMap& f = *floor_map_;
  if (have_floor_ && floor_revision_ == f.revision() && !footprint_changed_) return;
  const FloorGeometry& g = f.geometry();
  const int pad = g.width > 0 ? int(std::ceil(params_.unknown_margin_m / g.cell_size_m)) : 0;
  pad_ = pad;
  // The planner's raster: the floor map's, with `pad` unknown cells on every side.
  PlannerFloor& pf = floor_;
  pf.cell_size_m = g.cell_size_m;
  pf.width = g.width + 2 * pad;
  pf.height = g.height + 2 * pad;
  pf.origin_m = (g.origin_cell - Eigen::Vector2i::Constant(pad)).cast<float>() * g.cell_size_m;
  pf.cells.assign(size_t(pf.width) * size_t(pf.height), FloorCell::kUnknown);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) pf.cells[pf.Linear(x + pad, y + pad)] = f.At(x, y);
  // Footprint cells the map left unknown become free; then every free cell next to them is
  // frontier only if it still has an unknown 8-neighbour.
  std::vector<Eigen::Vector2i> changed;
  for (const auto& [gx, gy] : footprint_cells_) {
    const int x = gx - g.origin_cell.x() + pad, y = gy - g.origin_cell.y() + pad;
    if (!pf.Contains(x, y) || pf.cells[pf.Linear(x, y)] != FloorCell::kUnknown) continue;
    pf.cells[pf.Linear(x, y)] = FloorCell::kFree;
    changed.emplace_back(x, y);
  }
  auto has_unknown_neighbour = [&](int x, int y) {
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (pf.Contains(x + dx, y + dy) &&
            pf.cells[pf.Linear(x + dx, y + dy)] == FloorCell::kUnknown)
          return true;
    return false;
  };
  for (const Eigen::Vector2i& c : changed)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = c.x() + dx, y = c.y() + dy;
        if (!pf.Contains(x, y) || !IsFree(pf.cells[pf.Linear(x, y)])) continue;
        pf.cells[pf.Linear(x, y)] =
            has_unknown_neighbour(x, y) ? FloorCell::kFrontier : FloorCell::kFree;
      }
  // Clearance over the padded raster, as ComputeClearance does over the floor map's.
  Image<uint8_t> sites(pf.width, pf.height);
  for (size_t i = 0; i < pf.cells.size(); ++i)
    sites.data[i] = pf.cells[i] == FloorCell::kObstacle ? 1 : 0;
  const Image<float> d2 = SquaredDistanceTransform(sites);
  pf.clearance_m.resize(pf.cells.size());
  for (size_t i = 0; i < pf.cells.size(); ++i)
    pf.clearance_m[i] = std::isfinite(d2.data[i]) ? std::sqrt(d2.data[i]) * pf.cell_size_m : kInf;
  ++pf.revision;  // a new raster for the planner whenever either input changed
  floor_revision_ = f.revision();
  footprint_changed_ = false;
  have_floor_ = true;
}

PlannerMapInfo ExploreWorld::MapInfo() const {
  PlannerMapInfo info;
  // Both maps change together (one volume), but the floor map may lag by a step.
  info.revision = map_->revision() * 1000003ull + floor_.revision;  // both only grow
  info.voxel_size_m = map_->volume().voxel_size_m();
  info.floor_z_m = floor_map_->params().floor_z_m;
  info.bounds_min = {floor_.origin_m.x(), floor_.origin_m.y(), info.floor_z_m};
  info.bounds_max = {floor_.origin_m.x() + floor_.cell_size_m * float(floor_.width),
                     floor_.origin_m.y() + floor_.cell_size_m * float(floor_.height),
                     info.floor_z_m + params_.wall_height_m};
  return info;
}

// Both queries are answered point by point (ray by ray) in parallel: each answer depends on its
// own input and the map only, so the result is the same for any thread count.
void ExploreWorld::VoxelStates(std::span<const Eigen::Vector3f> points,
                               std::span<VoxelState> out) const {
  ParallelFor(points.size(), 1024, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) out[i] = map_->StateAt(points[i]);
  });
}

void ExploreWorld::Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const {
  // Half-voxel steps: enough to meet every voxel a ray crosses more than grazingly, and the
  // unobserved length is an estimate at that resolution anyway.
  const float step = 0.5f * map_->volume().voxel_size_m();
  const PlannerMapInfo info = MapInfo();
  const Eigen::Vector3f lo = info.bounds_min, hi = info.bounds_max;
  const float voxel = map_->volume().voxel_size_m();
  ParallelFor(rays.size(), 64, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const PlannerRay& ray = rays[i];
      PlannerRayHit hit;
      hit.distance_m = ray.max_range_m;
      // Consecutive half-voxel steps often stay in one voxel: its state is looked up once.
      GlobalVoxelIndex last{};
      VoxelState state = VoxelState::kUnobserved;
      bool have_last = false;
      for (float s = 0.f; s <= ray.max_range_m; s += step) {
        const Eigen::Vector3f p = ray.origin + s * ray.direction;
        if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) {
          hit.distance_m = s;
          hit.result = RayResult::kLeftMap;
          break;
        }
        const GlobalVoxelIndex g = VoxelAt(p, voxel);
        if (!have_last || !(g == last)) {
          state = map_->StateAt(g);
          last = g;
          have_last = true;
        }
        if (state == VoxelState::kOccupied) {
          hit.distance_m = s;
          hit.result = RayResult::kSurface;
          break;
        }
        if (state == VoxelState::kUnobserved) hit.unobserved_m += step;
      }
      out[i] = hit;
    }
  });
}

std::vector<Eigen::Vector3f> ExploreWorld::FrontierVoxels() const {
  const float voxel = map_->volume().voxel_size_m();
  std::vector<Eigen::Vector3f> out;
  for (const GlobalVoxelIndex& g : map_->FrontierVoxels()) out.push_back(VoxelCenter(g, voxel));
  return out;
}

std::vector<SurfaceVoxel> ExploreWorld::SurfaceVoxels() const {
  const std::vector<MapSurfaceVoxel> voxels = map_->SurfaceVoxels();
  std::vector<SurfaceVoxel> out(voxels.size());
  ParallelFor(voxels.size(), 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const MapSurfaceVoxel& v = voxels[i];
      SurfaceVoxel& s = out[i];
      s.position = v.center_W;
      s.normal = v.normal_W;
      s.uncertainty = std::clamp(v.uncertainty, 0.f, 1.f);
      s.weight = v.weight;
      s.instance = v.label == 0 ? -1 : int32_t(v.label);
    }
  });
  return out;
}

std::vector<ObjectInstance> ExploreWorld::Instances() const {
  std::vector<ObjectInstance> out;
  for (const InstanceRecord& r : map_->Instances()) {
    ObjectInstance o;
    o.id = r.id;
    o.label = r.class_name;
    o.bbox_min = r.bbox_min_W;
    o.bbox_max = r.bbox_max_W;
    out.push_back(o);
  }
  return out;
}

GeodesicParams ExploreWorld::Geodesic(float min_clearance_m) const {
  GeodesicParams p;
  p.robot_radius_m = min_clearance_m;
  p.unknown_traversable = false;
  p.clearance_from_unknown = false;
  p.snap_radius_m = params_.snap_radius_m;
  return p;
}

GeodesicCache& ExploreWorld::CacheFor(float min_clearance_m) const {
  return caches_[min_clearance_m];
}

Result<std::vector<float>> ExploreWorld::GeodesicField(const Eigen::Vector2f& source_m,
                                                       float min_clearance_m) const {
  if (floor_map_->width() <= 0) return Unsupported("the floor map is still empty");
  GeodesicCache& cache = CacheFor(min_clearance_m);
  // A planner reads the fields of all robots in turn: asked for one, compute every robot's at
  // once, in parallel (the cache keeps them for the calls that follow).
  std::vector<Eigen::Vector2f> robots_m;
  for (const PlannerRobot& r : robots_) robots_m.push_back(r.position_m);
  if (std::find(robots_m.begin(), robots_m.end(), source_m) != robots_m.end())
    cache.Prefetch(*floor_map_, robots_m, Geodesic(min_clearance_m));
  const std::shared_ptr<const DistanceField> field =
      cache.Field(*floor_map_, source_m, Geodesic(min_clearance_m));
  // Into the planner's padded raster (the margin is unknown: unreachable).
  const FloorGeometry& g = floor_map_->geometry();
  if (field->geometry != g || floor_.width != g.width + 2 * pad_)
    return Status(StatusCode::kInternal, "explore world: Refresh() missed a floor map change");
  std::vector<float> out(floor_.cells.size(), kInf);
  for (int y = 0; y < g.height; ++y)
    std::copy_n(&field->distance_m.at(0, y), g.width, &out[floor_.Linear(pad_, y + pad_)]);
  return out;
}

Result<std::vector<float>> ExploreWorld::DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
                                                        float min_clearance_m) const {
  if (floor_map_->width() <= 0) return Unsupported("the floor map is still empty");
  const Eigen::MatrixXf m =
      CacheFor(min_clearance_m).DistanceMatrix(*floor_map_, points_m, Geodesic(min_clearance_m));
  const size_t n = points_m.size();
  std::vector<float> out(n * n, kInf);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j) out[i * n + j] = m(Eigen::Index(i), Eigen::Index(j));
  return out;
}

Result<std::vector<Eigen::Vector2f>> ExploreWorld::ShortestPath(const Eigen::Vector2f& from_m,
                                                                const Eigen::Vector2f& to_m,
                                                                float min_clearance_m) const {
  if (floor_map_->width() <= 0) return Unsupported("the floor map is still empty");
  Result<std::vector<Eigen::Vector2f>> cells =
      CacheFor(min_clearance_m).Path(*floor_map_, from_m, to_m, Geodesic(min_clearance_m));
  if (!cells.ok()) return cells.status();
  // The cache's path runs between (snapped) cell centres; the ends are the points asked for.
  std::vector<Eigen::Vector2f> path = {from_m};
  for (const Eigen::Vector2f& c : *cells) {
    if ((c - path.back()).norm() > 1e-4f) path.push_back(c);
  }
  if ((to_m - path.back()).norm() > 1e-4f) path.push_back(to_m);
  return path;
}

}  // namespace voxplan
