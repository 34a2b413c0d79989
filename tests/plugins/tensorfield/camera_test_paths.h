#pragma once
// Shared by the camera-trajectory tests: the angle wrap they compare with, and a straight base
// path.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "plugins/tensorfield/algorithms/camera_path.h"

namespace voxplan::tensorfield::test {

// a in (-pi, pi].
inline double Wrap(double a) { return std::remainder(a, 2.0 * 3.14159265358979323846); }

// Base samples every spacing_m along +x from the origin (heading 0).
inline std::vector<CameraBaseSample> StraightPath(int samples, float spacing_m) {
  std::vector<CameraBaseSample> path;
  for (int s = 0; s < samples; ++s) {
    const float x = spacing_m * static_cast<float>(s);
    path.push_back({Eigen::Vector2f(x, 0.0f), 0.0f, x});
  }
  return path;
}

}  // namespace voxplan::tensorfield::test
