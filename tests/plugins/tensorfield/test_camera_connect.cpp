// X5's connecting camera trajectory (plugins/tensorfield/algorithms/camera_path.h, X L194): at a
// stop the new trajectory starts where the camera is and joins the optimised one. Continuous in
// position and orientation at the stop, within the camera's linear and angular speed limits and
// its workspace, the short way round, the hold while the base turns in place, and untouched when
// the camera is already there.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plugins/tensorfield/algorithms/camera_path.h"
#include "tests/plugins/tensorfield/camera_test_paths.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kSpeedTol = 1e-3f;  // relative, on step speeds
constexpr float kAngleTolRad = 1e-5f;
constexpr float kPositionTolM = 1e-5f;
constexpr float kWorkspaceTolM = 1e-4f;

using test::StraightPath;
using test::Wrap;

// An optimised trajectory along a straight 9 m path (the arm's default workspace): the views
// look half left and a little down, higher is better.
CameraPathResult Optimised(const CameraPathParams& p) {
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    return CameraViewScore{b.heading_rad + 0.5f, -0.1f, q.z()};
  };
  return PlanCameraPath(StraightPath(31, 0.3f), p, {}, score);
}

CameraConnectParams ConnectFor(const CameraPathParams& p) {
  CameraConnectParams c;
  c.workspace = p.candidates.workspace;
  c.limits = p.selection.limits;
  c.floor_z_m = p.candidates.floor_z_m;
  return c;
}

// Steps over the limits (with a relative tolerance), and the largest step speeds.
struct Steps {
  int over_linear = 0, over_angular = 0;
  float max_radps = 0.0f, max_mps = 0.0f;
};
Steps Check(const CameraTrajectory& t, const CameraSpeedLimits& l) {
  Steps out;
  for (std::size_t k = 1; k < t.samples.size(); ++k) {
    const CameraPathSample &a = t.samples[k - 1], &b = t.samples[k];
    const float dt = b.time_s - a.time_s;
    const float turn =
        std::hypot(static_cast<float>(Wrap(b.yaw_rad - a.yaw_rad)), b.pitch_rad - a.pitch_rad);
    const float move = (b.position_W - a.position_W).norm();
    out.over_angular += turn > l.angular_radps * dt * (1.0f + kSpeedTol) + kAngleTolRad;
    out.over_linear += move > l.linear_mps * dt * (1.0f + kSpeedTol) + kPositionTolM;
    if (dt > 0.0f) {
      out.max_radps = std::max(out.max_radps, turn / dt);
      out.max_mps = std::max(out.max_mps, move / dt);
    }
  }
  return out;
}

TEST(CameraConnect, StartsAtTheCameraAndJoinsTheTrajectoryWithinTheLimits) {
  const CameraPathParams p;
  const CameraPathResult r = Optimised(p);
  ASSERT_TRUE(r.selection.feasible);
  const CameraTrajectory optimised = r.trajectory;
  ASSERT_EQ(Check(optimised, p.selection.limits).over_angular, 0);
  // The camera at a stop: looking back over the right shoulder, low on the right of the base.
  CameraPose from;
  from.yaw_rad = -2.4f;
  from.pitch_rad = 0.2f;
  from.position_W =
      CameraPositionInWorkspace(optimised.samples.front().base, 0.5f, -1.2f, 0.5f, 0.f);
  CameraTrajectory t = optimised;
  const CameraConnection c = ConnectCameraTrajectory(from, ConnectFor(p), &t);
  ASSERT_TRUE(c.connected);
  ASSERT_EQ(t.samples.size(), optimised.samples.size());
  // Continuous at the stop: the first pose is the camera's.
  EXPECT_LT((t.samples.front().position_W - from.position_W).norm(), kPositionTolM);
  EXPECT_NEAR(Wrap(t.samples.front().yaw_rad - from.yaw_rad), 0.0, kAngleTolRad);
  EXPECT_NEAR(t.samples.front().pitch_rad, from.pitch_rad, kAngleTolRad);
  // The jump it replaces, and the speeds: the optimised start would need the jump in one step.
  const float jump = std::hypot(static_cast<float>(Wrap(optimised.samples.front().yaw_rad + 2.4)),
                                optimised.samples.front().pitch_rad - 0.2f);
  EXPECT_NEAR(c.jump_rad, jump, kAngleTolRad);
  EXPECT_GT(c.max_radps_before, 5.0f * p.selection.limits.angular_radps);
  EXPECT_GT(c.max_mps_before, p.selection.limits.linear_mps);
  // Within the limits throughout (and so continuous), and inside Ψ.
  const Steps s = Check(t, p.selection.limits);
  EXPECT_EQ(s.over_angular, 0);
  EXPECT_EQ(s.over_linear, 0);
  EXPECT_LE(c.max_radps_after, p.selection.limits.angular_radps * (1.0f + kSpeedTol));
  EXPECT_LE(c.max_mps_after, p.selection.limits.linear_mps * (1.0f + kSpeedTol));
  for (const CameraPathSample& k : t.samples)
    EXPECT_TRUE(
        InCameraWorkspace(k.position_W, k.base, p.candidates.workspace, 0.f, kWorkspaceTolM))
        << "arc " << k.arc_length_m;
  // The blend is long enough for the turn at half the limit: 1.5 jump / (a_m / 2).
  EXPECT_GE(c.duration_s, 3.0f * jump / p.selection.limits.angular_radps - 1e-3f);
  // After the stretch the camera is on the optimised trajectory again.
  int after = 0;
  for (std::size_t k = 0; k < t.samples.size(); ++k) {
    if (t.samples[k].time_s < t.samples.front().time_s + c.duration_s + 1e-3f) continue;
    ++after;
    EXPECT_LT((t.samples[k].position_W - optimised.samples[k].position_W).norm(), kPositionTolM);
    EXPECT_NEAR(Wrap(t.samples[k].yaw_rad - optimised.samples[k].yaw_rad), 0.0, kAngleTolRad);
    EXPECT_NEAR(t.samples[k].pitch_rad, optimised.samples[k].pitch_rad, kAngleTolRad);
  }
  EXPECT_GT(after, 0);
}

TEST(CameraConnect, TurnsTheShortWayRound) {
  // A head: the camera over the base, only the angles connect (position not known).
  CameraPathParams p;
  p.candidates.workspace.height_min_m = p.candidates.workspace.height_max_m = 1.2f;
  p.candidates.workspace.reach_min_m = 0.01f;
  p.candidates.workspace.reach_max_m = 0.02f;
  const CameraScoreFn score = [](const Eigen::Vector3f&, const CameraBaseSample&) {
    return CameraViewScore{3.0f, 0.0f, 1.0f};  // the trajectory looks at yaw 3.0
  };
  CameraPathResult r = PlanCameraPath(StraightPath(31, 0.3f), p, {}, score);
  const CameraTrajectory optimised = r.trajectory;
  CameraPose from;
  from.yaw_rad = -2.9f;  // 0.383 rad the short way across ±π, 5.9 the long way
  CameraTrajectory t = optimised;
  const CameraConnection c = ConnectCameraTrajectory(from, ConnectFor(p), &t);
  ASSERT_TRUE(c.connected);
  EXPECT_NEAR(c.jump_rad, 2.0 * kPi - 5.9, 1e-5);
  // Positions untouched, yaw from −2.9 down through −π to 3.0, monotone, never further round.
  double turned = 0.0;
  for (std::size_t k = 0; k < t.samples.size(); ++k) {
    EXPECT_EQ(t.samples[k].position_W, optimised.samples[k].position_W);
    EXPECT_LE(std::abs(Wrap(t.samples[k].yaw_rad - 3.0)), c.jump_rad + kAngleTolRad);
    if (k == 0) continue;
    const double step = Wrap(double{t.samples[k].yaw_rad} - t.samples[k - 1].yaw_rad);
    EXPECT_LE(step, kAngleTolRad) << "step " << k;  // turning one way only (negative)
    turned += std::abs(step);
  }
  EXPECT_NEAR(turned, c.jump_rad, 1e-4);
  EXPECT_NEAR(Wrap(t.samples.back().yaw_rad - 3.0), 0.0, kAngleTolRad);
  EXPECT_EQ(Check(t, p.selection.limits).over_angular, 0);
}

TEST(CameraConnect, HoldsWhileTheBaseTurnsInPlace) {
  const CameraPathParams p;
  const CameraTrajectory optimised = Optimised(p).trajectory;
  CameraPose from;
  from.yaw_rad = 1.5f;
  from.pitch_rad = 0.0f;
  CameraConnectParams cp = ConnectFor(p);
  cp.hold_s = 1.5f;
  CameraTrajectory t = optimised;
  const CameraConnection c = ConnectCameraTrajectory(from, cp, &t);
  ASSERT_TRUE(c.connected);
  EXPECT_GE(c.duration_s, cp.hold_s + cp.min_s);
  for (const CameraPathSample& k : t.samples) {
    if (k.time_s > cp.hold_s) break;
    EXPECT_NEAR(Wrap(k.yaw_rad - 1.5), 0.0, kAngleTolRad) << "t " << k.time_s;
    EXPECT_EQ(k.position_W, optimised.samples[&k - t.samples.data()].position_W);  // not known
  }
  EXPECT_EQ(Check(t, p.selection.limits).over_angular, 0);
}

TEST(CameraConnect, ACameraAlreadyThereIsLeftAlone) {
  const CameraPathParams p;
  const CameraTrajectory optimised = Optimised(p).trajectory;
  CameraPose from;
  from.yaw_rad = optimised.samples.front().yaw_rad;
  from.pitch_rad = optimised.samples.front().pitch_rad;
  from.position_W = optimised.samples.front().position_W;
  CameraTrajectory t = optimised;
  const CameraConnection c = ConnectCameraTrajectory(from, ConnectFor(p), &t);
  EXPECT_FALSE(c.connected);
  EXPECT_EQ(c.jump_rad, 0.0f);
  EXPECT_EQ(c.max_radps_before, c.max_radps_after);
  for (std::size_t k = 0; k < t.samples.size(); ++k) {
    EXPECT_EQ(t.samples[k].position_W, optimised.samples[k].position_W);
    EXPECT_EQ(t.samples[k].yaw_rad, optimised.samples[k].yaw_rad);
  }
}

TEST(CameraConnect, AShortTrajectoryStaysWithinTheLimits) {
  // A turn round at a wedge: π to make up on a 0.6 m (2 s) trajectory. The connection cannot
  // finish there (the next plan call goes on from where the camera got to) but starts at the
  // camera and keeps to the limits.
  const CameraPathParams p;
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    return CameraViewScore{b.heading_rad, 0.0f, q.z()};
  };
  CameraTrajectory t = PlanCameraPath(StraightPath(3, 0.3f), p, {}, score).trajectory;
  CameraPose from;
  from.yaw_rad = float(kPi) - 0.01f;
  CameraConnectParams cp = ConnectFor(p);
  const CameraConnection c = ConnectCameraTrajectory(from, cp, &t);
  ASSERT_TRUE(c.connected);
  EXPECT_GT(c.duration_s, t.samples.back().time_s);
  EXPECT_NEAR(Wrap(t.samples.front().yaw_rad - from.yaw_rad), 0.0, kAngleTolRad);
  const Steps s = Check(t, p.selection.limits);
  EXPECT_EQ(s.over_angular, 0);
  EXPECT_EQ(s.over_linear, 0);
  // It has turned some of the way, no faster than the blend's share of a_m allows on its own.
  EXPECT_GT(std::abs(Wrap(t.samples.back().yaw_rad - from.yaw_rad)), 0.1);
  EXPECT_LE(s.max_radps, p.selection.limits.angular_radps * (1.0f + kSpeedTol));
}

// The "selection" variant [ours]: eq. 8 itself starts from the camera, so the optimised views
// turn from where it looks within the limits, and the trajectory needs no connecting stretch.
TEST(CameraConnect, TheSelectionCanStartFromTheCamera) {
  const std::vector<CameraBaseSample> path = StraightPath(12, 0.3f);
  CameraPathParams p;
  p.candidates.workspace.height_min_m = p.candidates.workspace.height_max_m = 1.2f;
  p.candidates.workspace.reach_min_m = 0.01f;
  p.candidates.workspace.reach_max_m = 0.02f;
  // Each candidate looks along its bearing from the base (spread over ±90°, as the planner's do);
  // the gain is best straight ahead.
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    const Eigen::Vector2f d = q.head<2>() - b.xy_m;
    const float yaw = std::atan2(d.y(), d.x());
    return CameraViewScore{yaw, 0.0f, 0.5f + 0.5f * std::cos(yaw - b.heading_rad)};
  };
  p.start_from_camera = true;
  p.start_yaw_rad = 1.4f;  // looking left
  const CameraPathResult r = PlanCameraPath(path, p, {}, score);
  ASSERT_EQ(r.candidates[0].size(), 1u);
  EXPECT_NEAR(r.candidates[0][0].yaw_rad, 1.4f, kAngleTolRad);
  ASSERT_TRUE(r.selection.feasible);
  // The views turn from the camera towards the gain, no faster than a_m between samples (1 s).
  float prev = 1.4f;
  for (std::size_t s = 1; s < path.size(); ++s) {
    const float yaw = r.candidates[s][r.selection.selected[s]].yaw_rad;
    EXPECT_LE(std::abs(Wrap(yaw - prev)), p.selection.limits.angular_radps + kAngleTolRad);
    prev = yaw;
  }
  EXPECT_LT(std::abs(Wrap(prev)), 1.0);  // and it did turn towards the front
  EXPECT_NEAR(Wrap(r.trajectory.samples.front().yaw_rad - 1.4), 0.0, kAngleTolRad);
  EXPECT_EQ(Check(r.trajectory, p.selection.limits).over_angular, 0);
  // Nothing left for the connection to do.
  CameraPose from;
  from.yaw_rad = 1.4f;
  CameraTrajectory t = r.trajectory;
  EXPECT_FALSE(ConnectCameraTrajectory(from, ConnectFor(p), &t).connected);
}

}  // namespace
}  // namespace voxplan::tensorfield
