// Occupancy rasters and analytic fields for the tensor-field tests.
#pragma once

#include <cmath>
#include <functional>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield::test {

inline constexpr double kRes = 0.05;  // the paper's field grid (X§6)

// A w_m x h_m raster at kRes, origin 0, every cell `fill`.
inline omt::OccupancyRaster MakeRaster(double w_m, double h_m, omt::Cell fill) {
  omt::OccupancyRaster r;
  r.geometry.width = static_cast<int>(std::lround(w_m / kRes));
  r.geometry.height = static_cast<int>(std::lround(h_m / kRes));
  r.geometry.resolution_m = kRes;
  r.cells.assign(static_cast<std::size_t>(r.geometry.NumCells()), fill);
  return r;
}

// Sets the cells whose centres lie in [x0, x1) x [y0, y1).
inline void FillRect(omt::OccupancyRaster* r, double x0, double y0, double x1, double y1,
                     omt::Cell c) {
  for (int i = 0; i < r->geometry.NumCells(); ++i) {
    const Eigen::Vector2d p = r->geometry.Center(i);
    if (p.x() >= x0 && p.x() < x1 && p.y() >= y0 && p.y() < y1) {
      r->cells[static_cast<std::size_t>(i)] = c;
    }
  }
}

// A field over a w x h cell raster at kRes from f(cell centre).
inline TensorRaster AnalyticField(int w, int h,
                                  const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& f) {
  omt::RasterGeometry g;
  g.width = w;
  g.height = h;
  g.resolution_m = kRes;
  TensorRaster field = MakeTensorRaster(g);
  for (int i = 0; i < g.NumCells(); ++i) {
    const Eigen::Vector2d t = f(g.Center(i));
    field.tau11[static_cast<std::size_t>(i)] = t.x();
    field.tau12[static_cast<std::size_t>(i)] = t.y();
  }
  return field;
}

// Angle between two line directions (mod π), radians in [0, π/2].
inline double LineAngleBetween(double a, double b) {
  double d = std::fmod(std::abs(a - b), omt::kPi);
  return std::min(d, omt::kPi - d);
}

// Angle between two ray directions (mod 2π), radians in [0, π].
inline double RayAngleBetween(double a, double b) { return std::abs(omt::WrapAngle(a - b)); }

// A 7 m x 4 m raster holding a 6 m x 3 m room with two boxes (one of them off the walls).
inline omt::OccupancyRaster FurnishedRoom() {
  omt::OccupancyRaster r = MakeRaster(7.0, 4.0, omt::Cell::kOccupied);
  FillRect(&r, 0.5, 0.5, 6.5, 3.5, omt::Cell::kFree);
  FillRect(&r, 2.0, 1.5, 2.6, 2.0, omt::Cell::kOccupied);
  FillRect(&r, 4.5, 2.5, 5.5, 3.0, omt::Cell::kOccupied);
  return r;
}

}  // namespace voxplan::tensorfield::test
