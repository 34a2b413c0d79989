// The tensorfield planner's view gain (plugins/tensorfield/gain.cpp) with its surface term, in a
// known room: all floor seen, so the gain is the surface term alone, against the analytic
// Σ depth × u × cos(incidence) × profile × t dθ over the field of view's rays.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plugins/tensorfield/gain.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The rays stop at the first obstacle cell: t is quantised to one cell (5 cm) of about 2-3 m.
constexpr double kRelTol = 0.05;

// 8 m × 8 m at 5 cm centred on the origin, all free but a wall column at x in [2, 2.05)
// (surface uncertainty east_u, normal facing -x) and one at x in [-2.05, -2) (west_u, facing +x).
struct Room {
  omt::RasterGeometry geometry;
  std::vector<std::uint8_t> codes;
  SurfaceCells surface;
};

Room MakeRoom(float east_u, float west_u, Eigen::Vector2f east_normal = {-1.f, 0.f}) {
  Room r;
  r.geometry.width = r.geometry.height = 160;
  r.geometry.resolution_m = 0.05;
  r.geometry.origin_m = {-4.0, -4.0};
  const std::size_t n = static_cast<std::size_t>(r.geometry.NumCells());
  r.codes.assign(n, kFloorFree);
  r.surface.uncertainty.assign(n, 0.f);
  r.surface.normal.assign(n, Eigen::Vector2f::Zero());
  for (int y = 0; y < r.geometry.height; ++y)
    for (int x = 0; x < r.geometry.width; ++x) {
      const double cx = r.geometry.Center(x, y).x();
      const std::size_t i = static_cast<std::size_t>(r.geometry.Index(x, y));
      if (cx > 2.0 && cx < 2.05) {
        r.codes[i] = kFloorObstacle;
        r.surface.uncertainty[i] = east_u;
        r.surface.normal[i] = east_normal;
      } else if (cx > -2.05 && cx < -2.0) {
        r.codes[i] = kFloorObstacle;
        r.surface.uncertainty[i] = west_u;
        r.surface.normal[i] = {1.f, 0.f};
      }
    }
  return r;
}

GainParams Params(double depth_m) {
  GainParams p;
  p.range_m = 8.0;  // every wall hit (t <= 2.9 m) within half the range: profile 1
  p.near_m = 0.3;
  p.surface_depth_m = depth_m;
  return p;
}

// The analytic term for a wall x = 2 faced squarely with uncertainty u: a ray at angle a meets
// it at t = 2 / cos a with cos(incidence) = cos a, so each adds depth × u × 2 dθ.
double AnalyticEast(const GainParams& p, double u) {
  const double dtheta = 2.0 * kPi / p.rays;
  const int window = static_cast<int>(std::lround(p.fov_rad / dtheta));
  const double fan = 0.5 * window * dtheta * (p.range_m * p.range_m - p.near_m * p.near_m);
  return p.surface_depth_m * u * 2.0 * window * dtheta / fan;
}

TEST(ViewGainSurface, ProfileIsOneToHalfTheRangeThenFallsToZeroAtIt) {
  EXPECT_DOUBLE_EQ(SurfaceProfile(0.5, 5.0), 1.0);
  EXPECT_DOUBLE_EQ(SurfaceProfile(2.5, 5.0), 1.0);
  EXPECT_NEAR(SurfaceProfile(3.75, 5.0), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(SurfaceProfile(5.0, 5.0), 0.0);
  EXPECT_DOUBLE_EQ(SurfaceProfile(6.0, 5.0), 0.0);
}

TEST(ViewGainSurface, AnUncertainWallFacedSquarelyGivesTheAnalyticGain) {
  const Room room = MakeRoom(1.f, 0.f);
  const GainParams p = Params(0.5);
  const ViewGain gain(room.geometry, room.codes, p, room.surface);
  const double expected = AnalyticEast(p, 1.0);
  EXPECT_NEAR(gain.GainAt({0.0, 0.0}, 0.0), expected, kRelTol * expected);
  // Half the uncertainty, half the gain.
  const Room half = MakeRoom(0.5f, 0.f);
  const ViewGain half_gain(half.geometry, half.codes, p, half.surface);
  EXPECT_NEAR(half_gain.GainAt({0.0, 0.0}, 0.0), 0.5 * expected, kRelTol * expected);
}

TEST(ViewGainSurface, NothingFromAWellObservedWallTheBackOfOneOrWithTheTermOff) {
  const Room room = MakeRoom(1.f, 0.f);
  // The west wall (u = 0) behind the camera, the floor all seen.
  EXPECT_EQ(ViewGain(room.geometry, room.codes, Params(0.5), room.surface).GainAt({0, 0}, kPi),
            0.0);
  // The term off (the default), the surface given: the unseen floor only, none here.
  EXPECT_EQ(ViewGain(room.geometry, room.codes, Params(0.0), room.surface).GainAt({0, 0}, 0.0),
            0.0);
  // The wall's surface faces away from the camera (its outward normal +x): not seen from here.
  const Room back = MakeRoom(1.f, 0.f, {1.f, 0.f});
  EXPECT_EQ(ViewGain(back.geometry, back.codes, Params(0.5), back.surface).GainAt({0, 0}, 0.0),
            0.0);
}

TEST(ViewGainSurface, TheBestViewTurnsToTheLessObservedWall) {
  const GainParams p = Params(0.5);
  const Room east = MakeRoom(1.f, 0.2f);
  const ViewChoice e = ViewGain(east.geometry, east.codes, p, east.surface).Best({0, 0}, 0, kPi);
  EXPECT_LT(std::abs(std::remainder(e.yaw_rad, 2.0 * kPi)), 0.2);
  EXPECT_NEAR(e.gain, AnalyticEast(p, 1.0), kRelTol * AnalyticEast(p, 1.0));
  const Room west = MakeRoom(0.2f, 1.f);
  const ViewChoice w = ViewGain(west.geometry, west.codes, p, west.surface).Best({0, 0}, 0, kPi);
  EXPECT_LT(std::abs(std::remainder(w.yaw_rad - kPi, 2.0 * kPi)), 0.2);
}

// An unknown strip x in [1, 2) before the east wall: the best view sees it at the area-weighted
// mean distance of its cells (∫ t² dt / ∫ t dt over the fan's rays), which AimPitch turns into a
// tilt through the floor band's middle.
TEST(ViewGainSurface, TheViewsDistanceIsThatOfWhatItSeesAndAimPitchCentresTheBand) {
  Room room = MakeRoom(0.f, 0.f);
  for (int y = 0; y < room.geometry.height; ++y)
    for (int x = 0; x < room.geometry.width; ++x) {
      const double cx = room.geometry.Center(x, y).x();
      if (cx > 1.0 && cx < 2.0)
        room.codes[static_cast<std::size_t>(room.geometry.Index(x, y))] = kFloorUnknown;
    }
  const ViewChoice v =
      ViewGain(room.geometry, room.codes, Params(0.0)).Best({0, 0}, 0.0, 0.1, true);
  ASSERT_GT(v.gain, 0.0);
  // Along the axis the strip spans t in [1, 2): ∫ t² / ∫ t = 2 (b³ - a³) / 3 (b² - a²); the
  // rays off the axis (up to 45°) meet it farther out, by up to 1 / cos 45°.
  const double a = 1.0, b = 2.0;
  const double on_axis = 2.0 * (b * b * b - a * a * a) / (3.0 * (b * b - a * a));
  EXPECT_GT(v.distance_m, on_axis - 0.05);
  EXPECT_LT(v.distance_m, on_axis / std::cos(0.25 * kPi));
  // A camera 1.2 m up, the band 1.8 m: the axis through z = 0.9 m at that distance.
  EXPECT_NEAR(AimPitch(1.2, 2.0, 1.8), std::atan2(-0.3, 2.0), 1e-12);
  EXPECT_NEAR(AimPitch(0.9, 3.0, 1.8), 0.0, 1e-12);
  EXPECT_GT(AimPitch(0.4, 1.0, 1.8), 0.0);  // a low arm camera looks up
  // Nothing seen: no distance.
  const Room known = MakeRoom(0.f, 0.f);
  EXPECT_EQ(
      ViewGain(known.geometry, known.codes, Params(0.0)).Best({0, 0}, 0.0, kPi, true).distance_m,
      0.0);
}

}  // namespace
}  // namespace voxplan::tensorfield
