#pragma once
// Frame convention, written once: T_A_B maps points from frame B into frame A, p_A = T_A_B * p_B.
// Cameras use OpenCV axes (x right, y down, z forward); T_W_C is camera-to-world.
#include <Eigen/Geometry>
#include <string>

#include "core/status.h"

namespace voxplan {

using Pose3f = Eigen::Isometry3f;
using Pose3d = Eigen::Isometry3d;

// Checks a 4x4 camera-to-world matrix: finite, last row 0 0 0 1, rotation orthonormal
// (|R^T R - I| < 1e-3) with det +1.
Status ValidatePoseMatrix(const Eigen::Matrix4d& m);

// Builds a pose from translation and quaternion (x y z w). A quaternion whose norm is within
// 1e-2 of one is renormalised (`*renormalised` set); others, and non-finite values, are refused.
Result<Pose3d> PoseFromTranslationQuaternion(const Eigen::Vector3d& t, double qx, double qy,
                                             double qz, double qw, bool* renormalised = nullptr);

// T_W_C of a camera at `eye_W` looking at `target_W`, image up along `up_W` (x stays
// horizontal). Looking straight along `up_W` falls back to world Y as up. eye != target.
Pose3f LookAt(const Eigen::Vector3f& eye_W, const Eigen::Vector3f& target_W,
              const Eigen::Vector3f& up_W = Eigen::Vector3f::UnitZ());

}  // namespace voxplan
