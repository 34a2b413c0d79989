// Robots: footprint collision checks against a hand-made floor plan, motion limits and the
// simulation clock, modes, the camera pose from the robot state, the fusion trigger.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim/robot.h"

namespace voxplan {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr double kClockTolerance_s = 1e-5;
constexpr float kPoseTolerance = 1e-5f;

// A 4 m x 4 m free square (5 cm cells, origin at 0) walled by one obstacle row on each side,
// with a 1 m obstacle block in the middle ([1.5, 2.5]^2).
FloorPlan SquareWithPillar() {
  FloorPlan plan;
  plan.resolution_m = 0.05f;
  plan.width = plan.height = 80;
  plan.cells.assign(80 * 80, PlanCell::kFree);
  for (int y = 0; y < 80; ++y)
    for (int x = 0; x < 80; ++x) {
      const bool wall = x == 0 || y == 0 || x == 79 || y == 79;
      const bool pillar = x >= 30 && x < 50 && y >= 30 && y < 50;
      if (wall || pillar) plan.cells[size_t(y) * 80 + x] = PlanCell::kObstacle;
    }
  return plan;
}

RobotState At(float x, float y, float heading = 0.f) {
  RobotState s;
  s.position_W = {x, y};
  s.heading_rad = heading;
  return s;
}

TEST(Robot, FootprintAgainstFloorPlan) {
  const FloorPlan plan = SquareWithPillar();
  const float r = 0.2f;
  EXPECT_TRUE(FootprintFree(plan, {0.6f, 0.6f}, r));
  EXPECT_FALSE(FootprintFree(plan, {2.0f, 2.0f}, r));  // inside the pillar
  EXPECT_FALSE(FootprintFree(plan, {1.4f, 2.0f}, r));  // 0.1 m from the pillar
  EXPECT_TRUE(FootprintFree(plan, {1.2f, 2.0f}, r));   // 0.3 m from it
  // Exactly the radius from the nearest pillar cell's centre (1.525, 2.025), as a host route
  // at the clearance limit runs: touching, not blocked; a centimetre closer is.
  EXPECT_TRUE(FootprintFree(plan, {1.325f, 2.025f}, r));
  EXPECT_FALSE(FootprintFree(plan, {1.335f, 2.025f}, r));
  EXPECT_FALSE(FootprintFree(plan, {0.15f, 1.0f}, r));  // against the outer wall
  EXPECT_FALSE(FootprintFree(plan, {-1.f, 1.0f}, r));   // off the plan
  EXPECT_TRUE(SegmentFree(plan, {0.6f, 0.6f}, {3.4f, 0.6f}, r));
  EXPECT_FALSE(SegmentFree(plan, {0.6f, 0.6f}, {3.4f, 3.4f}, r));  // through the pillar
}

TEST(Robot, RefusesStartInsideObstacles) {
  const FloorPlan plan = SquareWithPillar();
  auto inside = Robot::Create({}, plan, At(2.f, 2.f));
  ASSERT_FALSE(inside.ok());
  EXPECT_NE(inside.status().message().find("(2, 2)"), std::string::npos)
      << inside.status().message();
  EXPECT_FALSE(Robot::Create({}, plan, At(1.45f, 2.f)).ok());  // footprint overlaps
  EXPECT_TRUE(Robot::Create({}, plan, At(0.6f, 0.6f)).ok());
  RobotParams bad;
  bad.radius_m = 0.f;
  EXPECT_FALSE(Robot::Create(bad, plan, At(0.6f, 0.6f)).ok());
  bad = {};
  bad.explorer.max_speed_mps = -1.f;
  EXPECT_FALSE(Robot::Create(bad, plan, At(0.6f, 0.6f)).ok());
}

TEST(Robot, ClockFollowsSpeedsAndTurnRates) {
  RobotParams params;
  auto robot = Robot::Create(params, SquareWithPillar(), At(0.6f, 0.6f));
  ASSERT_TRUE(robot.ok());
  const ModeParams& ex = params.explorer;
  // Straight ahead: distance / speed only.
  ASSERT_TRUE(robot->DriveTo({3.4f, 0.6f}).ok());
  EXPECT_NEAR(robot->clock_s(), 2.8 / ex.max_speed_mps, kClockTolerance_s);
  // A left turn of 90° first, then 2.8 m.
  double t = robot->clock_s();
  ASSERT_TRUE(robot->DriveTo({3.4f, 3.4f}).ok());
  EXPECT_NEAR(robot->clock_s() - t, (kPi / 2) / ex.max_turn_rate_radps + 2.8 / ex.max_speed_mps,
              kClockTolerance_s);
  EXPECT_NEAR(robot->state().heading_rad, kPi / 2, kPoseTolerance);
  EXPECT_NEAR(robot->distance_m(), 5.6, 1e-5);
  // The reconstructor is slower over the same leg.
  robot->SetMode(RobotMode::kReconstructor);
  t = robot->clock_s();
  ASSERT_TRUE(robot->DriveTo({3.4f, 0.6f}).ok());  // turn 180°, 2.8 m
  const ModeParams& rec = params.reconstructor;
  EXPECT_NEAR(robot->clock_s() - t, kPi / rec.max_turn_rate_radps + 2.8 / rec.max_speed_mps,
              kClockTolerance_s);
  EXPECT_LT(rec.max_speed_mps, ex.max_speed_mps);
  EXPECT_LT(rec.horizontal_fov_deg, ex.horizontal_fov_deg);
  EXPECT_LT(rec.max_range_m, ex.max_range_m);
  EXPECT_GT(robot->camera().fx, CameraWithFov(640, 480, ex.horizontal_fov_deg).fx);
  // Camera joints and dwell.
  t = robot->clock_s();
  robot->SetCameraYaw(kPi);
  EXPECT_NEAR(robot->clock_s() - t, kPi / params.camera_yaw_rate_radps, kClockTolerance_s);
  t = robot->clock_s();
  robot->Dwell();
  EXPECT_NEAR(robot->clock_s() - t, params.dwell_s, kClockTolerance_s);
  EXPECT_FALSE(robot->SetCameraPitch(1.5f).ok());  // beyond 60°
  EXPECT_TRUE(robot->SetCameraPitch(-0.3f).ok());
}

TEST(Robot, RefusesBlockedMovesAndKeepsState) {
  auto robot = Robot::Create({}, SquareWithPillar(), At(0.6f, 0.6f));
  ASSERT_TRUE(robot.ok());
  const Status s = robot->DriveTo({3.4f, 3.4f});
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("collides"), std::string::npos) << s.message();
  EXPECT_EQ(robot->clock_s(), 0.0);
  EXPECT_EQ(robot->state().position_W, Eigen::Vector2f(0.6f, 0.6f));
  EXPECT_EQ(robot->state().heading_rad, 0.f);
}

TEST(Robot, TheArmCameraMovesWithAContinuousPieceAtItsSpeedInsideItsWorkspace) {
  RobotParams params;
  params.explorer.mount = MountKind::kArm;  // Fetch-sized defaults, 0.25 m/s
  const ArmParams& arm = params.explorer.arm;
  auto robot = Robot::Create(params, SquareWithPillar(), At(0.6f, 0.6f));
  ASSERT_TRUE(robot.ok());
  const Eigen::Vector3f rest = robot->state().camera_offset_B;  // 0.3 m ahead, head height
  const Eigen::Vector3f target = ArmOffset(0.8f, {0.5f, 0.2f}, params.camera_height_m);
  // 0.4 m at 0.5 m/s: the piece's 0.8 s, the arm's speed moves the camera 0.2 m of its 0.49.
  const float step_m = 0.8f * arm.speed_mps;
  ASSERT_TRUE(robot->DriveAlong({1.0f, 0.6f}, 0.5f, 0.f, 0.f, target).ok());
  EXPECT_NEAR(robot->clock_s(), 0.8, kClockTolerance_s);  // the arm does not slow the base
  Eigen::Vector3f o = robot->state().camera_offset_B;
  EXPECT_NEAR((o - rest).norm(), step_m, 2e-3f);  // along its path, a little off the chord
  EXPECT_LE((o - rest).norm(), step_m + 1e-5f);
  EXPECT_LT((target - o).norm(), (target - rest).norm() - 0.9f * step_m);
  ASSERT_TRUE(robot->DriveAlong({1.4f, 0.6f}, 0.5f, 0.f, 0.f, target).ok());
  EXPECT_NE(robot->state().camera_offset_B, target);
  ASSERT_TRUE(robot->DriveAlong({1.8f, 0.6f}, 0.5f, 0.f, 0.f, target).ok());
  EXPECT_EQ(robot->state().camera_offset_B, target);
  EXPECT_NEAR(robot->clock_s(), 2.4, kClockTolerance_s);
  EXPECT_TRUE(robot->T_W_C().translation().isApprox(Eigen::Vector3f(2.3f, 0.8f, 0.8f), 1e-5f));

  // From one side of the base to the other: around the front, inside the workspace at every
  // step (a straight line would pass through the base, within the reach's inner limit).
  const Eigen::Vector3f right = ArmOffset(1.0f, {0.f, -0.5f}, params.camera_height_m);
  ASSERT_TRUE(robot->SetArmCamera(1.0f, {0.f, 0.5f}).ok());
  Eigen::Vector2f goal = robot->state().position_W;
  int pieces = 0;
  for (; pieces < 60 && robot->state().camera_offset_B != right; ++pieces) {
    goal.x() += 0.02f;  // 0.2 s at 0.1 m/s: 0.05 m of the arm's path
    ASSERT_TRUE(robot->DriveAlong(goal, 0.1f, 0.f, 0.f, right).ok());
    const Eigen::Vector3f& at = robot->state().camera_offset_B;
    EXPECT_EQ(ArmWorkspaceProblem(arm, at.z() + params.camera_height_m, at.head<2>()), "");
    EXPECT_NEAR(at.head<2>().norm(), 0.5f, 1e-5f);
  }
  EXPECT_EQ(robot->state().camera_offset_B, right);
  EXPECT_GE(pieces, 31);  // half a turn at 0.5 m: 1.57 m
  EXPECT_LE(pieces, 32);

  // Refused, state and clock unchanged: a target outside the workspace; an arm target on a head.
  const double t = robot->clock_s();
  const Status outside =
      robot->DriveAlong(robot->state().position_W + Eigen::Vector2f(0.1f, 0.f), 0.5f, 0.f, 0.f,
                        ArmOffset(2.0f, {0.5f, 0.f}, params.camera_height_m));
  EXPECT_FALSE(outside.ok());
  EXPECT_NE(outside.message().find("camera height"), std::string::npos) << outside.message();
  EXPECT_EQ(robot->clock_s(), t);
  EXPECT_EQ(robot->state().camera_offset_B, right);
  robot->SetMode(RobotMode::kReconstructor);  // on a head
  EXPECT_FALSE(robot
                   ->DriveAlong(robot->state().position_W + Eigen::Vector2f(0.1f, 0.f), 0.5f, 0.f,
                                0.f, target)
                   .ok());
}

TEST(Robot, ClampToArmWorkspaceMovesEachCoordinateIntoItsRange) {
  const ArmParams arm;  // 0.4-1.5 m high, 0.3-0.8 m reach, +-90 deg
  float h = 1.0f;
  Eigen::Vector2f o(0.5f, 0.1f);
  EXPECT_FALSE(ClampToArmWorkspace(arm, &h, &o));  // inside: unchanged
  EXPECT_EQ(h, 1.0f);
  EXPECT_EQ(o, Eigen::Vector2f(0.5f, 0.1f));
  h = 2.0f;
  EXPECT_TRUE(ClampToArmWorkspace(arm, &h, &o));  // only the height was out
  EXPECT_EQ(h, 1.5f);
  EXPECT_EQ(o, Eigen::Vector2f(0.5f, 0.1f));
  o = {2.0f, 0.f};
  EXPECT_TRUE(ClampToArmWorkspace(arm, &h, &o));  // too far: the reach's limit, same bearing
  EXPECT_NEAR(o.x(), 0.8f, 1e-6f);
  EXPECT_NEAR(o.y(), 0.f, 1e-6f);
  o = {-0.5f, 0.1f};  // behind the base: to the bearing limit on its side, reach kept
  EXPECT_TRUE(ClampToArmWorkspace(arm, &h, &o));
  EXPECT_NEAR(o.x(), 0.f, 1e-6f);
  EXPECT_NEAR(o.y(), std::hypot(0.5f, 0.1f), 1e-6f);
  o = {0.f, 0.f};  // at the base: straight ahead at the nearest reach
  EXPECT_TRUE(ClampToArmWorkspace(arm, &h, &o));
  EXPECT_NEAR(o.x(), 0.3f, 1e-6f);
  EXPECT_NEAR(o.y(), 0.f, 1e-6f);
  EXPECT_EQ(ArmWorkspaceProblem(arm, h, o), "");
}

TEST(Robot, CameraPoseFromState) {
  RobotState s = At(1.f, 2.f, kPi / 2);  // base facing +y
  const Pose3f a = CameraPoseFromState(s, 1.2f);
  EXPECT_TRUE(a.translation().isApprox(Eigen::Vector3f(1.f, 2.f, 1.2f)));
  // OpenCV axes: z forward (+y world), x right (+x world), y down (-z world).
  EXPECT_TRUE(a.linear().col(2).isApprox(Eigen::Vector3f::UnitY(), kPoseTolerance));
  EXPECT_TRUE(a.linear().col(0).isApprox(Eigen::Vector3f::UnitX(), kPoseTolerance));
  EXPECT_TRUE(a.linear().col(1).isApprox(-Eigen::Vector3f::UnitZ(), kPoseTolerance));
  // The yaw joint adds to the base heading; pitch up raises the optical axis.
  s.camera_yaw_rad = kPi / 2;
  s.camera_pitch_rad = 0.3f;
  const Pose3f b = CameraPoseFromState(s, 1.2f);
  const Eigen::Vector3f z = b.linear().col(2);
  EXPECT_NEAR(z.x(), -std::cos(0.3f), kPoseTolerance);
  EXPECT_NEAR(z.z(), std::sin(0.3f), kPoseTolerance);
  EXPECT_NEAR(b.linear().determinant(), 1.f, kPoseTolerance);
  EXPECT_TRUE((b.linear().transpose() * b.linear()).isIdentity(kPoseTolerance));
  EXPECT_NEAR(b.linear().col(0).z(), 0.f, kPoseTolerance);  // x stays horizontal
  // A 90° field of view at 640 px wide is fx = 320.
  const PinholeCamera cam = CameraWithFov(640, 480, 90.f);
  EXPECT_NEAR(cam.fx, 320.f, 1e-3f);
  EXPECT_EQ(cam.fx, cam.fy);
  EXPECT_EQ(cam.cx, 319.5f);
}

TEST(Robot, FusionTriggerOnDistanceOrAngle) {
  FusionTrigger trigger({0.1f, 10.f});
  RobotState s = At(0.f, 0.f);
  EXPECT_TRUE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));  // first frame
  s.position_W.x() = 0.05f;
  EXPECT_FALSE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));
  s.position_W.x() = 0.09f;
  EXPECT_FALSE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));  // still < 0.1 from the first
  s.position_W.x() = 0.12f;
  EXPECT_TRUE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));
  s.camera_yaw_rad = 8.f * kPi / 180.f;
  EXPECT_FALSE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));
  s.camera_yaw_rad = 12.f * kPi / 180.f;
  EXPECT_TRUE(trigger.ShouldFuse(CameraPoseFromState(s, 1.f)));
  EXPECT_EQ(trigger.fired(), 3u);
}

}  // namespace
}  // namespace voxplan
