// Grid primitives for the OMT planner: 2-D DDA ray traversal and the clearance transform.
#pragma once

#include <cmath>
#include <limits>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

// Amanatides–Woo DDA: visits the cells a ray from p_m along unit dir crosses, starting with
// the cell containing p_m, while the entry distance stays <= max_dist_m. visit(cell, t_entry_m)
// returns false to stop. Rays leaving the raster stop there.
template <class Visit>
void TraverseRay(const RasterGeometry& g, const Eigen::Vector2d& p_m, const Eigen::Vector2d& dir,
                 double max_dist_m, Visit&& visit) {
  const Eigen::Vector2d q = (p_m - g.origin_m) / g.resolution_m;
  int x = static_cast<int>(std::floor(q.x()));
  int y = static_cast<int>(std::floor(q.y()));
  if (!g.InBounds(x, y)) return;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const int step_x = dir.x() > 0 ? 1 : -1;
  const int step_y = dir.y() > 0 ? 1 : -1;
  const double res = g.resolution_m;
  const double t_delta_x = dir.x() != 0.0 ? res / std::abs(dir.x()) : kInf;
  const double t_delta_y = dir.y() != 0.0 ? res / std::abs(dir.y()) : kInf;
  double t_max_x =
      dir.x() != 0.0 ? ((dir.x() > 0 ? (x + 1 - q.x()) : (q.x() - x)) * t_delta_x) : kInf;
  double t_max_y =
      dir.y() != 0.0 ? ((dir.y() > 0 ? (y + 1 - q.y()) : (q.y() - y)) * t_delta_y) : kInf;
  double t = 0.0;
  while (t <= max_dist_m) {
    if (!visit(g.Index(x, y), t)) return;
    if (t_max_x < t_max_y) {
      t = t_max_x;
      t_max_x += t_delta_x;
      x += step_x;
    } else {
      t = t_max_y;
      t_max_y += t_delta_y;
      y += step_y;
    }
    if (!g.InBounds(x, y)) return;
  }
}

// Euclidean distance (metres) from every cell centre to the nearest obstacle cell centre,
// obstacles being occupied cells and, when unknown_is_obstacle, unknown ones. Exact
// (Felzenszwalb–Huttenlocher separable transform). Cells outside the raster are not obstacles;
// with no obstacle at all the clearance is a large finite value.
ClearanceRaster ComputeClearance(const OccupancyRaster& raster, bool unknown_is_obstacle = true);

// True when every point of segment a-b, sampled at half the raster resolution, has clearance
// >= min_clearance_m.
bool SegmentClear(const ClearanceRaster& clearance, const Eigen::Vector2d& a,
                  const Eigen::Vector2d& b, double min_clearance_m);

// Bilinear clearance at a world point (clamped at the border).
double ClearanceBilinear(const ClearanceRaster& clearance, const Eigen::Vector2d& p_m);

}  // namespace voxplan::omt
