// Hand-made rasters for the OMT planner tests and benchmark (header-only, plain data).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt::testing {

inline OccupancyRaster MakeRaster(double width_m, double height_m, double res_m, Cell fill) {
  OccupancyRaster r;
  r.geometry.width = static_cast<int>(std::lround(width_m / res_m));
  r.geometry.height = static_cast<int>(std::lround(height_m / res_m));
  r.geometry.resolution_m = res_m;
  r.geometry.origin_m = Eigen::Vector2d::Zero();
  r.cells.assign(static_cast<std::size_t>(r.geometry.NumCells()), fill);
  return r;
}

// Sets every cell whose centre lies in [x0, x1) × [y0, y1) (metres).
inline void FillRect(OccupancyRaster* r, double x0, double y0, double x1, double y1, Cell c) {
  const RasterGeometry& g = r->geometry;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const Eigen::Vector2d p = g.Center(x, y);
      if (p.x() >= x0 && p.x() < x1 && p.y() >= y0 && p.y() < y1)
        r->cells[static_cast<std::size_t>(g.Index(x, y))] = c;
    }
  }
}

// A 0.1 m wall frame around [x0, x1) × [y0, y1).
inline void FrameRect(OccupancyRaster* r, double x0, double y0, double x1, double y1) {
  FillRect(r, x0, y0, x1, y0 + 0.1, Cell::kOccupied);
  FillRect(r, x0, y1 - 0.1, x1, y1, Cell::kOccupied);
  FillRect(r, x0, y0, x0 + 0.1, y1, Cell::kOccupied);
  FillRect(r, x1 - 0.1, y0, x1, y1, Cell::kOccupied);
}

// Half-explored floor: an outer wall frame of width_m × height_m, interior walls with doors,
// a few furniture blocks; everything with x >= known_x_m is still unknown.
inline OccupancyRaster MakeApartment(double width_m, double height_m, double res_m,
                                     double known_x_m) {
  OccupancyRaster r = MakeRaster(width_m, height_m, res_m, Cell::kFree);
  FrameRect(&r, 0.0, 0.0, width_m, height_m);
  // Vertical interior walls every 5 m with a 1 m door; one horizontal wall with doors.
  for (double x = 5.0; x < width_m - 1.0; x += 5.0) {
    FillRect(&r, x, 0.0, x + 0.1, height_m * 0.5 - 0.5, Cell::kOccupied);
    FillRect(&r, x, height_m * 0.5 + 0.5, x + 0.1, height_m, Cell::kOccupied);
  }
  for (double x = 0.0; x < width_m; x += 5.0) {
    FillRect(&r, x, height_m * 0.65, x + 2.0, height_m * 0.65 + 0.1, Cell::kOccupied);
    FillRect(&r, x + 3.2, height_m * 0.65, x + 5.0, height_m * 0.65 + 0.1, Cell::kOccupied);
  }
  for (double x = 1.5; x < width_m; x += 5.0) FillRect(&r, x, 1.2, x + 0.8, 1.8, Cell::kOccupied);
  FillRect(&r, known_x_m, 0.0, width_m, height_m, Cell::kUnknown);
  // Surfaces scanned a little: weight 1 on every occupied cell.
  r.tsdf_weight.assign(r.cells.size(), 0.0f);
  for (std::size_t i = 0; i < r.cells.size(); ++i)
    if (r.cells[i] == Cell::kOccupied) r.tsdf_weight[i] = 1.0f;
  return r;
}

}  // namespace voxplan::omt::testing
