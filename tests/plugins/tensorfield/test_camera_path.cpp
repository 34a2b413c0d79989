// The arm camera trajectory (plugins/tensorfield/algorithms/camera_path.h): the DP against brute
// force over every selection, the weights' effects, the workspace, the speed limits and the
// interpolation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "plugins/tensorfield/algorithms/camera_path.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kEnergyTol = 1e-9;      // DP against brute force (same objective, double)
constexpr float kWorkspaceTolM = 1e-4f;  // Ψ membership after float clamping
constexpr float kSpeedTol = 1e-3f;       // relative, on the dense path's step speeds
constexpr float kKnotTolM = 1e-5f;       // the spline at a knot against the selected position
constexpr float kAngleTolRad = 1e-5f;
constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

double Wrap(double a) { return std::remainder(a, 2.0 * kPi); }

// Base samples every spacing_m along a straight line (heading 0) or a circular arc of the given
// curvature (1/m, positive turning left).
std::vector<CameraBaseSample> BasePath(int samples, float spacing_m, float curvature = 0.0f) {
  std::vector<CameraBaseSample> path;
  Eigen::Vector2f p(0.0f, 0.0f);
  float heading = 0.0f;
  for (int s = 0; s < samples; ++s) {
    path.push_back({p, heading, spacing_m * static_cast<float>(s)});
    // Exact arc step: chord at the mean heading.
    const float turn = curvature * spacing_m;
    const float chord = curvature != 0.0f ? 2.0f * std::sin(0.5f * turn) / curvature : spacing_m;
    p += chord * Eigen::Vector2f(std::cos(heading + 0.5f * turn), std::sin(heading + 0.5f * turn));
    heading = static_cast<float>(Wrap(heading + turn));
  }
  return path;
}

// Random candidates around a straight base path, with yaws spread across the ±π seam.
struct RandomCase {
  std::vector<double> times;
  std::vector<std::vector<CameraCandidate>> candidates;
};

RandomCase MakeRandomCase(std::mt19937& rng, int samples, int per_sample) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  RandomCase c;
  double t = 0.0;
  for (int s = 0; s < samples; ++s) {
    c.times.push_back(t);
    t += 0.8 + 0.4 * u01(rng);  // non-uniform sampling
    std::vector<CameraCandidate>& cs = c.candidates.emplace_back();
    for (int i = 0; i < per_sample; ++i) {
      CameraCandidate k;
      k.position_W = Eigen::Vector3f(0.3f * static_cast<float>(s) + 0.9f * (u01(rng) - 0.5f),
                                     0.9f * (u01(rng) - 0.5f), 0.4f + u01(rng));
      k.yaw_rad = static_cast<float>(Wrap(kPi - 0.2 + 0.9 * (u01(rng) - 0.5)));
      k.pitch_rad = 0.4f * (u01(rng) - 0.5f);
      k.gain = u01(rng);
      cs.push_back(k);
    }
  }
  return c;
}

// Eq. 8 as camera_path.h documents it, written out independently of the library: the objective
// of one selection with the speed constraints hard (∞ when broken) or penalised.
double Objective(const RandomCase& c, const std::vector<int>& x, const CameraSelectionParams& p,
                 bool hard, bool constrained = true) {
  const int n = static_cast<int>(x.size());
  double v_best = 0.0;
  for (const auto& cs : c.candidates)
    for (const CameraCandidate& k : cs) v_best = std::max(v_best, std::abs(double{k.gain}));
  const double dt_mean = n >= 2 ? (c.times.back() - c.times.front()) / (n - 1) : 1.0;
  const double l_ref = p.limits.linear_mps * dt_mean, a_ref = p.limits.angular_radps * dt_mean;
  auto at = [&](int s) -> const CameraCandidate& { return c.candidates[s][x[s]]; };
  double e = 0.0;
  for (int s = 0; s < n; ++s) e -= p.weight_gain * at(s).gain / v_best;
  auto constraint = [&](int a, int b) {
    const double dt = c.times[b] - c.times[a];
    const double v =
        (at(b).position_W.cast<double>() - at(a).position_W.cast<double>()).norm() / dt;
    const double dy = Wrap(double{at(b).yaw_rad} - at(a).yaw_rad);
    const double dp = double{at(b).pitch_rad} - at(a).pitch_rad;
    const double w = std::sqrt(dy * dy + dp * dp) / dt;
    double cost = 0.0;
    if (v > p.limits.linear_mps)
      cost += hard ? kInf : p.violation_penalty * (v / p.limits.linear_mps - 1.0);
    if (w > p.limits.angular_radps)
      cost += hard ? kInf : p.violation_penalty * (w / p.limits.angular_radps - 1.0);
    return cost;
  };
  for (int s = 1; s + 1 < n; ++s) {
    const Eigen::Vector3d d2 = at(s - 1).position_W.cast<double>() -
                               2.0 * at(s).position_W.cast<double>() +
                               at(s + 1).position_W.cast<double>();
    const double d2y = Wrap(double{at(s + 1).yaw_rad} - at(s).yaw_rad) -
                       Wrap(double{at(s).yaw_rad} - at(s - 1).yaw_rad);
    const double d2p = double{at(s - 1).pitch_rad} - 2.0 * at(s).pitch_rad + at(s + 1).pitch_rad;
    e += p.weight_linear * d2.squaredNorm() / (l_ref * l_ref);
    e += p.weight_angular * (d2y * d2y + d2p * d2p) / (a_ref * a_ref);
    if (constrained) e += constraint(s - 1, s + 1);
  }
  if (constrained && p.limit_adjacent_steps)
    for (int s = 0; s + 1 < n; ++s) e += constraint(s, s + 1);
  return e;
}

// The best objective over all C^S selections.
double BruteForce(const RandomCase& c, const CameraSelectionParams& p, bool hard,
                  bool constrained = true) {
  const int n = static_cast<int>(c.candidates.size());
  std::vector<int> x(n, 0);
  double best = kInf;
  while (true) {
    best = std::min(best, Objective(c, x, p, hard, constrained));
    int s = 0;
    while (s < n && ++x[s] == static_cast<int>(c.candidates[s].size())) x[s++] = 0;
    if (s == n) break;
  }
  return best;
}

TEST(CameraPath, DynamicProgrammeEqualsBruteForce) {
  std::mt19937 rng(20170705);
  int constrained_cases = 0, infeasible_cases = 0, cases = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int samples = 1 + trial % 6;
    const int per_sample = 1 + (trial / 6) % 4;
    const RandomCase c = MakeRandomCase(rng, samples, per_sample);
    CameraSelectionParams p;
    p.limit_adjacent_steps = trial % 2 == 0;
    const CameraSelection dp = SelectCameraViews(c.times, c.candidates, p);
    ASSERT_EQ(dp.selected.size(), c.candidates.size());
    for (int s = 0; s < samples; ++s) {
      ASSERT_GE(dp.selected[s], 0);
      ASSERT_LT(dp.selected[s], per_sample);
    }
    // The reported terms are the selection's own objective.
    const double mine = Objective(c, dp.selected, p, false);
    EXPECT_NEAR(dp.energy.total + dp.energy.penalty, mine, kEnergyTol) << "trial " << trial;
    const double hard = BruteForce(c, p, true);
    ++cases;
    if (hard < kInf) {
      EXPECT_TRUE(dp.feasible) << "trial " << trial;
      EXPECT_EQ(dp.energy.penalty, 0.0);
      EXPECT_NEAR(dp.energy.total, hard, kEnergyTol) << "trial " << trial;
      if (BruteForce(c, p, true, false) < hard - kEnergyTol) ++constrained_cases;
    } else {
      ++infeasible_cases;
      EXPECT_FALSE(dp.feasible) << "trial " << trial;
      EXPECT_GT(dp.linear_violations + dp.angular_violations, 0);
      EXPECT_NEAR(dp.energy.total + dp.energy.penalty, BruteForce(c, p, false), kEnergyTol)
          << "trial " << trial;
    }
  }
  // The cases must exercise the constraints: some optima move because of them, some are
  // infeasible, most are not.
  EXPECT_GT(constrained_cases, 0);
  EXPECT_GT(infeasible_cases, 0);
  EXPECT_GT(cases - infeasible_cases, cases / 2);
}

TEST(CameraPath, ZeroSmoothnessPicksTheBestGainPerSample) {
  std::mt19937 rng(7);
  const RandomCase c = MakeRandomCase(rng, 12, 10);
  CameraSelectionParams p;
  p.weight_linear = 0.0;
  p.weight_angular = 0.0;
  p.limits.linear_mps = 1e6f;  // no constraint binds
  p.limits.angular_radps = 1e6f;
  const CameraSelection sel = SelectCameraViews(c.times, c.candidates, p);
  ASSERT_TRUE(sel.feasible);
  for (std::size_t s = 0; s < c.candidates.size(); ++s) {
    const auto& cs = c.candidates[s];
    const int best = static_cast<int>(
        std::max_element(cs.begin(), cs.end(),
                         [](const auto& a, const auto& b) { return a.gain < b.gain; }) -
        cs.begin());
    EXPECT_EQ(sel.selected[s], best) << "sample " << s;
  }
}

// A deterministic rough gain field over camera positions, with the best view straight ahead.
CameraViewScore RoughGain(const Eigen::Vector3f& q, const CameraBaseSample& base) {
  const float h = std::sin(12.9898f * q.x() + 78.233f * q.y() + 37.719f * q.z()) * 43758.5453f;
  return {base.heading_rad, 0.0f, h - std::floor(h)};
}

double SecondDifferences(const CameraPathResult& r) {
  double sum = 0.0;
  const auto& sel = r.selection.selected;
  for (std::size_t s = 1; s + 1 < sel.size(); ++s) {
    const Eigen::Vector3f d = r.candidates[s - 1][sel[s - 1]].position_W -
                              2.0f * r.candidates[s][sel[s]].position_W +
                              r.candidates[s + 1][sel[s + 1]].position_W;
    sum += d.squaredNorm();
  }
  return sum;
}

TEST(CameraPath, LargeLinearWeightSmoothsPositions) {
  const std::vector<CameraBaseSample> path = BasePath(20, 0.3f);
  CameraPathParams loose;
  loose.selection.weight_linear = 0.0;
  CameraPathParams stiff;
  stiff.selection.weight_linear = 1e4;
  const CameraPathResult a = PlanCameraPath(path, loose, {}, RoughGain);
  const CameraPathResult b = PlanCameraPath(path, stiff, {}, RoughGain);
  ASSERT_TRUE(a.selection.feasible);
  ASSERT_TRUE(b.selection.feasible);
  EXPECT_GT(SecondDifferences(a), 0.05);  // the rough gain makes ω_L = 0 jump about
  EXPECT_LT(SecondDifferences(b), 0.1 * SecondDifferences(a));
  // ω_L = 0 earns at least as much gain: it optimises the gain alone under the same limits.
  EXPECT_LE(a.selection.energy.gain, b.selection.energy.gain + kEnergyTol);
  // "no_linear" is ω_L = 0.
  CameraPathParams no_linear;
  no_linear.mode = CameraMode::kNoLinear;
  EXPECT_EQ(PlanCameraPath(path, no_linear, {}, RoughGain).selection.selected,
            a.selection.selected);
}

TEST(CameraPath, CandidatesAndTrajectoryStayInTheWorkspace) {
  // A left turn (radius 1 m), a rough gain that favours long reach and no smoothing: the selected
  // views jump about, the spline overshoots Ψ between them, and the clamp has work to do.
  const std::vector<CameraBaseSample> path = BasePath(16, 0.3f, 1.0f);
  CameraPathParams p;
  p.selection.weight_linear = 0.0;
  p.selection.weight_angular = 0.0;
  p.selection.limits.linear_mps = 5.0f;  // the speed clamp must not do Ψ's work
  p.selection.limits.angular_radps = 50.0f;
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    CameraViewScore v = RoughGain(q, b);
    v.gain += CameraOffsetInBase(q, b, 0.0f).norm();
    return v;
  };
  // Free space: nothing above 1.2 m on the left of the base.
  const CameraFreeFn free = [&](const Eigen::Vector3f& q) { return q.z() < 1.2f || q.y() < 0.0f; };
  int rejected = 0;
  const CameraFreeFn counting = [&](const Eigen::Vector3f& q) {
    const bool ok = free(q);
    rejected += ok ? 0 : 1;
    return ok;
  };
  const CameraPathResult r = PlanCameraPath(path, p, counting, score);
  EXPECT_GT(rejected, 0);
  ASSERT_EQ(r.candidates.size(), path.size());
  for (std::size_t s = 0; s < path.size(); ++s) {
    EXPECT_EQ(static_cast<int>(r.candidates[s].size()), p.candidates.candidates_per_sample);
    for (const CameraCandidate& c : r.candidates[s]) {
      EXPECT_TRUE(
          InCameraWorkspace(c.position_W, path[s], p.candidates.workspace, 0.0f, kWorkspaceTolM));
      EXPECT_TRUE(free(c.position_W));
    }
    ASSERT_GE(r.selection.selected[s], 0);
    EXPECT_TRUE(free(r.candidates[s][r.selection.selected[s]].position_W));
  }
  ASSERT_FALSE(r.trajectory.samples.empty());
  EXPECT_NEAR(r.trajectory.samples.front().arc_length_m, path.front().arc_length_m, 1e-6f);
  EXPECT_NEAR(r.trajectory.samples.back().arc_length_m, path.back().arc_length_m, 1e-6f);
  EXPECT_GT(r.trajectory.workspace_clamps, 0);
  EXPECT_EQ(r.trajectory.linear_speed_clamps, 0);
  for (const CameraPathSample& c : r.trajectory.samples)
    EXPECT_TRUE(
        InCameraWorkspace(c.position_W, c.base, p.candidates.workspace, 0.0f, kWorkspaceTolM))
        << "arc " << c.arc_length_m;
  // The base pose of each dense sample is on the path (the circle of radius 1 about (0, 1)).
  for (const CameraPathSample& c : r.trajectory.samples)
    EXPECT_NEAR((c.base.xy_m - Eigen::Vector2f(0.0f, 1.0f)).norm(), 1.0f, 0.02f);
}

// Dense steps over the linear or angular limit.
int StepsOverLimit(const CameraTrajectory& t, const CameraSpeedLimits& l, bool angular) {
  int over = 0;
  for (std::size_t k = 1; k < t.samples.size(); ++k) {
    const CameraPathSample &a = t.samples[k - 1], &b = t.samples[k];
    const float dt = b.time_s - a.time_s;
    if (angular) {
      const float dy = static_cast<float>(Wrap(b.yaw_rad - a.yaw_rad));
      const float dp = b.pitch_rad - a.pitch_rad;
      over += std::hypot(dy, dp) > l.angular_radps * dt * (1.0f + kSpeedTol) + kAngleTolRad;
    } else {
      over += (b.position_W - a.position_W).norm() > l.linear_mps * dt * (1.0f + kSpeedTol) + 1e-5f;
    }
  }
  return over;
}

TEST(CameraPath, StraightPathKeepsTheLimitsWithoutClamps) {
  const std::vector<CameraBaseSample> path = BasePath(20, 0.3f);
  CameraPathParams p;
  // Look half left and slightly down; higher is better.
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    return CameraViewScore{b.heading_rad + 0.5f, -0.1f, q.z()};
  };
  const CameraPathResult r = PlanCameraPath(path, p, {}, score);
  ASSERT_TRUE(r.selection.feasible);
  const CameraTrajectory& t = r.trajectory;
  EXPECT_EQ(t.workspace_clamps, 0);
  EXPECT_EQ(t.linear_speed_clamps, 0);
  EXPECT_EQ(t.angular_speed_clamps, 0);
  EXPECT_EQ(t.speed_violations, 0);
  EXPECT_EQ(StepsOverLimit(t, p.selection.limits, false), 0);
  EXPECT_EQ(StepsOverLimit(t, p.selection.limits, true), 0);
  // Every sample between 0.3 m samples at output_step_m or finer.
  EXPECT_GE(t.samples.size(), 19u * 6u + 1u);
  // The spline passes through the selected positions.
  int knots = 0;
  for (const CameraPathSample& c : t.samples) {
    for (std::size_t s = 0; s < path.size(); ++s) {
      if (c.arc_length_m != path[s].arc_length_m) continue;
      const CameraCandidate& v = r.candidates[s][r.selection.selected[s]];
      EXPECT_LT((c.position_W - v.position_W).norm(), kKnotTolM) << "sample " << s;
      EXPECT_NEAR(c.yaw_rad, v.yaw_rad, kAngleTolRad);
      EXPECT_NEAR(c.pitch_rad, v.pitch_rad, kAngleTolRad);
      ++knots;
    }
  }
  EXPECT_EQ(knots, static_cast<int>(path.size()));
}

TEST(CameraPath, SpeedLimitsHoldOnTheInterpolatedPathOrAreCounted) {
  // A tight turn, a wild gain and no smoothing: the selection jumps and the clamps must act.
  const std::vector<CameraBaseSample> path = BasePath(20, 0.3f, 1.5f);
  CameraPathParams p;
  p.mode = CameraMode::kNoLinear;
  p.selection.weight_angular = 0.0;
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    CameraViewScore v = RoughGain(q, b);
    v.yaw_rad = b.heading_rad + 2.0f * (v.gain - 0.5f);
    return v;
  };
  const CameraPathResult r = PlanCameraPath(path, p, {}, score);
  const CameraTrajectory& t = r.trajectory;
  EXPECT_GT(t.linear_speed_clamps + t.angular_speed_clamps + t.workspace_clamps, 0);
  // Position: any step still over v_m is one the workspace forced, and counted.
  EXPECT_EQ(StepsOverLimit(t, p.selection.limits, false), t.speed_violations);
  EXPECT_LE(t.speed_violations, t.workspace_clamps);
  // Angles are never forced: every turn is within a_m.
  EXPECT_EQ(StepsOverLimit(t, p.selection.limits, true), 0);
  for (const CameraPathSample& c : t.samples)
    EXPECT_TRUE(
        InCameraWorkspace(c.position_W, c.base, p.candidates.workspace, 0.0f, kWorkspaceTolM));
}

TEST(CameraPath, AnglesTakeTheShortWayAcrossTheSeam) {
  // Three views on a straight path; yaw crosses ±π between the first two (3.0 -> -3.0 is a
  // 0.283 rad turn, not 6 rad) and turns back the short way after.
  const std::vector<CameraBaseSample> path = BasePath(3, 0.3f);
  std::vector<CameraCandidate> views(3);
  const float yaws[3] = {3.0f, -3.0f, 2.9f};
  for (int s = 0; s < 3; ++s) {
    views[s].position_W = CameraPositionInWorkspace(path[s], 0.6f, 0.0f, 0.9f, 0.0f);
    views[s].yaw_rad = yaws[s];
    views[s].pitch_rad = 0.1f * static_cast<float>(s);
  }
  const std::vector<const CameraCandidate*> ptrs = {&views[0], &views[1], &views[2]};
  CameraInterpolationParams p;
  p.limits.angular_radps = 10.0f;  // no clamp: test the interpolation itself
  const CameraTrajectory t = InterpolateCameraPath(path, ptrs, p);
  ASSERT_GT(t.samples.size(), 3u);
  EXPECT_EQ(t.angular_speed_clamps, 0);
  for (const CameraPathSample& c : t.samples) {
    const int seg = c.arc_length_m < path[1].arc_length_m ? 0 : 1;
    const double span = std::abs(Wrap(double{yaws[seg + 1]} - yaws[seg]));
    // Within the short arc between the segment's views: never further from either end than the
    // wrapped difference.
    EXPECT_LE(std::abs(Wrap(double{c.yaw_rad} - yaws[seg])), span + kAngleTolRad);
    EXPECT_LE(std::abs(Wrap(double{c.yaw_rad} - yaws[seg + 1])), span + kAngleTolRad);
    EXPECT_LE(std::abs(c.yaw_rad), kPi + kAngleTolRad);
  }
  // Each step turns by its segment's wrapped difference over the segment's 6 steps (0.3 m at
  // 0.05 m): no flip, no long way round.
  for (std::size_t k = 1; k < t.samples.size(); ++k) {
    const int seg = t.samples[k].arc_length_m <= path[1].arc_length_m ? 0 : 1;
    const double span = std::abs(Wrap(double{yaws[seg + 1]} - yaws[seg]));
    const double step = std::abs(Wrap(double{t.samples[k].yaw_rad} - t.samples[k - 1].yaw_rad));
    EXPECT_LE(step, span / 6.0 + kAngleTolRad) << "step " << k;
  }
  // And the knots carry the views' angles.
  EXPECT_NEAR(t.samples.front().yaw_rad, yaws[0], kAngleTolRad);
  EXPECT_NEAR(t.samples.back().yaw_rad, yaws[2], kAngleTolRad);
  EXPECT_NEAR(t.samples.back().pitch_rad, 0.2f, kAngleTolRad);
}

TEST(CameraPath, SamplesWithoutFreeCandidatesAreSkipped) {
  const std::vector<CameraBaseSample> path = BasePath(12, 0.3f);
  // Everything within 0.92 m of sample 3 (beyond its reach) is occupied, and only the right half
  // (y < 0) is free anywhere.
  const Eigen::Vector2f blocked = path[3].xy_m;
  constexpr float kBlockedRadiusM = 0.92f;
  const CameraFreeFn free = [&](const Eigen::Vector3f& q) {
    return (q.head<2>() - blocked).norm() > kBlockedRadiusM && q.y() < 0.0f;
  };
  CameraPathParams p;
  p.candidates.max_tries = 200;
  const CameraPathResult r = PlanCameraPath(path, p, free, RoughGain);
  EXPECT_TRUE(r.candidates[3].empty());
  int empty = 0;
  for (std::size_t s = 0; s < path.size(); ++s) {
    if (r.candidates[s].empty()) {
      ++empty;
      // Only the blocked sample and its neighbour behind (whose forward half-disc Ψ mostly lies
      // inside the obstacle) can lose every candidate.
      EXPECT_TRUE(s == 2 || s == 3) << "sample " << s;
      EXPECT_EQ(r.selection.selected[s], -1);
      continue;
    }
    // Far from the obstacle half of Ψ is free, so the retries still find C candidates.
    const float clear = (path[s].xy_m - blocked).norm() - kBlockedRadiusM;
    if (clear > p.candidates.workspace.reach_max_m) {
      EXPECT_EQ(static_cast<int>(r.candidates[s].size()), p.candidates.candidates_per_sample);
    }
    for (const CameraCandidate& c : r.candidates[s]) EXPECT_TRUE(free(c.position_W));
    ASSERT_GE(r.selection.selected[s], 0);
    EXPECT_TRUE(free(r.candidates[s][r.selection.selected[s]].position_W));
  }
  EXPECT_GE(empty, 1);
  EXPECT_EQ(r.selection.samples_without_candidates, empty);
  ASSERT_FALSE(r.trajectory.samples.empty());
  EXPECT_NEAR(r.trajectory.samples.back().arc_length_m, path.back().arc_length_m, 1e-6f);
  for (const CameraPathSample& c : r.trajectory.samples)
    EXPECT_TRUE(
        InCameraWorkspace(c.position_W, c.base, p.candidates.workspace, 0.0f, kWorkspaceTolM));
}

TEST(CameraPath, FixedModeIsTheRigidForwardCamera) {
  const std::vector<CameraBaseSample> path = BasePath(10, 0.3f, 0.5f);
  CameraPathParams p;
  p.mode = CameraMode::kFixed;
  int scored = 0;
  const CameraScoreFn score = [&](const Eigen::Vector3f&, const CameraBaseSample& b) {
    ++scored;
    return CameraViewScore{b.heading_rad, 0.0f, 1.0f};
  };
  const CameraPathResult r = PlanCameraPath(path, p, {}, score);
  EXPECT_EQ(scored, 0);
  ASSERT_EQ(r.candidates.size(), path.size());
  for (std::size_t s = 0; s < path.size(); ++s) {
    ASSERT_EQ(r.candidates[s].size(), 1u);
    EXPECT_EQ(r.selection.selected[s], 0);
  }
  for (const CameraPathSample& c : r.trajectory.samples) {
    const Eigen::Vector3f off = CameraOffsetInBase(c.position_W, c.base, 0.0f);
    EXPECT_NEAR(off.x(), p.fixed_forward_m, kWorkspaceTolM);
    EXPECT_NEAR(off.y(), 0.0f, kWorkspaceTolM);
    EXPECT_NEAR(off.z(), p.fixed_height_m, kWorkspaceTolM);
    EXPECT_NEAR(Wrap(c.yaw_rad - c.base.heading_rad), 0.0, kAngleTolRad);
    EXPECT_EQ(c.pitch_rad, p.fixed_pitch_rad);
  }
}

TEST(CameraPath, NoAngularModeDropsTheAngleTerm) {
  const std::vector<CameraBaseSample> path = BasePath(12, 0.3f);
  CameraPathParams p;
  p.mode = CameraMode::kNoAngular;
  const CameraScoreFn score = [](const Eigen::Vector3f& q, const CameraBaseSample& b) {
    CameraViewScore v = RoughGain(q, b);
    v.yaw_rad = b.heading_rad + 0.5f * (v.gain - 0.5f);
    return v;
  };
  const CameraPathResult r = PlanCameraPath(path, p, {}, score);
  EXPECT_EQ(r.selection.energy.angular, 0.0);
  CameraPathParams q;
  q.selection.weight_angular = 0.0;
  EXPECT_EQ(PlanCameraPath(path, q, {}, score).selection.selected, r.selection.selected);
  EXPECT_GT(PlanCameraPath(path, CameraPathParams{}, {}, score).selection.energy.angular, 0.0);
}

}  // namespace
}  // namespace voxplan::tensorfield
