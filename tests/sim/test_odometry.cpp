// The odometry noise model (sim/odometry.h): no motion no noise, the same draw for the same
// (seed, stream), and errors whose spread grows with the motion as the parameters say.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "sim/odometry.h"

namespace voxplan {
namespace {

Pose3f Motion(float forward_m, float turn_rad) {
  Pose3f delta = Pose3f::Identity();
  delta.translation() = Eigen::Vector3f(0.f, 0.f, forward_m);  // a camera looks along +z
  delta.linear() = Eigen::AngleAxisf(turn_rad, Eigen::Vector3f::UnitY()).toRotationMatrix();
  return delta;
}

TEST(Odometry, StandingStillIsExact) {
  const Pose3f noisy = NoisyOdometry(Pose3f::Identity(), {}, 3, 17);
  EXPECT_TRUE(noisy.isApprox(Pose3f::Identity(), 0.f));
}

TEST(Odometry, SameSeedAndStreamSameDraw) {
  const Pose3f delta = Motion(0.3f, 0.2f);
  EXPECT_TRUE(NoisyOdometry(delta, {}, 5, 9).isApprox(NoisyOdometry(delta, {}, 5, 9), 0.f));
  EXPECT_FALSE(NoisyOdometry(delta, {}, 5, 9).isApprox(NoisyOdometry(delta, {}, 5, 10), 1e-6f));
  EXPECT_FALSE(NoisyOdometry(delta, {}, 6, 9).isApprox(NoisyOdometry(delta, {}, 5, 9), 1e-6f));
}

TEST(Odometry, ErrorSpreadFollowsTheMotion) {
  // Over 4000 streams, the per-axis standard deviation of the translation error is
  // translation_per_m x |t| and the rotation error's rotation_per_rad x angle + rotation_per_m x
  // |t|, within 5 % (the sampling error of 12000 draws is under 2 %).
  OdometryNoiseParams p;
  p.translation_per_m = 0.05f;
  p.rotation_per_rad = 0.02f;
  p.rotation_per_m = 0.01f;
  const float forward = 0.5f, turn = 0.4f;
  const Pose3f delta = Motion(forward, turn);
  double sum_t2 = 0.0, sum_r2 = 0.0;
  const int n = 4000;
  for (int s = 0; s < n; ++s) {
    const Pose3f noisy = NoisyOdometry(delta, p, 1, uint64_t(s));
    sum_t2 += double((noisy.translation() - delta.translation()).squaredNorm());
    const Eigen::AngleAxisf err(delta.linear().transpose() * noisy.linear());
    sum_r2 += double(err.angle() * err.angle());
  }
  const double sigma_t = std::sqrt(sum_t2 / (3.0 * n));
  const double sigma_r = std::sqrt(sum_r2 / (3.0 * n));
  EXPECT_NEAR(sigma_t, 0.05 * forward, 0.05 * 0.05 * forward);
  EXPECT_NEAR(sigma_r, 0.02 * turn + 0.01 * forward, 0.05 * (0.02 * turn + 0.01 * forward));
}

}  // namespace
}  // namespace voxplan
