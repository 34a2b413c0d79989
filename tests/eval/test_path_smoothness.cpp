// Path smoothness (eval/path_smoothness.h) on hand-made tracks with exact answers: a straight
// drive, a turn in place, a circle (turning per metre = curvature), a square's corners, a camera
// pan at a standstill, the heading wrap, and the team sum.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "eval/path_smoothness.h"

namespace voxplan {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kExact = 1e-9;

RobotSample At(double t, double x, double y, double yaw, double cam_yaw = 0.0,
               double cam_pitch = 0.0) {
  RobotSample s;
  s.t_s = t;
  s.x_m = x;
  s.y_m = y;
  s.yaw_rad = yaw;
  s.cam_yaw_rad = cam_yaw;
  s.cam_pitch_rad = cam_pitch;
  return s;
}

TEST(PathSmoothness, StraightDriveAtConstantHeadingHasNoAngularMotion) {
  RobotTrack track{"r0", {}};
  for (int i = 0; i <= 20; ++i) track.samples.push_back(At(0.5 * i, 0.25 * i, 0.0, 0.3));
  const PathSmoothness s = BaseSmoothness(track);
  EXPECT_NEAR(s.time_s, 10.0, kExact);
  EXPECT_NEAR(s.distance_m, 5.0, kExact);
  EXPECT_EQ(s.mean_abs_angular_accel_radps2, 0.0);
  EXPECT_EQ(s.turning_rad, 0.0);
  EXPECT_EQ(s.sharp_turns, 0u);
}

TEST(PathSmoothness, TurnInPlaceStartsAndStopsItsAngularVelocity) {
  // A quarter turn in 1 s after 1 s at rest: ω jumps 0 -> π/2 -> 0 over a 2 s span.
  RobotTrack track{"r0",
                   {At(0.0, 1.0, 1.0, 0.0), At(1.0, 1.0, 1.0, 0.0), At(2.0, 1.0, 1.0, kPi / 2)}};
  const PathSmoothness s = BaseSmoothness(track);
  EXPECT_NEAR(s.angular_velocity_jumps_radps, kPi, kExact);
  EXPECT_NEAR(s.mean_abs_angular_accel_radps2, kPi / 2, kExact);
  EXPECT_NEAR(s.turning_rad, kPi / 2, kExact);
  EXPECT_EQ(s.turning_per_m, 0.0);  // no travel: no per-metre figures
  EXPECT_EQ(s.sharp_turns, 1u);     // the one window holds the whole quarter turn
  EXPECT_EQ(s.sharp_turns_per_10m, 0.0);
}

TEST(PathSmoothness, CircleTurnsByItsCurvaturePerMetreAtAConstantRate) {
  // Radius 2 m at 0.5 m/s, one revolution in 360 steps: ω = v / R throughout, so the only jumps
  // are at the start and the stop.
  const double radius = 2.0, speed = 0.5, omega = speed / radius;
  const int steps = 360;
  const double period = 2.0 * kPi / omega;
  RobotTrack track{"r0", {}};
  for (int i = 0; i <= steps; ++i) {
    const double t = period * i / steps, a = omega * t;
    track.samples.push_back(At(t, radius * std::cos(a), radius * std::sin(a), a + kPi / 2));
  }
  const PathSmoothness s = BaseSmoothness(track);
  EXPECT_NEAR(s.angular_velocity_jumps_radps, 2.0 * omega, 1e-9);
  EXPECT_NEAR(s.mean_abs_angular_accel_radps2, 2.0 * omega / period, 1e-9);
  EXPECT_NEAR(s.turning_rad, 2.0 * kPi, 1e-9);
  // Chords are a hair shorter than the arc: 1/R within the chord's relative error (~1e-5).
  EXPECT_NEAR(s.turning_per_m, 1.0 / radius, 1e-5);
  // 1° per 3.5 cm: no 0.5 m window turns by more than 45°.
  EXPECT_EQ(s.sharp_turns, 0u);
}

TEST(PathSmoothness, SquareCornersAreSharpTurns) {
  // 2 m sides driven in 0.25 m steps, a quarter turn in place at three corners.
  RobotTrack track{"r0", {}};
  double t = 0.0, x = 0.0, y = 0.0, yaw = 0.0;
  track.samples.push_back(At(t, x, y, yaw));
  for (int side = 0; side < 4; ++side) {
    if (side > 0) track.samples.push_back(At(t += 1.0, x, y, yaw += kPi / 2));
    for (int k = 0; k < 8; ++k) {
      x += 0.25 * std::cos(yaw);
      y += 0.25 * std::sin(yaw);
      track.samples.push_back(At(t += 0.5, x, y, yaw));
    }
  }
  const PathSmoothness s = BaseSmoothness(track);
  EXPECT_NEAR(s.distance_m, 8.0, 1e-9);
  EXPECT_EQ(s.sharp_turns, 3u);
  EXPECT_NEAR(s.sharp_turns_per_10m, 3.75, 1e-9);
  EXPECT_NEAR(s.turning_rad, 1.5 * kPi, 1e-9);
  // Each corner: ω 0 -> π/2 -> 0 (rad/s), 2 × π/2 per corner.
  EXPECT_NEAR(s.angular_velocity_jumps_radps, 3 * kPi, 1e-9);
}

TEST(PathSmoothness, HeadingWrapIsTheShortWayRound) {
  RobotTrack track{"r0", {At(0.0, 0.0, 0.0, 3.1), At(1.0, 0.5, 0.0, -3.1)}};
  const PathSmoothness s = BaseSmoothness(track);
  EXPECT_NEAR(s.turning_rad, 2.0 * kPi - 6.2, 1e-12);
}

TEST(PathSmoothness, CameraPanAtAStandstillMovesTheCameraNotTheBase) {
  // 12 pans of 30° in 0.35 s each, then a tilt of 0.5 rad: the base never turns.
  RobotTrack track{"r0", {}};
  for (int i = 0; i <= 12; ++i) track.samples.push_back(At(0.35 * i, 1.0, 2.0, 0.7, i * kPi / 6));
  track.samples.push_back(At(0.35 * 13, 1.0, 2.0, 0.7, 2 * kPi, 0.5));
  const PathSmoothness base = BaseSmoothness(track), camera = CameraSmoothness(track);
  EXPECT_EQ(base.turning_rad, 0.0);
  EXPECT_EQ(base.angular_velocity_jumps_radps, 0.0);
  EXPECT_NEAR(camera.turning_rad, 2 * kPi + 0.5, 1e-9);
  // Jumps: start (pan rate), pan -> tilt (a right angle between the rates), stop (tilt rate).
  const double pan = (kPi / 6) / 0.35, tilt = 0.5 / 0.35;
  EXPECT_NEAR(camera.angular_velocity_jumps_radps, pan + std::hypot(pan, tilt) + tilt, 1e-9);
}

TEST(PathSmoothness, TeamSumWeightsByTimeAndTravel) {
  RobotTrack turn{"r0", {At(0.0, 0.0, 0.0, 0.0), At(1.0, 0.0, 0.0, kPi / 2)}};
  RobotTrack drive{"r1", {At(0.0, 0.0, 0.0, 0.0), At(3.0, 3.0, 0.0, 0.0)}};
  const PathSmoothness team = CombineSmoothness(BaseSmoothness(turn), BaseSmoothness(drive));
  EXPECT_NEAR(team.time_s, 4.0, kExact);
  EXPECT_NEAR(team.distance_m, 3.0, kExact);
  EXPECT_NEAR(team.mean_abs_angular_accel_radps2, kPi / 4.0, kExact);  // π over 4 robot-seconds
  EXPECT_NEAR(team.turning_per_m, (kPi / 2) / 3.0, kExact);
  EXPECT_EQ(team.sharp_turns, 1u);
}

}  // namespace
}  // namespace voxplan
