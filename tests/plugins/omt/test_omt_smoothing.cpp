#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/omt/algorithms/smoothing.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

using testing::FillRect;
using testing::FrameRect;
using testing::MakeRaster;

constexpr double kRobotRadius = 0.18;
// λ = 10 holds task points: they may move, but only a little.
constexpr double kMaxTaskShift_m = 0.15;
constexpr double kYawTol = 1e-9;

// Σ ‖p_{i-1} − 2 p_i + p_{i+1}‖²: discrete curvature energy of the sample sequence.
double CurvatureEnergy(const std::vector<PathPoint>& pts) {
  double e = 0.0;
  for (std::size_t i = 1; i + 1 < pts.size(); ++i)
    e += (pts[i - 1].p_m - 2.0 * pts[i].p_m + pts[i + 1].p_m).squaredNorm();
  return e;
}

bool AllClear(const ClearanceRaster& c, const std::vector<PathPoint>& pts, double r) {
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!SegmentClear(c, pts[i - 1].p_m, pts[i].p_m, r)) return false;
  return true;
}

// 8 × 4 m room with a 1 × 1.4 m box in the middle of the bottom half.
OccupancyRaster Room() {
  OccupancyRaster r = MakeRaster(8.0, 4.0, 0.05, Cell::kFree);
  FrameRect(&r, 0.0, 0.0, 8.0, 4.0);
  FillRect(&r, 3.5, 0.1, 4.5, 1.5, Cell::kOccupied);
  return r;
}

std::vector<PathPoint> ZigZag() {
  // A staircase polyline (a grid-path look) from (1, 1) over the box to (7, 1); vertex 4 and
  // the end are task views.
  const std::vector<Eigen::Vector2d> poly{{1.0, 1.0}, {1.6, 1.0}, {1.6, 1.6}, {2.2, 1.6},
                                          {2.2, 2.2}, {4.0, 2.2}, {5.8, 2.2}, {5.8, 1.6},
                                          {6.4, 1.6}, {6.4, 1.0}, {7.0, 1.0}};
  return SamplePolyline(poly, {{4, 0}, {10, 1}}, 0.2);
}

TEST(OmtSmoothing, SamplingKeepsTaskVerticesAndSpacing) {
  const std::vector<PathPoint> pts = ZigZag();
  ASSERT_GT(pts.size(), 20u);
  int tasks = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    EXPECT_LE((pts[i].p_m - pts[i - 1].p_m).norm(), 0.2 * 1.5 + 1e-9);
    tasks += pts[i].task >= 0;
  }
  EXPECT_EQ(tasks, 2);
  EXPECT_EQ(pts.back().task, 1);
  EXPECT_TRUE(pts.back().p_m.isApprox(Eigen::Vector2d(7.0, 1.0)));
}

TEST(OmtSmoothing, Eq5ReducesCurvatureAndEnergyAndKeepsClearance) {
  const OccupancyRaster raster = Room();
  const ClearanceRaster clearance = ComputeClearance(raster);
  const std::vector<PathPoint> before = ZigZag();
  ASSERT_TRUE(AllClear(clearance, before, kRobotRadius));
  std::vector<PathPoint> after = before;
  SmoothingParams params;
  params.min_clearance_m = kRobotRadius;
  ASSERT_TRUE(SmoothPath(clearance, params, &after).ok());
  ASSERT_EQ(after.size(), before.size());
  EXPECT_LT(CurvatureEnergy(after), 0.5 * CurvatureEnergy(before));
  EXPECT_LT(Eq5Energy(clearance, after, before, params),
            Eq5Energy(clearance, before, before, params));
  EXPECT_TRUE(AllClear(clearance, after, kRobotRadius));
  EXPECT_TRUE(after.front().p_m.isApprox(before.front().p_m));  // the robot does not move
  for (std::size_t i = 0; i < after.size(); ++i)
    if (after[i].task >= 0) {
      EXPECT_LE((after[i].p_m - before[i].p_m).norm(), kMaxTaskShift_m);
    }
}

TEST(OmtSmoothing, TruncatedEtaLeavesAStraightPathAcrossAnOpenRoomStraight) {
  // A straight leg 1 m off the wall of an empty 8 × 4 m room: η is 0.95 m along it and grows to
  // 1.95 m at the room's middle. Eq. 5's 1/η weight pulls the samples towards the middle; with η
  // truncated at 0.5 m every weight is the same and the straight line is the optimum.
  OccupancyRaster raster = MakeRaster(8.0, 4.0, 0.05, Cell::kFree);
  FrameRect(&raster, 0.0, 0.0, 8.0, 4.0);
  const ClearanceRaster clearance = ComputeClearance(raster);
  const std::vector<PathPoint> before = SamplePolyline({{1.0, 1.0}, {7.0, 1.0}}, {{1, 0}}, 0.2);
  SmoothingParams params;
  params.min_clearance_m = kRobotRadius;
  ASSERT_LT(params.eta_cap_m, 0.9);
  auto smoothed = [&](double eta_cap_m) {
    std::vector<PathPoint> pts = before;
    SmoothingParams p = params;
    p.eta_cap_m = eta_cap_m;
    EXPECT_TRUE(SmoothPath(clearance, p, &pts).ok());
    double off_line_m = 0.0;
    for (const PathPoint& q : pts) off_line_m = std::max(off_line_m, std::abs(q.p_m.y() - 1.0));
    return std::make_pair(PolylineLength(pts), off_line_m);
  };
  constexpr double kStraight_m = 1e-3;
  const auto [capped_len, capped_off] = smoothed(params.eta_cap_m);
  EXPECT_LT(capped_off, kStraight_m);
  EXPECT_LE(capped_len, 6.0 + kStraight_m);  // (the soft λ anchor lets the end creep closer)
  // Untruncated (the paper's η), the same leg bows almost to the middle (0.99 m) and is 8 %
  // longer.
  const auto [full_len, full_off] = smoothed(1e9);
  EXPECT_GT(full_off, 0.5);
  EXPECT_GT(full_len, 1.05 * 6.0);
}

TEST(OmtSmoothing, UTurnAroundAThinWallDoesNotCutThroughIt) {
  // A 5 cm wall with a U-turn around its end. Eq. 5 only sees η at the samples, so on its
  // own the optimiser jumps the samples across the wall (the path shrinks from 6.4 m to under
  // 1 m); the clearance term and the step-back must keep every segment clear.
  OccupancyRaster raster = MakeRaster(8.0, 5.0, 0.05, Cell::kFree);
  FrameRect(&raster, 0.0, 0.0, 8.0, 5.0);
  FillRect(&raster, 4.0, 0.1, 4.05, 3.0, Cell::kOccupied);
  const ClearanceRaster clearance = ComputeClearance(raster);
  const std::vector<Eigen::Vector2d> poly{{3.6, 0.6}, {3.6, 3.4}, {4.45, 3.4}, {4.45, 0.6}};
  const std::vector<PathPoint> before = SamplePolyline(poly, {{3, 0}}, 0.2);
  ASSERT_TRUE(AllClear(clearance, before, kRobotRadius));
  std::vector<PathPoint> after = before;
  SmoothingParams params;
  params.min_clearance_m = kRobotRadius;
  ASSERT_TRUE(SmoothPath(clearance, params, &after).ok());
  EXPECT_TRUE(AllClear(clearance, after, kRobotRadius));
  EXPECT_LE(CurvatureEnergy(after), CurvatureEnergy(before));
  EXPECT_LE(PolylineLength(after), PolylineLength(before));
  // Still going around the wall's end.
  double top = 0.0;
  for (const PathPoint& p : after) top = std::max(top, p.p_m.y());
  EXPECT_GT(top, 3.0);
}

TEST(OmtSmoothing, HermiteYawHitsTaskViewsWithoutOvershoot) {
  const std::vector<PathPoint> pts = ZigZag();
  // Task 0 at 170°, task 1 at -170°: the short turn through 180°, not 340° the other way.
  const std::vector<double> task_yaw{170.0 * kPi / 180.0, -170.0 * kPi / 180.0};
  const double start_yaw = 90.0 * kPi / 180.0;
  const std::vector<double> yaw = InterpolateYaw(pts, start_yaw, task_yaw);
  ASSERT_EQ(yaw.size(), pts.size());
  EXPECT_NEAR(yaw.front(), start_yaw, kYawTol);
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (pts[i].task >= 0) {
      EXPECT_NEAR(WrapAngle(yaw[i] - task_yaw[pts[i].task]), 0.0, kYawTol);
    }
  // Unwrapped, keys are 90°, 170°, 190°: the spline is monotone and stays within [90°, 190°].
  double prev = yaw.front();
  double unwrapped = prev;
  for (std::size_t i = 1; i < yaw.size(); ++i) {
    const double step = WrapAngle(yaw[i] - prev);
    EXPECT_GE(step, -1e-12);
    unwrapped += step;
    prev = yaw[i];
    EXPECT_LE(unwrapped, 190.0 * kPi / 180.0 + 1e-9);
    EXPECT_LT(std::abs(step), 0.2);  // smooth: no jumps between 0.2 m samples
  }
}

TEST(OmtSmoothing, StepYawTurnsAtTaskViews) {
  const std::vector<PathPoint> pts = ZigZag();
  const std::vector<double> task_yaw{1.0, -1.0};
  const std::vector<double> yaw = StepYaw(pts, 0.0, task_yaw);
  EXPECT_NEAR(yaw.front(), 1.0, kYawTol);  // heading for the first task view already
  EXPECT_NEAR(yaw.back(), -1.0, kYawTol);
}

}  // namespace
}  // namespace voxplan::omt
