#include "plugins/omt/algorithms/validness.h"

#include <algorithm>
#include <cmath>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::omt {

double DistanceProfile(double d_m, const SensorParams& params) {
  if (d_m <= 0.0 || d_m >= params.d_inf_m) return 0.0;
  if (d_m < params.d_min_m) return d_m / params.d_min_m;
  if (d_m <= params.d_max_m) return 1.0;
  return (params.d_inf_m - d_m) / (params.d_inf_m - params.d_max_m);
}

double AngleProfile(double alpha_rad, const SensorParams& params) {
  return std::exp(-(alpha_rad * alpha_rad) / (params.sigma_rad * params.sigma_rad));
}

std::optional<Eigen::Vector2d> SurfaceNormal(const OccupancyRaster& raster, int cell,
                                             const SensorParams& params) {
  const RasterGeometry& g = raster.geometry;
  const int cx = g.X(cell);
  const int cy = g.Y(cell);
  const int r = params.normal_radius_cells;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if ((dx == 0 && dy == 0) || !g.InBounds(cx + dx, cy + dy)) continue;
      if (raster.At(g.Index(cx + dx, cy + dy)) != Cell::kFree) continue;
      sum += Eigen::Vector2d(dx, dy).normalized();
    }
  }
  // Below half a unit vector the free cells surround the cell: no meaningful surface side.
  if (sum.norm() < 0.5) return std::nullopt;
  return sum.normalized();
}

namespace {

// φ for a view looking along dir at a surface with optional normal n (pointing to free space).
double AngleTerm(const Eigen::Vector2d& dir, const std::optional<Eigen::Vector2d>& normal,
                 const SensorParams& params) {
  if (!normal) return 1.0;
  const double c = std::clamp(dir.dot(-*normal), -1.0, 1.0);
  return AngleProfile(std::acos(c), params);
}

}  // namespace

RayHit CastRay(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
               const SensorParams& params) {
  RayHit hit;
  const int start = raster.geometry.IndexOf(p_m);
  const Eigen::Vector2d dir(std::cos(yaw_rad), std::sin(yaw_rad));
  TraverseRay(raster.geometry, p_m, dir, params.d_inf_m, [&](int cell, double t) {
    if (cell == start) return true;
    const Cell c = raster.At(cell);
    if (c == Cell::kFree) return true;
    hit.kind = c == Cell::kOccupied ? RayHit::Kind::kOccupied : RayHit::Kind::kUnknown;
    hit.cell = cell;
    hit.distance_m = (raster.geometry.Center(cell) - p_m).norm();
    return false;
  });
  return hit;
}

double ViewValidness(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
                     const SensorParams& params) {
  const RayHit hit = CastRay(raster, p_m, yaw_rad, params);
  if (hit.kind != RayHit::Kind::kOccupied) return 1.0;
  const Eigen::Vector2d dir(std::cos(yaw_rad), std::sin(yaw_rad));
  return AngleTerm(dir, SurfaceNormal(raster, hit.cell, params), params) *
         DistanceProfile(hit.distance_m, params);
}

ValidnessMap ComputeValidnessMap(const OccupancyRaster& raster, const SensorParams& params) {
  ValidnessMap map;
  map.geometry = raster.geometry;
  map.bins = params.angle_bins;
  const int n = raster.geometry.NumCells();
  map.values.assign(static_cast<std::size_t>(n) * map.bins, -1.0f);
  // Normals are shared by the many rays that end on the same cell.
  std::vector<float> normal_cache(static_cast<std::size_t>(n) * 3, 0.0f);
  for (int i = 0; i < n; ++i) {
    if (raster.At(i) != Cell::kFree) continue;
    const Eigen::Vector2d p = raster.geometry.Center(i);
    for (int b = 0; b < map.bins; ++b) {
      const double yaw = BinYaw(b, params);
      const RayHit hit = CastRay(raster, p, yaw, params);
      float rho = 1.0f;
      if (hit.kind == RayHit::Kind::kOccupied) {
        float* nc = &normal_cache[static_cast<std::size_t>(hit.cell) * 3];
        if (nc[2] == 0.0f) {
          const auto normal = SurfaceNormal(raster, hit.cell, params);
          nc[2] = normal ? 1.0f : -1.0f;
          if (normal) {
            nc[0] = static_cast<float>(normal->x());
            nc[1] = static_cast<float>(normal->y());
          }
        }
        std::optional<Eigen::Vector2d> normal;
        if (nc[2] > 0.0f) normal = Eigen::Vector2d(nc[0], nc[1]);
        const Eigen::Vector2d dir(std::cos(yaw), std::sin(yaw));
        rho = static_cast<float>(AngleTerm(dir, normal, params) *
                                 DistanceProfile(hit.distance_m, params));
      }
      map.values[static_cast<std::size_t>(i) * map.bins + b] = rho;
    }
  }
  return map;
}

void ViewsSeeingTarget(const OccupancyRaster& raster, int target_cell, const SensorParams& params,
                       std::vector<TargetView>* out) {
  out->clear();
  const RasterGeometry& g = raster.geometry;
  const Eigen::Vector2d target = g.Center(target_cell);
  const auto normal = SurfaceNormal(raster, target_cell, params);
  for (int b = 0; b < params.angle_bins; ++b) {
    const double yaw = BinYaw(b, params);
    const Eigen::Vector2d dir(std::cos(yaw), std::sin(yaw));
    const double phi = AngleTerm(dir, normal, params);
    // Walk from the target against the viewing direction; every free cell passed sees it.
    TraverseRay(g, target, -dir, params.d_inf_m, [&](int cell, double) {
      if (cell == target_cell) return true;
      if (raster.At(cell) != Cell::kFree) return false;
      const double d = (g.Center(cell) - target).norm();
      if (d >= params.d_inf_m) return false;
      const double rho = phi * DistanceProfile(d, params);
      if (rho > 0.0) out->push_back({cell, b, d, static_cast<float>(rho)});
      return true;
    });
  }
}

}  // namespace voxplan::omt
