#pragma once
// A robot's odometry: the camera's true motion between two frames with drift-like noise, the
// prior a tracker starts from (Xu 2017's quality claims are about registration, so the loop can
// fuse at tracked poses instead of the truth). Counter-based and seeded: the same (seed, stream)
// gives the same noise on every platform.
#include <cstdint>

#include "core/pose.h"

namespace voxplan {

struct OdometryNoiseParams {
  float translation_per_m = 0.02f;  // 1 σ per axis, per metre the camera moved
  float rotation_per_rad = 0.01f;   // 1 σ per axis, per radian it turned
  float rotation_per_m = 0.002f;    // 1 σ per axis, per metre moved (heading drift while driving)
};

// delta_C = T_W_Cprev^-1 * T_W_C (the motion in the previous camera's frame) with noise: a
// translation error of σ = translation_per_m · |t| on each axis and a rotation error (axis-angle,
// each axis) of σ = rotation_per_rad · angle + rotation_per_m · |t|. Zero motion, zero noise.
Pose3f NoisyOdometry(const Pose3f& delta_C, const OdometryNoiseParams& params, uint64_t seed,
                     uint64_t stream);

}  // namespace voxplan
