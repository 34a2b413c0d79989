// X12's look-at into unknown space (plugins/tensorfield/algorithms/camera_path.h, X L308-310):
// where the path meets unknown space, the samples within 2 m of it get a look-at view and eq. 8's
// look-at term. Analytic cases: where the targets are found along a path, which samples get one
// (ahead and within 2 m), the views the term pulls round and those it leaves, the speed limits
// winning over it, and the DP against brute force with the new term.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "plugins/tensorfield/algorithms/camera_path.h"
#include "tests/plugins/tensorfield/camera_test_paths.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kAngleTolRad = 1e-5f;
constexpr double kEnergyTol = 1e-9;
constexpr float kTouchM = 0.25f;  // the robot's radius plus the clearance margin (the planner's)

using test::StraightPath;
using test::Wrap;

// A head: the camera over the base centre (a 1-2 cm ring at 1.2 m), turning on its joint.
CameraPathParams HeadParams() {
  CameraPathParams p;
  p.candidates.workspace.height_min_m = p.candidates.workspace.height_max_m = 1.2f;
  p.candidates.workspace.reach_min_m = 0.01f;
  p.candidates.workspace.reach_max_m = 0.02f;
  p.output_step_m = 0.1f;
  return p;
}

// Every candidate's best view looks along yaw_offset from the heading with gain 1 (the planner's
// gain: nothing better to see elsewhere).
CameraScoreFn LookAlong(float yaw_offset) {
  return [yaw_offset](const Eigen::Vector3f&, const CameraBaseSample& b) {
    return CameraViewScore{b.heading_rad + yaw_offset, 0.0f, 1.0f};
  };
}

CameraLookAt LookAtPoint(const Eigen::Vector2f& xy, float arc_m, float half_fov_rad,
                         float view_gain) {
  CameraLookAt la;
  la.targets.push_back({Eigen::Vector3f(xy.x(), xy.y(), 1.2f), arc_m});
  la.params.half_fov_rad = half_fov_rad;
  la.gain = [view_gain](const Eigen::Vector3f&, float, float, const CameraBaseSample&) {
    return view_gain;
  };
  return la;
}

float BearingFrom(const CameraCandidate& c, const Eigen::Vector2f& target) {
  const Eigen::Vector2f d = target - c.position_W.head<2>();
  return std::atan2(d.y(), d.x());
}

TEST(CameraLookAt, TargetsWhereTheBodyMeetsUnknownSpace) {
  const std::vector<Eigen::Vector2f> line = {{0.0f, 0.0f}, {2.0f, 0.0f}, {2.9f, 0.0f}};
  // Unknown space beside the path for x in [1, 2], 0.2 m off it (an unscanned alcove): the body
  // meets it all along, its nearest point moving with the robot.
  const NearestUnknownFn alcove = [](const Eigen::Vector2f& p,
                                     float within) -> std::optional<Eigen::Vector2f> {
    const Eigen::Vector2f u(std::clamp(p.x(), 1.0f, 2.0f), 0.2f);
    if ((u - p).norm() > within) return std::nullopt;
    return u;
  };
  const std::vector<CameraLookAtTarget> t = FindLookAtTargets(line, kTouchM, 0.025f, 1.2f, alcove);
  ASSERT_FALSE(t.empty());
  // From where the body first reaches it (0.15 m before x = 1) to as far after x = 2, in order.
  EXPECT_NEAR(t.front().arc_length_m, 1.0f - 0.15f, 0.025f + 1e-4f);
  EXPECT_NEAR(t.back().arc_length_m, 2.0f, 1e-4f);  // the same point after x = 2: not repeated
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_NEAR(t[k].point_W.y(), 0.2f, 1e-6f);
    EXPECT_NEAR(t[k].point_W.z(), 1.2f, 1e-6f);
    if (k > 0) {
      EXPECT_GT(t[k].arc_length_m, t[k - 1].arc_length_m);
      EXPECT_NE(t[k].point_W, t[k - 1].point_W);
    }
  }
  // A door into unknown space beyond x = 3: the one nearest point (3, 0) from where the body
  // reaches it (x = 3 - 0.25) on, once.
  const NearestUnknownFn door = [](const Eigen::Vector2f& p,
                                   float within) -> std::optional<Eigen::Vector2f> {
    if (3.0f - p.x() > within) return std::nullopt;
    return Eigen::Vector2f(3.0f, 0.0f);
  };
  const std::vector<CameraLookAtTarget> d = FindLookAtTargets(line, kTouchM, 0.025f, 1.2f, door);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NEAR(d[0].arc_length_m, 3.0f - kTouchM, 0.025f + 1e-4f);
  // The same unknown space 0.3 m beside the path: the body never meets it, so no target.
  const NearestUnknownFn beside = [](const Eigen::Vector2f& p,
                                     float within) -> std::optional<Eigen::Vector2f> {
    if (0.3f > within) return std::nullopt;
    return Eigen::Vector2f(p.x(), 0.3f);
  };
  EXPECT_TRUE(FindLookAtTargets(line, kTouchM, 0.025f, 1.2f, beside).empty());
}

TEST(CameraLookAt, SamplesWithinTwoMetresAheadGetTheTarget) {
  const std::vector<CameraBaseSample> path = StraightPath(11, 0.3f);  // x = 0 .. 3
  const std::vector<CameraLookAtTarget> targets = {{Eigen::Vector3f(3.5f, 0.0f, 1.2f), 3.25f}};
  const std::vector<int> k = AssignLookAtTargets(path, targets, 2.0f);
  ASSERT_EQ(k.size(), path.size());
  for (std::size_t s = 0; s < path.size(); ++s) {
    const bool near = 3.5f - path[s].xy_m.x() < 2.0f;  // x > 1.5
    EXPECT_EQ(k[s], near ? 0 : -1) << "sample " << s;
  }
  // A target behind a sample (the path has passed it) is not looked back at.
  const std::vector<CameraLookAtTarget> behind = {{Eigen::Vector3f(0.3f, 0.3f, 1.2f), 0.3f}};
  const std::vector<int> b = AssignLookAtTargets(path, behind, 2.0f);
  EXPECT_EQ(b[0], 0);
  EXPECT_EQ(b[1], 0);
  for (std::size_t s = 2; s < path.size(); ++s) EXPECT_EQ(b[s], -1) << "sample " << s;
  // The first target ahead that is near: a nearer one further along wins over a far one first.
  const std::vector<CameraLookAtTarget> two = {{Eigen::Vector3f(0.0f, 5.0f, 1.2f), 0.1f},
                                               {Eigen::Vector3f(1.0f, 1.0f, 1.2f), 1.0f}};
  EXPECT_EQ(AssignLookAtTargets(path, two, 2.0f)[0], 1);
}

TEST(CameraLookAt, ScoreIsWhetherTheViewSeesTheTarget) {
  const Eigen::Vector3f cam(0.0f, 0.0f, 1.2f);
  const Eigen::Vector3f left(0.0f, 1.0f, 0.0f);  // height does not matter: the views are level
  EXPECT_EQ(LookAtScore(cam, 0.5f * float(kPi), left, 0.1f), 1.0f);
  EXPECT_EQ(LookAtScore(cam, 0.5f * float(kPi) - 0.09f, left, 0.1f), 1.0f);
  EXPECT_EQ(LookAtScore(cam, 0.5f * float(kPi) - 0.11f, left, 0.1f), 0.0f);
  EXPECT_EQ(LookAtScore(cam, 0.0f, left, 0.1f), 0.0f);
  // Across the ±π seam.
  const Eigen::Vector3f back(-1.0f, -0.01f, 1.2f);
  EXPECT_EQ(LookAtScore(cam, float(kPi) - 0.01f, back, 0.1f), 1.0f);
}

// Unknown space within 2 m of every sample, to the left of the path; the gain looks right. The
// look-at pulls every view round to see it, through views of less gain.
TEST(CameraLookAt, UnknownSpaceWithinTwoMetresAttractsTheViews) {
  const std::vector<CameraBaseSample> path = StraightPath(6, 0.3f);  // x = 0 .. 1.5
  const Eigen::Vector2f target(0.75f, 1.2f);                         // 1.42 m from the ends
  const CameraPathParams p = HeadParams();
  const CameraScoreFn score = LookAlong(-0.6f);
  const CameraLookAt la = LookAtPoint(target, 1.5f, 0.25f, 0.2f);  // met at the path's end
  const CameraPathResult without = PlanCameraPath(path, p, {}, score);
  const CameraPathResult with = PlanCameraPath(path, p, {}, score, la);
  ASSERT_TRUE(with.selection.feasible);
  // Without the term every view looks along its best gain, away from the unknown space.
  for (std::size_t s = 0; s < path.size(); ++s) {
    const CameraCandidate& c = without.candidates[s][without.selection.selected[s]];
    EXPECT_NEAR(Wrap(c.yaw_rad + 0.6), 0.0, kAngleTolRad);
    EXPECT_EQ(LookAtScore(c.position_W, c.yaw_rad, la.targets[0].point_W, 0.25f), 0.0f);
  }
  // With it every sample has the target (ahead, within 2 m), and every selected view sees it.
  for (std::size_t s = 0; s < path.size(); ++s) {
    EXPECT_EQ(with.lookat_target[s], 0) << "sample " << s;
    ASSERT_EQ(with.candidates[s].size(), without.candidates[s].size() + 1);
    const CameraCandidate& c = with.candidates[s][with.selection.selected[s]];
    EXPECT_EQ(c.lookat, 1.0f) << "sample " << s;
    EXPECT_TRUE(c.lookat_view);
    EXPECT_NEAR(Wrap(c.yaw_rad - BearingFrom(c, target)), 0.0, kAngleTolRad);
    EXPECT_EQ(c.pitch_rad, 0.0f);
    EXPECT_FLOAT_EQ(c.gain, 0.2f);
  }
  EXPECT_EQ(with.lookat_samples, 6);
  EXPECT_EQ(with.lookat_seen, 6);
  EXPECT_EQ(with.lookat_changed, 6);
  EXPECT_NEAR(with.selection.energy.lookat, -6.0, kEnergyTol);
  // The views' gain is lower: the term bought the look.
  EXPECT_GT(with.selection.energy.gain, without.selection.energy.gain);
  EXPECT_EQ(without.selection.energy.lookat, 0.0);
}

// A target 2.5 m from every sample: beyond the 2 m bound nothing changes, bit for bit.
TEST(CameraLookAt, UnknownSpaceBeyondTwoMetresDoesNot) {
  const std::vector<CameraBaseSample> path = StraightPath(6, 0.3f);
  const CameraPathParams p = HeadParams();
  const CameraScoreFn score = LookAlong(-0.6f);
  const CameraLookAt far = LookAtPoint({0.75f, 2.6f}, 1.5f, 0.25f, 0.2f);  // ≥ 2.6 m away
  const CameraPathResult without = PlanCameraPath(path, p, {}, score);
  const CameraPathResult with = PlanCameraPath(path, p, {}, score, far);
  EXPECT_EQ(with.lookat_samples, 0);
  for (std::size_t s = 0; s < path.size(); ++s) {
    EXPECT_EQ(with.lookat_target[s], -1);
    EXPECT_EQ(with.candidates[s].size(), without.candidates[s].size());
  }
  EXPECT_EQ(with.selection.selected, without.selection.selected);
  EXPECT_EQ(with.selection.energy.total, without.selection.energy.total);
  ASSERT_EQ(with.trajectory.samples.size(), without.trajectory.samples.size());
  for (std::size_t k = 0; k < with.trajectory.samples.size(); ++k)
    EXPECT_EQ(with.trajectory.samples[k].yaw_rad, without.trajectory.samples[k].yaw_rad);
  // The bound is the parameter: at 3 m the same target attracts.
  CameraLookAt wide = far;
  wide.params.range_m = 3.0f;
  EXPECT_GT(PlanCameraPath(path, p, {}, score, wide).lookat_samples, 0);
}

// Along a longer path only the samples within 2 m of the target turn to it; the ones before go
// on looking along their gain.
TEST(CameraLookAt, OnlyTheSamplesWithinTwoMetresTurn) {
  const std::vector<CameraBaseSample> path = StraightPath(9, 0.3f);  // x = 0 .. 2.4
  const Eigen::Vector2f target(3.3f, 0.8f);
  const CameraPathParams p = HeadParams();
  const CameraScoreFn score = LookAlong(0.0f);
  const CameraLookAt la = LookAtPoint(target, 3.0f, 0.2f, 0.8f);  // 0.24 rad off at x = 0
  const CameraPathResult r = PlanCameraPath(path, p, {}, score, la);
  ASSERT_TRUE(r.selection.feasible);
  int near = 0;
  for (std::size_t s = 0; s < path.size(); ++s) {
    const bool within = (target - path[s].xy_m).norm() < 2.0f;  // x = 1.5 .. 2.4
    near += within ? 1 : 0;
    const CameraCandidate& c = r.candidates[s][r.selection.selected[s]];
    const float seen = LookAtScore(c.position_W, c.yaw_rad, la.targets[0].point_W, 0.2f);
    EXPECT_EQ(seen, within ? 1.0f : 0.0f) << "sample " << s;
    if (!within) {
      EXPECT_NEAR(Wrap(c.yaw_rad), 0.0, kAngleTolRad) << "sample " << s;
    }
  }
  EXPECT_EQ(near, 4);
  EXPECT_EQ(r.lookat_samples, 4);
  EXPECT_EQ(r.lookat_seen, 4);
  // With ω_U = 0 the added views (less gain than the rest) are never taken.
  CameraPathParams off = p;
  off.selection.weight_lookat = 0.0;
  const CameraPathResult r0 = PlanCameraPath(path, off, {}, score, la);
  EXPECT_EQ(r0.lookat_seen, 0);
  EXPECT_EQ(r0.lookat_changed, 0);
}

// The look-at is a term, not a constraint: a target whose view lies further round than the
// camera can turn between two samples is not looked at (the speed limits are hard).
TEST(CameraLookAt, TheSpeedLimitsWinOverTheTerm) {
  const std::vector<CameraBaseSample> path = StraightPath(6, 0.3f);  // x = 0 .. 1.5
  const Eigen::Vector2f target(3.2f, 0.9f);  // within 2 m of the last sample only
  const CameraPathParams p = HeadParams();
  const CameraScoreFn score = LookAlong(-0.6f);  // 1.09 rad from the target's bearing there
  const CameraPathResult r =
      PlanCameraPath(path, p, {}, score, LookAtPoint(target, 3.0f, 0.25f, 0.2f));
  EXPECT_TRUE(r.selection.feasible);
  EXPECT_EQ(r.lookat_samples, 1);
  EXPECT_EQ(r.lookat_seen, 0);
  EXPECT_EQ(r.selection.linear_violations + r.selection.angular_violations, 0);
}

// Eq. 8 with the look-at term, written out independently: the DP's selection over candidates
// with the added views is the best of all C^S selections.
double Objective(const std::vector<double>& times,
                 const std::vector<std::vector<CameraCandidate>>& cand, const std::vector<int>& x,
                 const CameraSelectionParams& p) {
  const int n = static_cast<int>(x.size());
  double v_best = 0.0;
  for (const auto& cs : cand)
    for (const CameraCandidate& k : cs) v_best = std::max(v_best, std::abs(double{k.gain}));
  const double dt_mean = n >= 2 ? (times.back() - times.front()) / (n - 1) : 1.0;
  const double l_ref = p.limits.linear_mps * dt_mean, a_ref = p.limits.angular_radps * dt_mean;
  auto at = [&](int s) -> const CameraCandidate& { return cand[s][x[s]]; };
  auto over = [&](int a, int b) {
    const double dt = times[b] - times[a];
    const double v = (at(b).position_W - at(a).position_W).cast<double>().norm() / dt;
    const double w = std::hypot(Wrap(double{at(b).yaw_rad} - at(a).yaw_rad),
                                double{at(b).pitch_rad} - at(a).pitch_rad) /
                     dt;
    return v > p.limits.linear_mps || w > p.limits.angular_radps;
  };
  double e = 0.0;
  for (int s = 0; s < n; ++s)
    e -= p.weight_gain * at(s).gain / v_best + p.weight_lookat * at(s).lookat;
  for (int s = 1; s + 1 < n; ++s) {
    const Eigen::Vector3d d2 =
        (at(s - 1).position_W - 2.0f * at(s).position_W + at(s + 1).position_W).cast<double>();
    const double d2y = Wrap(double{at(s + 1).yaw_rad} - at(s).yaw_rad) -
                       Wrap(double{at(s).yaw_rad} - at(s - 1).yaw_rad);
    const double d2p = double{at(s - 1).pitch_rad} - 2.0 * at(s).pitch_rad + at(s + 1).pitch_rad;
    e += p.weight_linear * d2.squaredNorm() / (l_ref * l_ref);
    e += p.weight_angular * (d2y * d2y + d2p * d2p) / (a_ref * a_ref);
    if (over(s - 1, s + 1)) return std::numeric_limits<double>::infinity();
  }
  for (int s = 0; s + 1 < n && p.limit_adjacent_steps; ++s)
    if (over(s, s + 1)) return std::numeric_limits<double>::infinity();
  return e;
}

TEST(CameraLookAt, DynamicProgrammeEqualsBruteForceWithTheTerm) {
  int changed_cases = 0;
  for (int trial = 0; trial < 24; ++trial) {
    // 4-5 samples, 3 candidates each (4 with the added view): at most 4^5 selections.
    const int samples = 4 + trial % 2;
    std::vector<CameraBaseSample> path = StraightPath(samples, 0.3f);
    CameraPathParams p = HeadParams();
    p.candidates.candidates_per_sample = 3;
    p.candidates.workspace = CameraWorkspace{};  // an arm: positions matter too
    p.selection.weight_lookat = 0.25 * (trial % 5);
    // Every third trial starts from a camera pose (one candidate at the first sample).
    p.start_from_camera = trial % 3 == 2;
    p.start_yaw_rad = 0.2f;
    p.start_position_W = Eigen::Vector3f(0.5f, 0.1f, 0.9f);
    // A rough gain over positions, best views spread around the heading.
    const CameraScoreFn score = [trial](const Eigen::Vector3f& q, const CameraBaseSample& b) {
      const float h =
          std::sin(12.9898f * q.x() + 78.233f * q.y() + 37.719f * q.z() + trial) * 43758.5453f;
      const float g = h - std::floor(h);
      // Yaws within 0.6 rad of each other: a camera can always turn between any two in a step.
      return CameraViewScore{b.heading_rad + 0.6f * (g - 0.5f), 0.0f, g};
    };
    const Eigen::Vector2f target(0.2f * static_cast<float>(trial % 7), 1.0f - 0.3f * (trial % 3));
    const CameraLookAt la = LookAtPoint(target, 10.0f, 0.4f, 0.3f + 0.02f * trial);
    const CameraPathResult r = PlanCameraPath(path, p, {}, score, la);
    const std::vector<double> times = CameraSampleTimes(path, p.selection.base_speed_mps);
    // Brute force over every selection of the candidates with their added views.
    std::vector<int> x(samples, 0);
    double best = std::numeric_limits<double>::infinity();
    while (true) {
      best = std::min(best, Objective(times, r.candidates, x, p.selection));
      int s = 0;
      while (s < samples && ++x[s] == static_cast<int>(r.candidates[s].size())) x[s++] = 0;
      if (s == samples) break;
    }
    ASSERT_TRUE(std::isfinite(best)) << "trial " << trial;
    ASSERT_TRUE(r.selection.feasible);
    EXPECT_NEAR(r.selection.energy.total, best, kEnergyTol) << "trial " << trial;
    EXPECT_NEAR(Objective(times, r.candidates, r.selection.selected, p.selection),
                r.selection.energy.total, kEnergyTol);
    double u = 0.0;
    for (int s = 0; s < samples; ++s) u += r.candidates[s][r.selection.selected[s]].lookat;
    EXPECT_NEAR(r.selection.energy.lookat, -p.selection.weight_lookat * u, kEnergyTol);
    changed_cases += r.lookat_changed > 0 ? 1 : 0;
  }
  EXPECT_GT(changed_cases, 0);  // the term moves some optima
}

}  // namespace
}  // namespace voxplan::tensorfield
