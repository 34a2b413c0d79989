// Trajectory evaluation against hand-computed answers: rigid motion only (ATE 0), a known
// offset on a symmetric subset, partial timestamp overlap, and the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "eval/eval_trajectory.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

constexpr double kTol = 1e-9;

// Poses at the 8 cube corners (+-1 m): their covariance is isotropic, so a subset whose
// centroid is the cube centre leaves the best rotation at identity (hand-computable ATE).
std::vector<Pose3d> CubePoses() {
  std::vector<Pose3d> poses;
  for (int i = 0; i < 8; ++i) {
    Pose3d T = Pose3d::Identity();
    T.linear() =
        Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d(0.3, -0.2, 1.0).normalized()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    poses.push_back(T);
  }
  return poses;
}

Pose3d SomeRigidMotion() {
  Pose3d T = Pose3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(3.0, -1.5, 0.25);
  return T;
}

TumTrajectory Make(const std::vector<double>& t, const std::vector<Pose3d>& poses) {
  TumTrajectory trajectory;
  trajectory.timestamps_s = t;
  trajectory.T_W_C = poses;
  return trajectory;
}

std::vector<double> Times(size_t n, double start = 0.0, double step = 0.1) {
  std::vector<double> t;
  for (size_t i = 0; i < n; ++i) t.push_back(start + step * double(i));
  return t;
}

TEST(EvalTrajectoryTest, RigidlyMovedCopyHasZeroError) {
  const std::vector<Pose3d> estimate = CubePoses();
  std::vector<Pose3d> reference;
  for (const Pose3d& T : estimate) reference.push_back(SomeRigidMotion() * T);
  Result<TrajectoryEvalResult> r =
      EvaluateTrajectory(Make(Times(8), estimate), Make(Times(8), reference));
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->pairs, 8u);
  EXPECT_NEAR(r->ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(r->ate_max_m, 0.0, 1e-9);
  EXPECT_NEAR(r->rpe_trans_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(r->rpe_rot_rmse_deg, 0.0, 1e-6);
  EXPECT_EQ(r->rpe_pairs, 7u);
  EXPECT_TRUE(r->T_ref_est.isApprox(SomeRigidMotion(), 1e-9));
}

TEST(EvalTrajectoryTest, OffsetOnSymmetricSubsetGivesHandComputedError) {
  // Corners 0 (-1,-1,-1) and 7 (1,1,1) of the estimate move by d along x. Their centroid is
  // the cube's, so the best rotation stays identity and the best translation is the mean
  // offset 2d/8 = d/4: residuals 3d/4 (twice) and d/4 (six times).
  const double d = 0.08;
  std::vector<Pose3d> estimate = CubePoses(), reference;
  for (const Pose3d& T : estimate) reference.push_back(SomeRigidMotion() * T);
  for (int i : {0, 7}) estimate[size_t(i)].translation().x() += d;

  Result<TrajectoryEvalResult> r =
      EvaluateTrajectory(Make(Times(8), estimate), Make(Times(8), reference));
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_NEAR(r->ate_rmse_m, d / 4.0 * std::sqrt(3.0), kTol);  // sqrt((2*9 + 6) / 8) d/4
  EXPECT_NEAR(r->ate_mean_m, 3.0 * d / 8.0, kTol);
  EXPECT_NEAR(r->ate_median_m, d / 4.0, kTol);
  EXPECT_NEAR(r->ate_max_m, 3.0 * d / 4.0, kTol);
  // Consecutive pairs (0,1) and (6,7) each hold one moved pose: relative translation error
  // |R_k^T d e_x| = d there, 0 elsewhere; rotations untouched.
  EXPECT_NEAR(r->rpe_trans_rmse_m, d * std::sqrt(2.0 / 7.0), kTol);
  EXPECT_NEAR(r->rpe_trans_mean_m, 2.0 * d / 7.0, kTol);
  EXPECT_NEAR(r->rpe_rot_rmse_deg, 0.0, 1e-6);
}

TEST(EvalTrajectoryTest, PartialOverlapAssociatesNearestWithinMaxDt) {
  // Reference at 0.0, 0.1, ..., 0.7; the estimate runs 0.305 .. 1.005 with a 5 ms lag, so its
  // first 5 poses (0.305 .. 0.705) meet the reference's last 5 and the rest run past its end.
  const std::vector<Pose3d> cube = CubePoses();
  std::vector<Pose3d> estimate;
  for (int i = 3; i < 8; ++i) estimate.push_back(cube[size_t(i)]);
  for (int i = 0; i < 3; ++i) estimate.push_back(cube[size_t(i)]);  // after the reference ends
  Result<TrajectoryEvalResult> r =
      EvaluateTrajectory(Make(Times(8, 0.305), estimate), Make(Times(8), cube));
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->pairs, 5u);
  EXPECT_NEAR(r->ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(r->rpe_trans_rmse_m, 0.0, 1e-9);

  // A tighter window than the lag leaves nothing.
  TrajectoryEvalParams strict;
  strict.max_dt_s = 0.001;
  EXPECT_FALSE(
      EvaluateTrajectory(Make(Times(8, 0.305), estimate), Make(Times(8), cube), strict).ok());
}

TEST(EvalTrajectoryTest, FilesRoundTripAndNoOverlapNamesBothFiles) {
  const test::TempDir dir("voxplan-traj");
  const std::vector<Pose3d> cube = CubePoses();
  const std::string est = (dir / "est.txt").string(), ref = (dir / "ref.txt").string();
  ASSERT_TRUE(WriteTumTrajectory(est, Times(8, 100.0), cube).ok());
  ASSERT_TRUE(WriteTumTrajectory(ref, Times(8), cube).ok());

  Result<TumTrajectory> read = ReadTumTrajectory(est);
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->T_W_C.size(), 8u);
  EXPECT_EQ(read->source, est);
  for (size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(read->timestamps_s[i], 100.0 + 0.1 * double(i), 1e-6);
    EXPECT_TRUE(read->T_W_C[i].isApprox(cube[i], 1e-7));
  }

  Result<TumTrajectory> reference = ReadTumTrajectory(ref);
  ASSERT_TRUE(reference.ok());
  Result<TrajectoryEvalResult> r = EvaluateTrajectory(*read, *reference);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("no overlapping timestamps"), std::string::npos);
  EXPECT_NE(r.status().message().find(est), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find(ref), std::string::npos) << r.status().message();

  EXPECT_FALSE(WriteTumTrajectory(est, Times(3), cube).ok());  // lengths differ
}

}  // namespace
}  // namespace voxplan
