// Plain data shared by the OMT planner algorithms (Dong et al. 2019). Self-contained: the
// planner plugin sees only the planner C API, so nothing here includes voxplan libraries.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace voxplan::omt {

inline constexpr double kPi = 3.14159265358979323846;

// One cell of the 2-D occupancy raster: the occupancy volume sliced at sensor height.
enum class Cell : std::uint8_t { kFree = 0, kOccupied = 1, kUnknown = 2 };

// Row-major raster geometry; cell (x, y) covers [origin + (x, y) * res, origin + (x+1, y+1) * res).
struct RasterGeometry {
  int width = 0;
  int height = 0;
  double resolution_m = 0.05;
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();

  int NumCells() const { return width * height; }
  bool InBounds(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  int Index(int x, int y) const { return y * width + x; }
  int X(int index) const { return index % width; }
  int Y(int index) const { return index / width; }
  Eigen::Vector2d Center(int x, int y) const {
    return origin_m + resolution_m * Eigen::Vector2d(x + 0.5, y + 0.5);
  }
  Eigen::Vector2d Center(int index) const { return Center(X(index), Y(index)); }
  // Cell containing a world point; -1 when outside.
  int IndexOf(const Eigen::Vector2d& p_m) const {
    const Eigen::Vector2d q = (p_m - origin_m) / resolution_m;
    const int x = static_cast<int>(std::floor(q.x()));
    const int y = static_cast<int>(std::floor(q.y()));
    return InBounds(x, y) ? Index(x, y) : -1;
  }
};

struct OccupancyRaster {
  RasterGeometry geometry;
  std::vector<Cell> cells;
  // TSDF weight per cell (§3.2 uncertainty of surface cells); empty means weight 0 everywhere.
  std::vector<float> tsdf_weight;
  // Cells a robot looked at from a task view without the map resolving them (non-zero): their
  // uncertainty is out of the sensor's reach from there, so they are neither queued nor counted
  // in a view's importance (they still hide what lies behind). Empty: none.
  std::vector<std::uint8_t> settled;

  Cell At(int index) const { return cells[static_cast<std::size_t>(index)]; }
  float WeightAt(int index) const {
    return tsdf_weight.empty() ? 0.0f : tsdf_weight[static_cast<std::size_t>(index)];
  }
  bool SettledAt(int index) const {
    return !settled.empty() && settled[static_cast<std::size_t>(index)] != 0;
  }
};

// Distance from each cell centre to the nearest obstacle (eq. 5's outside distance η), metres.
struct ClearanceRaster {
  RasterGeometry geometry;
  std::vector<float> clearance_m;

  float At(int index) const { return clearance_m[static_cast<std::size_t>(index)]; }
  // Clearance at a world point (nearest cell); 0 outside the raster.
  float AtPoint(const Eigen::Vector2d& p_m) const {
    const int i = geometry.IndexOf(p_m);
    return i < 0 ? 0.0f : At(i);
  }
};

// Expected failures are reported as values, never by aborting.
struct Status {
  enum class Code { kOk, kInvalidInput, kNoReachableTasks, kSolverFailed };
  Code code = Code::kOk;
  std::string message;

  static Status Ok() { return {}; }
  static Status Error(Code code, std::string message) { return {code, std::move(message)}; }
  bool ok() const { return code == Code::kOk; }
};

// Row-major dense matrix of distances (metres); infinity marks unreachable pairs.
struct DistanceMatrix {
  int rows = 0;
  int cols = 0;
  std::vector<double> values;

  DistanceMatrix() = default;
  DistanceMatrix(int r, int c, double fill = 0.0)
      : rows(r), cols(c), values(static_cast<std::size_t>(r) * c, fill) {}
  double operator()(int r, int c) const { return values[static_cast<std::size_t>(r) * cols + c]; }
  double& operator()(int r, int c) { return values[static_cast<std::size_t>(r) * cols + c]; }
};

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a <= 0.0) a += 2.0 * kPi;
  return a - kPi;
}

}  // namespace voxplan::omt
