// The tensorfield planner's view gain [ours]: X's V(q, α) and I(e, p) are in an unavailable
// appendix (X L220, L270; planner-wave.md §2.4). A 2-D stand-in on the floor raster: the unseen
// floor (unknown and frontier cells) a camera at p sees within its range and field of view, rays
// stopping at obstacle cells and passing through unknown ones, as a share of the fan's area.
// The design's second term, surface uncertainty x cos(incidence) x a distance profile, is
// optional (surface_depth_m > 0): the obstacle a ray stops at counts as a strip of unseen floor
// that deep, scaled by its surface's uncertainty, the cosine and the profile. Plain data;
// deterministic.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/frames.h"

namespace voxplan::tensorfield {

struct GainParams {
  double near_m = 0.3;   // floor nearer than this is not counted (the footprint; min range)
  double range_m = 5.0;  // the camera's depth range
  double fov_rad = 1.5707963;
  int rays = 72;  // over 2π
  // The surface term's weight, as the depth (m) of unseen floor a fully uncertain surface faced
  // squarely at a good distance is worth; 0: unseen floor only.
  double surface_depth_m = 0.0;
};

// The surface term's distance profile [ours]: 1 up to half the range, falling linearly to 0 at
// the range (depth noise grows with distance, so far views add little weight).
double SurfaceProfile(double distance_m, double range_m);

// A view's pitch [ours]: the optical axis through the middle of the band from the floor up to
// band_m, distance_m away (the view's ViewChoice::distance_m), from a camera camera_height_m above
// the floor. The 2-D gain's unseen cells stand for whole columns of that band.
double AimPitch(double camera_height_m, double distance_m, double band_m);

struct ViewChoice {
  double yaw_rad = 0.0;     // world yaw of the view's axis
  double gain = 0.0;        // unseen area in the fan / the fan's area, in [0, 1]
  double distance_m = 0.0;  // the gain-weighted mean distance of what it sees; 0: nothing
};

class ViewGain {
 public:
  // codes: one FloorCode (frames.h) per cell of geometry (the planner passes settled cells as
  // free: they count as seen). Rays march at the raster's resolution. surface: on geometry's
  // cells, or empty (no surface term).
  ViewGain(const omt::RasterGeometry& geometry, std::vector<std::uint8_t> codes,
           const GainParams& params, SurfaceCells surface = {});

  // Unseen area (m²) of each ray's sector around p, ray k at angle 2πk / rays, with the surface
  // term of the obstacle it stops at.
  // moments: when given, Σ area × distance per ray.
  std::vector<double> Sectors(const Eigen::Vector2d& p_m,
                              std::vector<double>* moments = nullptr) const;
  // The best view at p whose axis lies within half_window_rad of centre_rad (≥ π: any).
  // with_distance: fill ViewChoice::distance_m too (else 0).
  ViewChoice Best(const Eigen::Vector2d& p_m, double centre_rad, double half_window_rad,
                  bool with_distance = false) const;
  // The best view at p in any direction (the I(e, p) of an edge point).
  double PointGain(const Eigen::Vector2d& p_m) const;
  // The view along yaw_rad exactly.
  double GainAt(const Eigen::Vector2d& p_m, double yaw_rad) const;

  const GainParams& params() const { return params_; }

 private:
  double SurfaceTerm(int c, int previous, const Eigen::Vector2d& d) const;

  omt::RasterGeometry geometry_;
  std::vector<std::uint8_t> unseen_;  // 1 unknown or frontier, 2 obstacle, 0 free
  SurfaceCells surface_;
  GainParams params_;
  int window_ = 1;  // rays in one field of view
  double fan_area_m2_ = 1.0;
};

}  // namespace voxplan::tensorfield
