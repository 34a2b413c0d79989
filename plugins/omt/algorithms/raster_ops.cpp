#include "plugins/omt/algorithms/raster_ops.h"

#include <algorithm>
#include <vector>

namespace voxplan::omt {
namespace {

// 1-D squared distance transform of f (Felzenszwalb & Huttenlocher 2012), in cell units.
void Transform1d(const std::vector<double>& f, int n, std::vector<double>* d, std::vector<int>* v,
                 std::vector<double>* z) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int k = 0;
  (*v)[0] = 0;
  (*z)[0] = -kInf;
  (*z)[1] = kInf;
  for (int q = 1; q < n; ++q) {
    if (f[q] == kInf) continue;
    if (f[(*v)[k]] == kInf) {
      (*v)[k] = q;
      continue;
    }
    double s = ((f[q] + q * q) - (f[(*v)[k]] + (*v)[k] * (*v)[k])) / (2.0 * q - 2.0 * (*v)[k]);
    while (s <= (*z)[k]) {
      --k;
      s = ((f[q] + q * q) - (f[(*v)[k]] + (*v)[k] * (*v)[k])) / (2.0 * q - 2.0 * (*v)[k]);
    }
    ++k;
    (*v)[k] = q;
    (*z)[k] = s;
    (*z)[k + 1] = kInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while ((*z)[k + 1] < q) ++k;
    const double dq = q - (*v)[k];
    (*d)[q] = f[(*v)[k]] == kInf ? kInf : dq * dq + f[(*v)[k]];
  }
}

}  // namespace

ClearanceRaster ComputeClearance(const OccupancyRaster& raster, bool unknown_is_obstacle) {
  const RasterGeometry& g = raster.geometry;
  ClearanceRaster out;
  out.geometry = g;
  out.clearance_m.assign(static_cast<std::size_t>(g.NumCells()), 0.0f);
  if (g.NumCells() == 0) return out;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> grid(static_cast<std::size_t>(g.NumCells()));
  for (int i = 0; i < g.NumCells(); ++i) {
    const Cell c = raster.At(i);
    const bool obstacle = c == Cell::kOccupied || (unknown_is_obstacle && c == Cell::kUnknown);
    grid[static_cast<std::size_t>(i)] = obstacle ? 0.0 : kInf;
  }
  const int n = std::max(g.width, g.height);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int x = 0; x < g.width; ++x) {  // columns
    for (int y = 0; y < g.height; ++y) f[y] = grid[g.Index(x, y)];
    Transform1d(f, g.height, &d, &v, &z);
    for (int y = 0; y < g.height; ++y) grid[g.Index(x, y)] = d[y];
  }
  for (int y = 0; y < g.height; ++y) {  // rows
    for (int x = 0; x < g.width; ++x) f[x] = grid[g.Index(x, y)];
    Transform1d(f, g.width, &d, &v, &z);
    for (int x = 0; x < g.width; ++x) grid[g.Index(x, y)] = d[x];
  }
  // No obstacle anywhere: the raster diagonal bounds every useful clearance.
  const double cap = g.resolution_m * std::hypot(g.width, g.height);
  for (int i = 0; i < g.NumCells(); ++i) {
    const double dist = std::sqrt(grid[static_cast<std::size_t>(i)]) * g.resolution_m;
    out.clearance_m[static_cast<std::size_t>(i)] = static_cast<float>(std::min(dist, cap));
  }
  return out;
}

bool SegmentClear(const ClearanceRaster& clearance, const Eigen::Vector2d& a,
                  const Eigen::Vector2d& b, double min_clearance_m) {
  const double len = (b - a).norm();
  const double step = 0.5 * clearance.geometry.resolution_m;
  const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / n);
    if (clearance.AtPoint(p) < min_clearance_m) return false;
  }
  return true;
}

double ClearanceBilinear(const ClearanceRaster& clearance, const Eigen::Vector2d& p_m) {
  const RasterGeometry& g = clearance.geometry;
  const Eigen::Vector2d q = (p_m - g.origin_m) / g.resolution_m - Eigen::Vector2d(0.5, 0.5);
  const double qx = std::clamp(q.x(), 0.0, g.width - 1.0);
  const double qy = std::clamp(q.y(), 0.0, g.height - 1.0);
  const int x0 = std::min(static_cast<int>(qx), g.width - 2 < 0 ? 0 : g.width - 2);
  const int y0 = std::min(static_cast<int>(qy), g.height - 2 < 0 ? 0 : g.height - 2);
  const int x1 = std::min(x0 + 1, g.width - 1);
  const int y1 = std::min(y0 + 1, g.height - 1);
  const double fx = qx - x0;
  const double fy = qy - y0;
  const double c00 = clearance.At(g.Index(x0, y0));
  const double c10 = clearance.At(g.Index(x1, y0));
  const double c01 = clearance.At(g.Index(x0, y1));
  const double c11 = clearance.At(g.Index(x1, y1));
  return (1 - fy) * ((1 - fx) * c00 + fx * c10) + fy * ((1 - fx) * c01 + fx * c11);
}

}  // namespace voxplan::omt
