#include "core/pose.h"

#include <cassert>
#include <cmath>

namespace voxplan {

Status ValidatePoseMatrix(const Eigen::Matrix4d& m) {
  if (!m.allFinite()) return InvalidArgument("pose has NaN or infinite entries");
  if (std::abs(m(3, 0)) > 1e-6 || std::abs(m(3, 1)) > 1e-6 || std::abs(m(3, 2)) > 1e-6 ||
      std::abs(m(3, 3) - 1.0) > 1e-6)
    return InvalidArgument("pose last row is not 0 0 0 1");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double ortho_err = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho_err > 1e-3 || r.determinant() < 0.0)
    return InvalidArgument(
        "pose rotation is not orthonormal (|R^T R - I| = " + std::to_string(ortho_err) + ")");
  return Status::Ok();
}

Result<Pose3d> PoseFromTranslationQuaternion(const Eigen::Vector3d& t, double qx, double qy,
                                             double qz, double qw, bool* renormalised) {
  if (!t.allFinite() || !std::isfinite(qx) || !std::isfinite(qy) || !std::isfinite(qz) ||
      !std::isfinite(qw))
    return InvalidArgument("pose has NaN or infinite values");
  Eigen::Quaterniond q(qw, qx, qy, qz);
  const double n = q.norm();
  if (std::abs(n - 1.0) > 1e-2)
    return InvalidArgument("quaternion is not unit (norm " + std::to_string(n) + ")");
  if (renormalised) *renormalised = std::abs(n - 1.0) > 1e-6;
  q.normalize();
  Pose3d pose = Pose3d::Identity();
  pose.linear() = q.toRotationMatrix();
  pose.translation() = t;
  return pose;
}

Pose3f LookAt(const Eigen::Vector3f& eye_W, const Eigen::Vector3f& target_W,
              const Eigen::Vector3f& up_W) {
  assert((target_W - eye_W).norm() > 0.0f);
  const Eigen::Vector3f z_W = (target_W - eye_W).normalized();  // forward
  Eigen::Vector3f x_W = z_W.cross(up_W);                        // right
  if (x_W.norm() < 1e-6f) x_W = z_W.cross(Eigen::Vector3f::UnitY());
  x_W.normalize();
  const Eigen::Vector3f y_W = z_W.cross(x_W);  // down in the image
  Pose3f T_W_C = Pose3f::Identity();
  T_W_C.linear().col(0) = x_W;
  T_W_C.linear().col(1) = y_W;
  T_W_C.linear().col(2) = z_W;
  T_W_C.translation() = eye_W;
  return T_W_C;
}

}  // namespace voxplan
