// Pathline advection (X L182-195, L308): RK4 on analytic fields, the orientation rule, obstacles,
// the wall push and the wedge speed profile on synthetic floor plans.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/tensorfield/algorithms/advection.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"
#include "tests/plugins/tensorfield/tensor_scenes.h"

namespace voxplan::tensorfield {
namespace {

using omt::Cell;
using omt::kPi;
using test::FillRect;
using test::kRes;
using test::MakeRaster;
using test::RayAngleBetween;

constexpr double kDeg = kPi / 180.0;
// A uniform field is sampled exactly, so the line is straight to rounding.
constexpr double kStraightTolerance_m = 1e-9;
// Circle of radius 1 m from the bilinearly sampled θ = φ + 90° pattern at 5 cm cells: the sampled
// tensor deviates from the exact one by O(res² |∇²τ|) ≈ 1e-3, a radial drift of a few mm per turn.
constexpr double kCircleTolerance_m = 5e-3;

// Turning angle between consecutive segments of a pathline, the largest.
double MaxTurn(const Pathline& line) {
  double worst = 0.0;
  for (std::size_t i = 2; i < line.points.size(); ++i) {
    const Eigen::Vector2d a = line.points[i - 1].position_m - line.points[i - 2].position_m;
    const Eigen::Vector2d b = line.points[i].position_m - line.points[i - 1].position_m;
    worst = std::max(worst, RayAngleBetween(std::atan2(a.y(), a.x()), std::atan2(b.y(), b.x())));
  }
  return worst;
}

TEST(Advection, UniformFieldGoesStraightAtTheStepAndLength) {
  const double theta = 0.3;
  const TensorRaster f =
      test::AnalyticField(80, 80, [&](const Eigen::Vector2d&) { return BasisTensor(theta); });
  const Eigen::Vector2d start(2.0, 2.0);
  for (double heading : {theta + 0.4, theta + kPi - 0.4}) {  // either side of the line field
    for (double length : {0.36, 1.0}) {
      AdvectionParams params;
      params.max_length_m = length;
      const Pathline line = AdvectPathline(f, start, heading, {}, params);
      EXPECT_EQ(line.stop, AdvectionStop::kLength);
      ASSERT_EQ(line.points.size(), static_cast<std::size_t>(std::ceil(length / 0.05 - 1e-9)) + 1);
      EXPECT_NEAR(line.Length(), length, 1e-12);
      // The major eigenvector oriented towards the heading.
      const double dir = std::cos(heading - theta) > 0 ? theta : theta + kPi;
      const Eigen::Vector2d u(std::cos(dir), std::sin(dir));
      for (std::size_t i = 0; i < line.points.size(); ++i) {
        const PathPoint& p = line.points[i];
        const Eigen::Vector2d d = p.position_m - start;
        EXPECT_NEAR(d.x() * u.y() - d.y() * u.x(), 0.0, kStraightTolerance_m);  // on the line
        EXPECT_NEAR(d.dot(u), p.arc_length_m, kStraightTolerance_m);            // forwards
        if (i > 0 && i + 1 < line.points.size()) {
          EXPECT_NEAR(p.arc_length_m - line.points[i - 1].arc_length_m, 0.05, 1e-12);
        }
        EXPECT_LE(RayAngleBetween(p.heading_rad, dir), 1e-9);
        EXPECT_EQ(p.speed_mps, params.max_speed_mps);  // no wedge ahead
      }
    }
  }
}

// The vector-field baselines (AdvectionParams::vector_field): the components are a vector, its
// sign chosen once from the heading; a sink (vectors converging from both sides, the normals of
// two facing walls) stops the line where the field cancels.
TEST(Advection, VectorFieldKeepsItsSignAndRunsIntoASink) {
  const TensorRaster uniform =
      test::AnalyticField(80, 80, [](const Eigen::Vector2d&) { return Eigen::Vector2d(1.0, 0.0); });
  AdvectionParams params;
  params.vector_field = true;
  params.max_length_m = 1.0;
  for (double heading : {0.4, kPi - 0.4}) {
    const Pathline line = AdvectPathline(uniform, {2.0, 2.0}, heading, {}, params);
    ASSERT_EQ(line.stop, AdvectionStop::kLength);
    const double sign = std::cos(heading) > 0.0 ? 1.0 : -1.0;
    EXPECT_NEAR(line.points.back().position_m.x() - 2.0, sign * 1.0, 1e-9);
    EXPECT_NEAR(line.points.back().position_m.y(), 2.0, 1e-9);
  }
  // Normals of walls at y = 0 and y = 4 m: (0, 1) below the mid line, (0, -1) above, cancelling
  // at y = 2. From y = 1 heading up the line stops at the mid line, within one step.
  const TensorRaster sink = test::AnalyticField(80, 80, [](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(0.0, std::tanh(4.0 * (2.0 - p.y())));
  });
  params.max_length_m = 3.0;
  params.min_magnitude = 1e-3;
  const Pathline into = AdvectPathline(sink, {2.0, 1.0}, 0.5 * kPi, {}, params);
  EXPECT_EQ(into.stop, AdvectionStop::kDegenerate);
  EXPECT_NEAR(into.points.back().position_m.y(), 2.0, 0.05);
  EXPECT_LT(into.Length(), 1.05);
}

TEST(Advection, AWallPushThatUndoesTheStepEndsTheLineAsBlocked) {
  // A vector field straight into a wall at x < 0.5, the push as long as the step: each step
  // is pushed back to where it started. The line must end there (it once looped for ever).
  omt::OccupancyRaster room = test::MakeRaster(4.0, 4.0, omt::Cell::kFree);
  test::FillRect(&room, 0.0, 0.0, 0.5, 4.0, omt::Cell::kOccupied);
  const omt::ClearanceRaster clearance = omt::ComputeClearance(room);
  const TensorRaster into_wall = test::AnalyticField(
      80, 80, [](const Eigen::Vector2d&) { return Eigen::Vector2d(-1.0, 0.0); });
  AdvectionParams params;
  params.vector_field = true;
  params.max_length_m = 2.0;
  params.wall_clearance_m = 0.3;
  params.wall_push_per_step_m = params.step_m;
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  const Pathline line = AdvectPathline(into_wall, {0.725, 2.0}, kPi, {}, params, obstacles);
  EXPECT_EQ(line.stop, AdvectionStop::kBlocked);
  EXPECT_LT(line.Length(), 0.2);
}

TEST(Advection, CircularFieldIsFollowedAlongTheCircle) {
  const Eigen::Vector2d c(2.0, 2.0);
  // θ = polar angle + 90°: the major eigenvectors are tangent to circles around c.
  const TensorRaster f = test::AnalyticField(80, 80, [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d d = p - c;
    return BasisTensor(std::atan2(d.y(), d.x()) + 0.5 * kPi);
  });
  AdvectionParams params;
  params.max_length_m = 0.9 * 2.0 * kPi;  // most of one turn: no loop yet
  const Pathline line = AdvectPathline(f, c + Eigen::Vector2d(1.0, 0.0), 0.5 * kPi, {}, params);
  EXPECT_EQ(line.stop, AdvectionStop::kLength);
  ASSERT_GT(line.points.size(), 100u);
  double swept = 0.0;
  for (std::size_t i = 0; i < line.points.size(); ++i) {
    const Eigen::Vector2d d = line.points[i].position_m - c;
    EXPECT_NEAR(d.norm(), 1.0, kCircleTolerance_m) << i;
    if (i > 0) {
      const Eigen::Vector2d e = line.points[i - 1].position_m - c;
      swept += std::atan2(e.x() * d.y() - e.y() * d.x(), e.dot(d));
    }
  }
  EXPECT_NEAR(swept, 0.9 * 2.0 * kPi, 0.01);  // counter-clockwise, as the heading started
  // Longer: the line closes the circle and stops there.
  params.max_length_m = 10.0;
  const Pathline loop = AdvectPathline(f, c + Eigen::Vector2d(1.0, 0.0), 0.5 * kPi, {}, params);
  EXPECT_EQ(loop.stop, AdvectionStop::kLoop);
  EXPECT_NEAR(loop.Length(), 2.0 * kPi, params.loop_radius_m + params.step_m);
}

TEST(Advection, OrientationRuleNeverTurnsBackInOneStep) {
  // A line field whose angle changes by up to ~90° between neighbouring cells: without orienting
  // each stage towards the direction of travel, the line would reverse.
  const TensorRaster f = test::AnalyticField(80, 80, [](const Eigen::Vector2d& p) {
    const double h = std::sin(12.9898 * p.x() + 78.233 * p.y()) * 43758.5453;
    return BasisTensor(kPi * (h - std::floor(h)));
  });
  AdvectionParams params;
  params.max_length_m = 2.0;
  params.min_magnitude = 0.0;
  params.loop_radius_m = 0.0;
  int lines = 0;
  for (double heading = 0.0; heading < 2.0 * kPi; heading += 0.7) {
    const Pathline line = AdvectPathline(f, Eigen::Vector2d(2.0, 2.0), heading, {}, params);
    ASSERT_GE(line.points.size(), 3u);
    EXPECT_LE(MaxTurn(line), 0.5 * kPi + 1e-9) << heading;
    // The first step agrees with the heading.
    const Eigen::Vector2d first = line.points[1].position_m - line.points[0].position_m;
    EXPECT_GE(first.dot(Eigen::Vector2d(std::cos(heading), std::sin(heading))), 0.0);
    ++lines;
  }
  EXPECT_EQ(lines, 9);
}

TEST(Advection, TimeVaryingFramesAreBlendedAlongTheArc) {
  const auto uniform = [](double theta) {
    return test::AnalyticField(80, 80, [=](const Eigen::Vector2d&) { return BasisTensor(theta); });
  };
  const std::vector<TensorRaster> frames = {uniform(0.0), uniform(30.0 * kDeg)};
  AdvectionParams params;
  params.max_length_m = 1.0;
  params.frame_spacing_m = 0.5;
  const Pathline line = AdvectPathline(frames, Eigen::Vector2d(1.0, 1.0), 0.0, {}, params);
  ASSERT_EQ(line.stop, AdvectionStop::kLength);
  // From arc 0.5 on, the last frame: 30°. Before it the blend of (1, 0) and (cos 60°, sin 60°)
  // whose angle grows monotonically.
  double previous = -1.0;
  for (std::size_t i = 1; i < line.points.size(); ++i) {
    const Eigen::Vector2d d = line.points[i].position_m - line.points[i - 1].position_m;
    const double a = std::atan2(d.y(), d.x());
    EXPECT_GE(a, previous - 1e-12);
    previous = a;
    if (line.points[i - 1].arc_length_m >= 0.5) {
      EXPECT_NEAR(a, 30.0 * kDeg, 1e-9);
    }
  }
  EXPECT_GT(line.points[2].position_m.y() - 1.0, 0.0);  // already turning in the first steps
}

// A corridor y in [1, 2) from x = 0 to 8 (open ends), the walls 1 m apart.
omt::OccupancyRaster OpenCorridor() {
  omt::OccupancyRaster r = MakeRaster(8.0, 3.0, Cell::kOccupied);
  FillRect(&r, 0.0, 1.0, 8.0, 2.0, Cell::kFree);
  return r;
}

TEST(Advection, HeadingIntoAWallIsBlockedBeforeIt) {
  const omt::OccupancyRaster r = OpenCorridor();
  const omt::ClearanceRaster clearance = omt::ComputeClearance(r);
  // A field at 30° everywhere: the line would cross the corridor into the far wall.
  TensorRaster f = test::AnalyticField(r.geometry.width, r.geometry.height,
                                       [](const Eigen::Vector2d&) { return BasisTensor(0.5); });
  f.domain = FieldDomain(r, false);
  AdvectionParams params;
  params.max_length_m = 3.0;
  params.wall_clearance_m = 0.0;  // the push would only delay the hit
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  const Pathline line = AdvectPathline(f, Eigen::Vector2d(2.0, 1.5), 0.5, {}, params, obstacles);
  EXPECT_EQ(line.stop, AdvectionStop::kBlocked);
  EXPECT_TRUE(line.Blocked());
  for (const PathPoint& p : line.points) {
    EXPECT_EQ(r.At(r.geometry.IndexOf(p.position_m)), Cell::kFree);
    EXPECT_GE(omt::ClearanceBilinear(clearance, p.position_m), params.block_clearance_m);
  }
  // Stopped within one step of the clearance band, not earlier: the next 5 cm step along 0.5 rad
  // lowers the clearance by at most 5 cm × sin(0.5).
  const double last = omt::ClearanceBilinear(clearance, line.points.back().position_m);
  EXPECT_LT(last, params.block_clearance_m + params.step_m * std::sin(0.5) + 1e-9);

  // Along the corridor nothing blocks; the counter sees one blocked line of two.
  const TensorRaster along = test::AnalyticField(
      r.geometry.width, r.geometry.height, [](const Eigen::Vector2d&) { return BasisTensor(0.0); });
  const Pathline free_line =
      AdvectPathline(along, Eigen::Vector2d(2.0, 1.5), 0.0, {}, params, obstacles);
  EXPECT_EQ(free_line.stop, AdvectionStop::kLength);
  BlockedPathCounter counter;
  counter.Add(line);
  counter.Add(free_line);
  EXPECT_EQ(counter.pathlines, 2);
  EXPECT_EQ(counter.blocked, 1);
  EXPECT_DOUBLE_EQ(counter.Rate(), 0.5);

  // Without any obstacle information the same line runs until it leaves the field's domain.
  const Pathline no_obstacles = AdvectPathline(f, Eigen::Vector2d(2.0, 1.5), 0.5, {}, params);
  EXPECT_EQ(no_obstacles.stop, AdvectionStop::kLeftDomain);
}

TEST(Advection, KeyFrameCorridorStaysInFreeSpaceAndStepsAwayFromTheWall) {
  const omt::OccupancyRaster r = OpenCorridor();
  const omt::ClearanceRaster clearance = omt::ComputeClearance(r);
  const TensorRaster f = KeyFrameField(r, {});
  AdvectionParams params;
  params.max_length_m = 2.0;
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  // Start 0.2 m from the lower wall's face (its cell centres at y = 0.975).
  const Eigen::Vector2d start(3.0, 1.2);
  const double start_clearance = omt::ClearanceBilinear(clearance, start);
  ASSERT_LT(start_clearance, params.wall_clearance_m);
  const Pathline line = AdvectPathline(f, start, 0.0, {}, params, obstacles);
  EXPECT_EQ(line.stop, AdvectionStop::kLength);
  EXPECT_GT(line.wall_pushes, 0);
  double previous = start_clearance;
  for (const PathPoint& p : line.points) {
    EXPECT_EQ(r.At(r.geometry.IndexOf(p.position_m)), Cell::kFree);
    const double c = omt::ClearanceBilinear(clearance, p.position_m);
    if (previous < params.wall_clearance_m - 1e-6) {
      EXPECT_GE(c, previous - 1e-6);  // moving out
    }
    previous = c;
    EXPECT_GT(p.position_m.x(), start.x() - 1e-9);  // along the corridor, forwards
  }
  // Out of the band by the end (0.1 m to gain at 2.5 cm per step).
  EXPECT_GE(omt::ClearanceBilinear(clearance, line.points.back().position_m),
            params.wall_clearance_m - 0.01);
  // Without the push the tangential field keeps the line by the wall.
  params.wall_clearance_m = 0.0;
  const Pathline unpushed = AdvectPathline(f, start, 0.0, {}, params, obstacles);
  EXPECT_LT(omt::ClearanceBilinear(clearance, unpushed.points.back().position_m),
            params.block_clearance_m + 0.05);
}

// The dead-end corridor of test_tensor_field: closed at x = 0.5, open at x = 5.
omt::OccupancyRaster DeadEndCorridor() {
  omt::OccupancyRaster r = MakeRaster(5.0, 3.0, Cell::kOccupied);
  FillRect(&r, 0.5, 1.0, 5.0, 2.0, Cell::kFree);
  return r;
}

TEST(Advection, SlowsDownAndStopsAtTheWedgeOfADeadEnd) {
  const omt::OccupancyRaster r = DeadEndCorridor();
  const omt::ClearanceRaster clearance = omt::ComputeClearance(r);
  const TensorRaster f = KeyFrameField(r, {});
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(f);
  ASSERT_EQ(points.size(), 1u);
  ASSERT_EQ(points[0].type, DegenerateType::kWedge);
  const Eigen::Vector2d wedge = points[0].position_m;
  AdvectionParams params;
  params.max_length_m = 4.0;
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  const Pathline line =
      AdvectPathline(f, Eigen::Vector2d(3.5, 1.5), kPi, points, params, obstacles);
  ASSERT_EQ(line.stop, AdvectionStop::kWedge);
  EXPECT_EQ(line.stop_point, 0);
  EXPECT_EQ(line.wedge_ahead, 0);
  EXPECT_LE((line.points.back().position_m - wedge).norm(), params.wedge_capture_radius_m);
  EXPECT_GT(line.Length(), 1.5);  // it drove most of the corridor first
  // Speed: full until slowdown_distance before the wedge, then strictly down to the minimum.
  const double s_end = line.Length();
  for (std::size_t i = 0; i < line.points.size(); ++i) {
    const PathPoint& p = line.points[i];
    if (s_end - p.arc_length_m >= params.slowdown_distance_m) {
      EXPECT_DOUBLE_EQ(p.speed_mps, params.max_speed_mps);
    }
    if (i > 0) {
      const PathPoint& q = line.points[i - 1];
      if (s_end - q.arc_length_m < params.slowdown_distance_m) {
        EXPECT_LT(p.speed_mps, q.speed_mps);
      } else {
        EXPECT_LE(p.speed_mps, q.speed_mps);
      }
    }
  }
  EXPECT_DOUBLE_EQ(line.points.back().speed_mps, params.min_speed_mps);

  // A short pathline (X4's 0.36 m) starting 0.7 m short of the wedge ends at its length, but the
  // look-ahead already sees the wedge and the profile slows down within it.
  AdvectionParams short_params;
  const Eigen::Vector2d near = wedge + Eigen::Vector2d(0.7, 0.0);
  const Pathline short_line = AdvectPathline(f, near, kPi, points, short_params, obstacles);
  EXPECT_EQ(short_line.stop, AdvectionStop::kLength);
  EXPECT_NEAR(short_line.Length(), short_params.max_length_m, 1e-9);
  ASSERT_EQ(short_line.wedge_ahead, 0);
  EXPECT_GT(short_line.wedge_ahead_arc_m, short_params.max_length_m);
  EXPECT_LT(short_line.wedge_ahead_arc_m, 0.7 + short_params.step_m);
  EXPECT_LT(short_line.points.back().speed_mps, short_params.max_speed_mps);
  for (std::size_t i = 1; i < short_line.points.size(); ++i) {
    EXPECT_LE(short_line.points[i].speed_mps, short_line.points[i - 1].speed_mps);
  }
  // Without the wedge list the line is not stopped there (it turns at the degenerate point or
  // stops on the vanishing field, never reported as a wedge).
  const Pathline blind = AdvectPathline(f, Eigen::Vector2d(3.5, 1.5), kPi, {}, params, obstacles);
  EXPECT_NE(blind.stop, AdvectionStop::kWedge);
  EXPECT_EQ(blind.wedge_ahead, -1);
}

TEST(Advection, LeavingAWedgeBehindDoesNotStop) {
  const omt::OccupancyRaster r = DeadEndCorridor();
  const TensorRaster f = KeyFrameField(r, {});
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(f);
  ASSERT_EQ(points.size(), 1u);
  // Starting just past the wedge towards the open end: the line only moves away from it.
  const Eigen::Vector2d start = points[0].position_m + Eigen::Vector2d(0.1, 0.0);
  AdvectionParams params;
  params.max_length_m = 1.0;
  const Pathline line = AdvectPathline(f, start, 0.0, points, params);
  EXPECT_EQ(line.stop, AdvectionStop::kLength);
  EXPECT_EQ(line.wedge_ahead, -1);
}

TEST(Advection, SpeedRampAndStartOutsideTheRaster) {
  AdvectionParams params;
  EXPECT_DOUBLE_EQ(SpeedBeforeWedge(0.0, -1.0, params), params.max_speed_mps);
  EXPECT_DOUBLE_EQ(SpeedBeforeWedge(1.0, 1.0, params), params.min_speed_mps);
  EXPECT_DOUBLE_EQ(SpeedBeforeWedge(0.0, 1.0, params), params.max_speed_mps);
  EXPECT_NEAR(SpeedBeforeWedge(0.7, 1.0, params),
              params.min_speed_mps + 0.5 * (params.max_speed_mps - params.min_speed_mps), 1e-12);
  const TensorRaster f =
      test::AnalyticField(10, 10, [](const Eigen::Vector2d&) { return BasisTensor(0.0); });
  const Pathline line = AdvectPathline(f, Eigen::Vector2d(-1.0, 0.2), 0.0, {}, params);
  EXPECT_TRUE(line.points.empty());
  EXPECT_EQ(line.stop, AdvectionStop::kLeftDomain);
}

}  // namespace
}  // namespace voxplan::tensorfield
