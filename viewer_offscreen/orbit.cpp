#include "viewer_offscreen/orbit.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

namespace voxplan {

namespace {

constexpr float kFramingMargin = 1.05f;

float Radians(float deg) { return deg * std::numbers::pi_v<float> / 180.0f; }

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
