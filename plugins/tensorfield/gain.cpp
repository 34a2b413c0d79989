// The 2-D view gain: ray sectors over the floor raster, best field-of-view window.
#include "plugins/tensorfield/gain.h"

#include <algorithm>
#include <cmath>

#include "plugins/tensorfield/frames.h"

namespace voxplan::tensorfield {

double SurfaceProfile(double distance_m, double range_m) {
  if (range_m <= 0.0) return 0.0;
  return std::clamp(2.0 * (1.0 - distance_m / range_m), 0.0, 1.0);
}

double AimPitch(double camera_height_m, double distance_m, double band_m) {
  return std::atan2(0.5 * band_m - camera_height_m, std::max(distance_m, 1e-3));
}

ViewGain::ViewGain(const omt::RasterGeometry& geometry, std::vector<std::uint8_t> codes,
                   const GainParams& params, SurfaceCells surface)
    : geometry_(geometry), params_(params) {
  if (params_.surface_depth_m > 0.0 &&
      surface.uncertainty.size() == static_cast<std::size_t>(geometry.NumCells()) &&
      surface.normal.size() == surface.uncertainty.size())
    surface_ = std::move(surface);
  params_.rays = std::max(8, params_.rays);
  unseen_.resize(codes.size());
  for (std::size_t i = 0; i < codes.size(); ++i)
    unseen_[i] = codes[i] == kFloorObstacle                                ? 2
                 : codes[i] == kFloorUnknown || codes[i] == kFloorFrontier ? 1
                                                                           : 0;
  const double dtheta = 2.0 * omt::kPi / params_.rays;
  window_ = std::clamp(static_cast<int>(std::lround(params_.fov_rad / dtheta)), 1, params_.rays);
  const double r = params_.range_m, n = std::min(params_.near_m, r);
  fan_area_m2_ = std::max(1e-9, 0.5 * window_ * dtheta * (r * r - n * n));
}

std::vector<double> ViewGain::Sectors(const Eigen::Vector2d& p_m,
                                      std::vector<double>* moments) const {
  const int rays = params_.rays;
  std::vector<double> out(static_cast<std::size_t>(rays), 0.0);
  if (moments) moments->assign(static_cast<std::size_t>(rays), 0.0);
  const double dtheta = 2.0 * omt::kPi / rays;
  const double step = geometry_.resolution_m;
  for (int k = 0; k < rays; ++k) {
    const double a = dtheta * k;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    double area = 0.0, moment = 0.0;
    int previous = -1;
    for (double t = 0.5 * step; t <= params_.range_m; t += step) {
      const int c = geometry_.IndexOf(p_m + t * d);
      if (c < 0) break;
      const std::uint8_t u = unseen_[static_cast<std::size_t>(c)];
      double added = 0.0;
      if (u == 2) {
        if (!surface_.empty() && t >= params_.near_m)
          added = SurfaceTerm(c, previous, d) * SurfaceProfile(t, params_.range_m) * t * dtheta *
                  params_.surface_depth_m;
      } else if (u == 1 && t >= params_.near_m) {
        added = t * step * dtheta;
      }
      area += added;
      moment += added * t;
      if (u == 2) break;
      previous = c;
    }
    out[static_cast<std::size_t>(k)] = area;
    if (moments) (*moments)[static_cast<std::size_t>(k)] = moment;
  }
  return out;
}

// The uncertainty x cos(incidence) of the surface a ray along d meets at obstacle cell c: its
// voxels may sit in c or, at the zero crossing, in the free cell before it, so the larger of
// the two. A cell without a normal counts as faced squarely.
double ViewGain::SurfaceTerm(int c, int previous, const Eigen::Vector2d& d) const {
  double best = 0.0;
  for (const int cell : {c, previous}) {
    if (cell < 0) continue;
    const std::size_t i = static_cast<std::size_t>(cell);
    const double u = surface_.uncertainty[i];
    if (u <= 0.0) continue;
    const Eigen::Vector2f& n = surface_.normal[i];
    const double facing = n.squaredNorm() > 0.f ? std::max(0.0, -d.dot(n.cast<double>())) : 1.0;
    best = std::max(best, u * facing);
  }
  return best;
}

ViewChoice ViewGain::Best(const Eigen::Vector2d& p_m, double centre_rad, double half_window_rad,
                          bool with_distance) const {
  std::vector<double> m;
  const std::vector<double> s = Sectors(p_m, with_distance ? &m : nullptr);
  if (!with_distance) m.assign(s.size(), 0.0);
  const int rays = params_.rays;
  const double dtheta = 2.0 * omt::kPi / rays;
  // Window starting at ray k covers rays k .. k + window - 1; its axis is their middle.
  double sum = 0.0, moment = 0.0;
  for (int j = 0; j < window_; ++j) {
    sum += s[static_cast<std::size_t>(j % rays)];
    moment += m[static_cast<std::size_t>(j % rays)];
  }
  ViewChoice best;
  best.yaw_rad = centre_rad;
  best.gain = -1.0;
  double best_moment = 0.0;
  for (int k = 0; k < rays; ++k) {
    const double axis = dtheta * (k + 0.5 * (window_ - 1));
    if (half_window_rad >= omt::kPi ||
        std::abs(omt::WrapAngle(axis - centre_rad)) <= half_window_rad + 1e-9) {
      if (sum > best.gain + 1e-12) {
        best.gain = sum;
        best_moment = moment;
        best.yaw_rad = omt::WrapAngle(axis);
      }
    }
    const std::size_t in = static_cast<std::size_t>((k + window_) % rays);
    const std::size_t out = static_cast<std::size_t>(k);
    sum += s[in] - s[out];
    moment += m[in] - m[out];
  }
  if (best.gain < 0.0) {  // no window axis inside the range: look along its centre
    best.yaw_rad = centre_rad;
    best.gain = GainAt(p_m, centre_rad) * fan_area_m2_;
    best_moment = 0.0;
  }
  best.distance_m = best.gain > 1e-12 && best_moment > 0.0 ? best_moment / best.gain : 0.0;
  best.gain = std::clamp(best.gain / fan_area_m2_, 0.0, 1.0);
  return best;
}

double ViewGain::PointGain(const Eigen::Vector2d& p_m) const {
  return Best(p_m, 0.0, omt::kPi).gain;
}

double ViewGain::GainAt(const Eigen::Vector2d& p_m, double yaw_rad) const {
  const std::vector<double> s = Sectors(p_m);
  const int rays = params_.rays;
  const double dtheta = 2.0 * omt::kPi / rays;
  double a = std::fmod(yaw_rad, 2.0 * omt::kPi);
  if (a < 0.0) a += 2.0 * omt::kPi;
  const int first = static_cast<int>(std::lround(a / dtheta - 0.5 * (window_ - 1)));
  double sum = 0.0;
  for (int j = 0; j < window_; ++j)
    sum += s[static_cast<std::size_t>(((first + j) % rays + rays) % rays)];
  return std::clamp(sum / fan_area_m2_, 0.0, 1.0);
}

}  // namespace voxplan::tensorfield
