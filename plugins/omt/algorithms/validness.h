// Validness map ρ over the view space (x, y, θ) of §3.2: ρ = φ·ψ with φ = exp(-α²/σ²) scoring
// the scanning angle α against the surface anti-normal and ψ the scanning distance (Fig. 3(c)).
#pragma once

#include <optional>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

struct SensorParams {
  double d_min_m = 0.5;  // valid range of an Xtion/Kinect-class sensor (§3.2)
  double d_max_m = 3.0;
  double d_inf_m = 6.0;                 // ψ reaches 0 here; rays are cast this far (Fig. 3(c))
  double sigma_rad = 0.6;               // φ width
  double fov_rad = 58.0 * kPi / 180.0;  // horizontal field of view
  int angle_bins = 72;                  // 5° steps
  int normal_radius_cells = 2;          // neighbourhood for the 2-D surface normal
};

// Fig. 3(c) is only drawn in the paper; we read it as: linear ramp 0 → 1 on [0, d_min],
// 1 on [d_min, d_max], linear ramp 1 → 0 on [d_max, d_inf], 0 beyond.
double DistanceProfile(double d_m, const SensorParams& params);
// φ(α) = exp(-α²/σ²).
double AngleProfile(double alpha_rad, const SensorParams& params);
// Heading of angle bin b (radians).
inline double BinYaw(int bin, const SensorParams& params) {
  return 2.0 * kPi * bin / params.angle_bins;
}

// 2-D normal of the surface at a cell, pointing into free space: the normalised sum of unit
// offsets to free cells in the neighbourhood. None when the free cells balance out.
std::optional<Eigen::Vector2d> SurfaceNormal(const OccupancyRaster& raster, int cell,
                                             const SensorParams& params);

struct RayHit {
  enum class Kind { kNone, kOccupied, kUnknown };
  Kind kind = Kind::kNone;
  int cell = -1;
  double distance_m = 0.0;
};
// First non-free cell along the ray (the start cell excluded), up to d_inf.
RayHit CastRay(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
               const SensorParams& params);

// ρ of one view, literally as §3.2: 1 when the ray meets nothing or an unknown cell, else φψ
// of the first occupied cell.
double ViewValidness(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
                     const SensorParams& params);

// The M × N × bins volume of §3.2 (value of cell i, bin b at i * bins + b), computed only for
// free cells (others hold -1, as the paper skips them).
struct ValidnessMap {
  RasterGeometry geometry;
  int bins = 0;
  std::vector<float> values;
  float At(int cell, int bin) const {
    return values[static_cast<std::size_t>(cell) * bins + static_cast<std::size_t>(bin)];
  }
};
ValidnessMap ComputeValidnessMap(const OccupancyRaster& raster, const SensorParams& params);

// The entries of the validness map whose central ray passes through target_cell: views at
// free cells on backward rays from the target, one ray per angle bin, stopped by the first
// non-free cell (occlusion) or d_inf. Their ρ is φψ against the target itself, occupied or
// frontier: for an unknown target the paper's constant 1 would make every view tie, so we keep
// the distance and angle terms (with the frontier normal) to rank them.
struct TargetView {
  int cell = -1;
  int bin = 0;
  double distance_m = 0.0;
  float validness = 0.0f;
};
void ViewsSeeingTarget(const OccupancyRaster& raster, int target_cell, const SensorParams& params,
                       std::vector<TargetView>* out);

}  // namespace voxplan::omt
