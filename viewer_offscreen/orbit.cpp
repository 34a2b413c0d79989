#include "viewer_offscreen/orbit.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

namespace voxplan {

namespace {

constexpr float kFramingMargin = 1.05f;

float Radians(float deg) { return deg * std::numbers::pi_v<float> / 180.0f; }

// Tangents of the half-angles of `camera`'s view, narrowed by the framing margin.
Eigen::Vector2f HalfViewTangents(const PinholeCamera& camera) {
  return {0.5f * float(camera.width) / std::abs(camera.fx) / kFramingMargin,
          0.5f * float(camera.height) / std::abs(camera.fy) / kFramingMargin};
}

}  // namespace

std::vector<Pose3f> OrbitPoses(const Eigen::Vector3f& centre_W, float radius_m, float height_m,
                               int n, const Eigen::Vector3f& up_W) {
  const Eigen::Vector3f up = up_W.normalized();
  // Axes of the orbit plane: +X and +Y for Z-up; any right-handed pair otherwise.
  Eigen::Vector3f a_W = std::abs(up.z()) > 0.9f
                            ? Eigen::Vector3f(Eigen::Vector3f::UnitX())
                            : Eigen::Vector3f(up.cross(Eigen::Vector3f::UnitZ()));
  a_W = (a_W - a_W.dot(up) * up).normalized();
  const Eigen::Vector3f b_W = up.cross(a_W);
  std::vector<Pose3f> poses;
  poses.reserve(size_t(std::max(n, 0)));
  for (int k = 0; k < n; ++k) {
    const float angle = 2.0f * std::numbers::pi_v<float> * float(k) / float(n);
    const Eigen::Vector3f eye_W = centre_W + radius_m * std::cos(angle) * a_W +
                                  radius_m * std::sin(angle) * b_W + height_m * up;
    poses.push_back(LookAt(eye_W, centre_W, up));
  }
  return poses;
}

OrbitFraming FrameBox(const Eigen::AlignedBox3f& box_W, const PinholeCamera& camera,
                      float elevation_deg) {
  OrbitFraming f;
  if (!box_W.isEmpty()) f.centre_W = box_W.center();
  f.bound_radius_m = box_W.isEmpty() ? 0.0f : 0.5f * box_W.diagonal().norm();
  const float r = std::max(f.bound_radius_m, 1e-3f);
  // Half-angles of the view; the sphere fits when its angular radius is within the narrower.
  const float half_x = std::atan(0.5f * float(camera.width) / std::abs(camera.fx));
  const float half_y = std::atan(0.5f * float(camera.height) / std::abs(camera.fy));
  const float half_fov = std::min(half_x, half_y);
  // A little margin so the silhouette does not touch the image border.
  f.distance_m = kFramingMargin * r / std::sin(half_fov);
  f.radius_m = f.distance_m * std::cos(Radians(elevation_deg));
  f.height_m = f.distance_m * std::sin(Radians(elevation_deg));
  return f;
}

OrbitFraming FrameSurface(const std::vector<Eigen::Vector3f>& samples_W,
                          const PinholeCamera& camera, float elevation_deg, int n,
                          const Eigen::Vector3f& up_W, float trim) {
  if (samples_W.empty()) return FrameBox(Eigen::AlignedBox3f(), camera, elevation_deg);
  // The index of the largest value left once a `trim` share (rounded down) is left out above.
  const size_t m = samples_W.size();
  const size_t k = m - 1 - size_t(double(std::clamp(trim, 0.0f, 0.5f)) * double(m - 1));
  std::vector<float> values(m);
  const auto upper_quantile = [&values, k] {
    std::nth_element(values.begin(), values.begin() + ptrdiff_t(k), values.end());
    return values[k];
  };
  Eigen::AlignedBox3f box;
  for (int axis = 0; axis < 3; ++axis) {
    for (size_t i = 0; i < m; ++i) values[i] = -samples_W[i][axis];
    box.min()[axis] = -upper_quantile();
    for (size_t i = 0; i < m; ++i) values[i] = samples_W[i][axis];
    box.max()[axis] = upper_quantile();
  }
  OrbitFraming f;
  f.centre_W = box.center();
  f.bound_radius_m = 0.5f * box.diagonal().norm();
  // The views' rotations (the same at any distance). A sample q (camera axes, relative to the
  // centre) is in view from distance d when d + q.z >= max(|q.x| / tx, |q.y| / ty, 5 cm).
  const float e = Radians(elevation_deg);
  const std::vector<Pose3f> views =
      OrbitPoses(f.centre_W, std::cos(e), std::sin(e), std::max(n, 1), up_W);
  const Eigen::Vector2f t = HalfViewTangents(camera);
  float distance = 1e-3f;
  for (const Pose3f& view : views) {
    const Eigen::Matrix3f R_C_W = view.linear().transpose();
    for (size_t i = 0; i < m; ++i) {
      const Eigen::Vector3f q = R_C_W * (samples_W[i] - f.centre_W);
      values[i] = std::max({std::abs(q.x()) / t.x(), std::abs(q.y()) / t.y(), 0.05f}) - q.z();
    }
    distance = std::max(distance, upper_quantile());
  }
  f.distance_m = distance;
  f.radius_m = distance * std::cos(e);
  f.height_m = distance * std::sin(e);
  return f;
}

PinholeCamera CameraFromFov(int width, int height, float horizontal_fov_deg) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = 0.5f * float(width) / std::tan(0.5f * Radians(horizontal_fov_deg));
  camera.fy = camera.fx;
  // Pixel centres are integers, so the centre of the image is at (w - 1) / 2.
  camera.cx = 0.5f * float(width - 1);
  camera.cy = 0.5f * float(height - 1);
  return camera;
}

}  // namespace voxplan
