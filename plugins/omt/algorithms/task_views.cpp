#include "plugins/omt/algorithms/task_views.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::omt {

double CellUncertainty(Cell cell, float tsdf_weight, const UncertaintyParams& params) {
  switch (cell) {
    case Cell::kFree:
      return 0.0;
    case Cell::kUnknown:
      return params.unknown_uncertainty;
    case Cell::kOccupied:
      break;
  }
  return 1.0 / (1.0 + std::max(0.0f, tsdf_weight) / params.weight_scale);
}

std::vector<Candidate> CollectCandidates(const OccupancyRaster& raster,
                                         const UncertaintyParams& params) {
  const RasterGeometry& g = raster.geometry;
  std::vector<Candidate> out;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int i = g.Index(x, y);
      const Cell c = raster.At(i);
      if (c == Cell::kFree) continue;
      const bool next_to_free = (x > 0 && raster.At(i - 1) == Cell::kFree) ||
                                (x + 1 < g.width && raster.At(i + 1) == Cell::kFree) ||
                                (y > 0 && raster.At(i - g.width) == Cell::kFree) ||
                                (y + 1 < g.height && raster.At(i + g.width) == Cell::kFree);
      if (!next_to_free || raster.SettledAt(i)) continue;
      const double u = CellUncertainty(c, raster.WeightAt(i), params);
      if (c == Cell::kOccupied && u < params.min_surface_uncertainty) continue;
      out.push_back({i, static_cast<float>(u)});
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.uncertainty > b.uncertainty;
  });
  return out;
}

double ViewImportance(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
                      const TaskViewParams& params, std::vector<int>* covered) {
  const RasterGeometry& g = raster.geometry;
  const SensorParams& s = params.sensor;
  const UncertaintyParams& u = params.uncertainty;
  const int start = g.IndexOf(p_m);
  // Angular step so neighbouring rays are half a cell apart at d_max: every cell in the fan
  // is reached; duplicates are merged below (a cell keeps its largest contribution).
  const double step = 0.5 * g.resolution_m / s.d_max_m;
  const int rays = std::max(1, static_cast<int>(std::ceil(s.fov_rad / step)));
  // Neighbouring rays cross the same cells near the view: a cell counts once, with the
  // largest gain any ray gives it. Per-thread scratch, reset after use, keeps this O(fan).
  thread_local std::vector<double> best_gain;
  thread_local std::vector<int> touched;
  if (best_gain.size() != static_cast<std::size_t>(g.NumCells()))
    best_gain.assign(static_cast<std::size_t>(g.NumCells()), -1.0);
  touched.clear();
  auto contribute = [&](int cell, double gain) {
    double& b = best_gain[static_cast<std::size_t>(cell)];
    if (b < 0.0) touched.push_back(cell);
    b = std::max(b, gain);
  };
  constexpr double kMinVisibility = 0.05;  // below this an unknown cell is not worth walking
  for (int r = 0; r <= rays; ++r) {
    const double yaw = yaw_rad - 0.5 * s.fov_rad + s.fov_rad * r / rays;
    const Eigen::Vector2d dir(std::cos(yaw), std::sin(yaw));
    double unknown_since = -1.0;
    TraverseRay(g, p_m, dir, s.d_max_m, [&](int cell, double t) {
      if (cell == start) return true;
      const Cell c = raster.At(cell);
      if (c == Cell::kFree) {
        // Unknown space ended in free space we already know: the ray stays transparent.
        unknown_since = -1.0;
        contribute(cell, 0.0);
        return true;
      }
      const double d = (g.Center(cell) - p_m).norm();  // free cells, the most, need none
      if (c == Cell::kOccupied) {
        const auto normal = SurfaceNormal(raster, cell, s);
        double phi = 1.0;
        if (normal) phi = AngleProfile(std::acos(std::clamp(dir.dot(-*normal), -1.0, 1.0)), s);
        const double q = phi * DistanceProfile(d, s);
        const double w = std::max(0.0f, raster.WeightAt(cell)) / u.weight_scale;
        const double gain =
            (unknown_since >= 0.0 ? std::exp(-(t - unknown_since) / u.unknown_decay_m) : 1.0) *
            (1.0 / (1.0 + w) - 1.0 / (1.0 + w + q * u.observation_weight));
        contribute(cell, raster.SettledAt(cell) ? 0.0 : gain);
        return false;
      }
      if (unknown_since < 0.0) unknown_since = t;
      const double visibility = std::exp(-(t - unknown_since) / u.unknown_decay_m);
      if (visibility < kMinVisibility) return false;
      contribute(cell, raster.SettledAt(cell)
                           ? 0.0
                           : u.unknown_uncertainty * DistanceProfile(d, s) * visibility);
      return true;
    });
  }
  // Summed in ascending cell order so the result does not depend on ray order.
  std::sort(touched.begin(), touched.end());
  double sum = 0.0;
  for (int cell : touched) {
    sum += best_gain[static_cast<std::size_t>(cell)];
    best_gain[static_cast<std::size_t>(cell)] = -1.0;
    if (covered) covered->push_back(cell);
  }
  const double scale = g.resolution_m / params.reference_cell_m;
  return sum * scale * scale;
}

namespace {

bool ViewCellUsable(const ClearanceRaster& clearance, const std::vector<std::uint8_t>* accessible,
                    double min_clearance_m, int cell) {
  if (clearance.At(cell) <= min_clearance_m) return false;
  return accessible == nullptr || (*accessible)[static_cast<std::size_t>(cell)] != 0;
}

// NoTV: the collision-free, accessible free cell nearest to the frontier target (within d_max).
int NearestUsableCell(const OccupancyRaster& raster, const ClearanceRaster& clearance,
                      const std::vector<std::uint8_t>* accessible, double min_clearance_m,
                      int target, double radius_m) {
  const RasterGeometry& g = raster.geometry;
  const int r = static_cast<int>(std::ceil(radius_m / g.resolution_m));
  const int tx = g.X(target);
  const int ty = g.Y(target);
  int best = -1;
  long best_d2 = 0;
  for (int y = std::max(0, ty - r); y <= std::min(g.height - 1, ty + r); ++y) {
    for (int x = std::max(0, tx - r); x <= std::min(g.width - 1, tx + r); ++x) {
      const int i = g.Index(x, y);
      if (raster.At(i) != Cell::kFree) continue;
      if (!ViewCellUsable(clearance, accessible, min_clearance_m, i)) continue;
      const long d2 = static_cast<long>(x - tx) * (x - tx) + static_cast<long>(y - ty) * (y - ty);
      if (d2 > static_cast<long>(r) * r) continue;
      if (best < 0 || d2 < best_d2) {  // scan order breaks ties: deterministic
        best = i;
        best_d2 = d2;
      }
    }
  }
  return best;
}

}  // namespace

std::vector<TaskView> ExtractTaskViews(const OccupancyRaster& raster,
                                       const ClearanceRaster& clearance,
                                       const TaskViewParams& params,
                                       const std::vector<std::uint8_t>* accessible) {
  const RasterGeometry& g = raster.geometry;
  std::vector<TaskView> views;
  if (g.NumCells() == 0 || params.max_views <= 0) return views;
  const std::vector<Candidate> queue = CollectCandidates(raster, params.uncertainty);
  std::vector<std::uint8_t> removed(static_cast<std::size_t>(g.NumCells()), 0);
  const double min_clearance = params.clearance_factor * params.robot_radius_m;
  std::vector<TargetView> seen;
  std::vector<int> covered;
  int heads = 0;
  for (const Candidate& head : queue) {
    if (static_cast<int>(views.size()) >= params.max_views || heads >= params.max_heads) break;
    if (removed[static_cast<std::size_t>(head.cell)]) continue;
    removed[static_cast<std::size_t>(head.cell)] = 1;
    ++heads;
    int view_cell = -1;
    float validness = 0.0f;
    if (params.frontier_points_only) {
      view_cell = NearestUsableCell(raster, clearance, accessible, min_clearance, head.cell,
                                    params.sensor.d_max_m);
      validness = 1.0f;
    } else {
      ViewsSeeingTarget(raster, head.cell, params.sensor, &seen);
      // ψ is flat on [d_min, d_max], so many views tie at the top; among those, the one
      // nearest the middle of the range sees the widest stretch with margin on both sides
      // (the first of equals wins: deterministic).
      const double d_mid = 0.5 * (params.sensor.d_min_m + params.sensor.d_max_m);
      constexpr float kTie = 1e-6f;
      double best_offset = 0.0;
      for (const TargetView& v : seen) {
        if (v.validness < validness - kTie) continue;
        const double offset = std::abs(v.distance_m - d_mid);
        if (v.validness <= validness + kTie && offset >= best_offset) continue;
        if (!ViewCellUsable(clearance, accessible, min_clearance, v.cell)) continue;
        view_cell = v.cell;
        validness = std::max(validness, v.validness);
        best_offset = offset;
      }
    }
    if (view_cell < 0) continue;
    TaskView view;
    view.position_m = g.Center(view_cell);
    const Eigen::Vector2d to_target = g.Center(head.cell) - view.position_m;
    view.yaw_rad = std::atan2(to_target.y(), to_target.x());
    view.cell = view_cell;
    view.target_cell = head.cell;
    view.target_unknown = raster.At(head.cell) == Cell::kUnknown;
    view.target_near_m = std::max(0.0, to_target.norm() - 0.5 * g.resolution_m);
    view.validness = validness;
    covered.clear();
    view.importance = ViewImportance(raster, view.position_m, view.yaw_rad, params, &covered);
    for (int c : covered) removed[static_cast<std::size_t>(c)] = 1;
    views.push_back(view);
  }
  if (params.sort_by_importance) {
    std::stable_sort(views.begin(), views.end(), [](const TaskView& a, const TaskView& b) {
      return a.importance > b.importance;
    });
  }
  return views;
}

double ViewCapacity(const SensorParams& sensor) {
  // ∫ψ(d) d dd over [0, d_max]: the ramp to d_min gives d_min² / 3, the flat part the rest.
  const double d_min = std::min(sensor.d_min_m, sensor.d_max_m);
  return sensor.fov_rad *
         (d_min * d_min / 3.0 + 0.5 * (sensor.d_max_m * sensor.d_max_m - d_min * d_min));
}

bool ShouldTerminate(const std::vector<TaskView>& views, double importance_threshold) {
  return std::none_of(views.begin(), views.end(),
                      [&](const TaskView& v) { return v.importance > importance_threshold; });
}

}  // namespace voxplan::omt
