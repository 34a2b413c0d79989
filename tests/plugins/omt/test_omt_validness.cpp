#include <gtest/gtest.h>

#include <cmath>

#include "plugins/omt/algorithms/validness.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

using testing::FillRect;
using testing::MakeRaster;

constexpr double kTol = 1e-9;
// Normals come from a 5 × 5 cell neighbourhood; on straight walls they are exact by symmetry,
// and distances are measured between cell centres.
constexpr double kValidnessTol = 0.02;

TEST(OmtValidness, DistanceProfileFollowsFigure3c) {
  const SensorParams p;
  EXPECT_NEAR(DistanceProfile(0.0, p), 0.0, kTol);
  EXPECT_NEAR(DistanceProfile(0.25, p), 0.5, kTol);
  EXPECT_NEAR(DistanceProfile(0.5, p), 1.0, kTol);
  EXPECT_NEAR(DistanceProfile(2.0, p), 1.0, kTol);
  EXPECT_NEAR(DistanceProfile(3.0, p), 1.0, kTol);
  EXPECT_NEAR(DistanceProfile(4.5, p), 0.5, kTol);
  EXPECT_NEAR(DistanceProfile(6.0, p), 0.0, kTol);
  EXPECT_NEAR(DistanceProfile(8.0, p), 0.0, kTol);
}

TEST(OmtValidness, AngleProfileIsGaussianWithSigma06) {
  const SensorParams p;
  EXPECT_NEAR(AngleProfile(0.0, p), 1.0, kTol);
  EXPECT_NEAR(AngleProfile(0.6, p), std::exp(-1.0), kTol);
  EXPECT_LT(AngleProfile(1.2, p), AngleProfile(0.6, p));
}

// 4 × 4 m free room whose right part (x >= 3 m) is solid wall.
OccupancyRaster WallScene() {
  OccupancyRaster r = MakeRaster(4.0, 4.0, 0.05, Cell::kFree);
  FillRect(&r, 3.0, 0.0, 4.0, 4.0, Cell::kOccupied);
  return r;
}

TEST(OmtValidness, HeadOnViewOfWallInRangeIsFullyValid) {
  const OccupancyRaster r = WallScene();
  const SensorParams p;
  const Eigen::Vector2d view = r.geometry.Center(r.geometry.IndexOf({1.0, 2.0}));
  EXPECT_NEAR(ViewValidness(r, view, 0.0, p), 1.0, kValidnessTol);
  // Too close: 0.25 m from the wall face, ψ on its ramp.
  const Eigen::Vector2d close = r.geometry.Center(r.geometry.IndexOf({2.76, 2.0}));
  const double d = 3.025 - close.x();
  EXPECT_NEAR(ViewValidness(r, close, 0.0, p), DistanceProfile(d, p), kValidnessTol);
  EXPECT_LT(ViewValidness(r, close, 0.0, p), 0.8);
}

TEST(OmtValidness, ObliqueViewIsPenalisedByScanningAngle) {
  const OccupancyRaster r = WallScene();
  const SensorParams p;
  const Eigen::Vector2d view = r.geometry.Center(r.geometry.IndexOf({1.5, 1.0}));
  const double alpha = kPi / 4.0;
  EXPECT_NEAR(ViewValidness(r, view, alpha, p), AngleProfile(alpha, p), kValidnessTol);
}

TEST(OmtValidness, UnknownOrNothingAheadIsValid) {
  OccupancyRaster r = MakeRaster(4.0, 4.0, 0.05, Cell::kFree);
  const SensorParams p;
  EXPECT_NEAR(ViewValidness(r, {1.0, 2.0}, 0.0, p), 1.0, kTol);  // ray leaves the raster
  FillRect(&r, 3.0, 0.0, 4.0, 4.0, Cell::kUnknown);
  EXPECT_EQ(CastRay(r, {1.0, 2.0}, 0.0, p).kind, RayHit::Kind::kUnknown);
  EXPECT_NEAR(ViewValidness(r, {1.0, 2.0}, 0.0, p), 1.0, kTol);
}

// Target: an occupied pillar at (3, 2); the view at (1, 2) looks along +x at it.
struct TargetScene {
  OccupancyRaster raster = MakeRaster(4.0, 4.0, 0.05, Cell::kFree);
  int target = -1;
  int view = -1;
  TargetScene() {
    FillRect(&raster, 3.0, 1.8, 3.4, 2.2, Cell::kOccupied);
    target = raster.geometry.IndexOf({3.025, 2.025});
    view = raster.geometry.IndexOf({1.025, 2.025});
  }
};

bool SeesTargetHeadOn(const OccupancyRaster& r, int target, int view, float* rho) {
  std::vector<TargetView> seen;
  ViewsSeeingTarget(r, target, SensorParams{}, &seen);
  for (const TargetView& v : seen) {
    if (v.cell == view && v.bin == 0) {
      *rho = v.validness;
      return true;
    }
  }
  return false;
}

TEST(OmtValidness, VisibleTargetIsSeenWithForwardRayValidness) {
  TargetScene s;
  float rho = 0.0f;
  ASSERT_TRUE(SeesTargetHeadOn(s.raster, s.target, s.view, &rho));
  const SensorParams p;
  // The forward ray from the view hits the target cell, and both computations agree.
  const RayHit hit = CastRay(s.raster, s.raster.geometry.Center(s.view), 0.0, p);
  EXPECT_EQ(hit.cell, s.target);
  EXPECT_NEAR(rho, ViewValidness(s.raster, s.raster.geometry.Center(s.view), 0.0, p),
              kValidnessTol);
  EXPECT_GT(rho, 0.9f);
}

TEST(OmtValidness, OccludedTargetIsNotSeen) {
  TargetScene s;
  FillRect(&s.raster, 2.0, 1.9, 2.1, 2.1, Cell::kOccupied);  // occluder on the line of sight
  float rho = 0.0f;
  EXPECT_FALSE(SeesTargetHeadOn(s.raster, s.target, s.view, &rho));
  // Forward ray from the view now stops at the occluder.
  const RayHit hit = CastRay(s.raster, s.raster.geometry.Center(s.view), 0.0, SensorParams{});
  EXPECT_EQ(hit.kind, RayHit::Kind::kOccupied);
  EXPECT_NE(hit.cell, s.target);
  EXPECT_LT(hit.distance_m, 1.1);
}

TEST(OmtValidness, MapMatchesPerViewValidnessAndSkipsNonFreeCells) {
  OccupancyRaster r = MakeRaster(1.5, 1.0, 0.05, Cell::kFree);
  FillRect(&r, 1.2, 0.0, 1.5, 1.0, Cell::kOccupied);
  FillRect(&r, 0.0, 0.8, 0.6, 1.0, Cell::kUnknown);
  SensorParams p;
  const ValidnessMap map = ComputeValidnessMap(r, p);
  ASSERT_EQ(map.values.size(), static_cast<std::size_t>(r.geometry.NumCells()) * 72);
  for (int i = 0; i < r.geometry.NumCells(); i += 7) {
    for (int b = 0; b < 72; b += 5) {
      if (r.At(i) != Cell::kFree) {
        EXPECT_EQ(map.At(i, b), -1.0f);
        continue;
      }
      const double expected = ViewValidness(r, r.geometry.Center(i), BinYaw(b, p), p);
      EXPECT_NEAR(map.At(i, b), expected, 1e-6);
      EXPECT_GE(map.At(i, b), 0.0f);
      EXPECT_LE(map.At(i, b), 1.0f);
    }
  }
}

}  // namespace
}  // namespace voxplan::omt
