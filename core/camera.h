#pragma once
// Pinhole camera with OpenCV axes. fy may be negative (ICL-NUIM's flipped image y axis).
#include <Eigen/Core>

namespace voxplan {

struct PinholeCamera {
  int width = 0;
  int height = 0;
  float fx = 0.f, fy = 0.f, cx = 0.f, cy = 0.f;

  bool Valid() const { return width > 0 && height > 0 && fx != 0.f && fy != 0.f; }
  // Pixel (u, v) of a camera-frame point with z > 0; pixel centres are integers.
  Eigen::Vector2f Project(const Eigen::Vector3f& p_C) const {
    return {fx * p_C.x() / p_C.z() + cx, fy * p_C.y() / p_C.z() + cy};
  }
  // Camera-frame point at depth z (along the optical axis) through pixel (u, v).
  Eigen::Vector3f Unproject(float u, float v, float z) const {
    return {(u - cx) / fx * z, (v - cy) / fy * z, z};
  }
  bool InImage(int u, int v) const { return u >= 0 && v >= 0 && u < width && v < height; }
};

}  // namespace voxplan
