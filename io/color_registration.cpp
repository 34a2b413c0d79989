#include "io/color_registration.h"

#include <algorithm>
#include <cmath>

namespace voxplan {
namespace {

// Bilinear sample at (u, v) (pixel centres at integers), channel by channel, rounded.
uint32_t Sample(const ColorImage& image, float u, float v) {
  const int u0 = int(std::floor(u)), v0 = int(std::floor(v));
  const float a = u - float(u0), b = v - float(v0);
  const auto at = [&](int x, int y) {
    return image.at(std::clamp(x, 0, image.width - 1), std::clamp(y, 0, image.height - 1));
  };
  const uint32_t c00 = at(u0, v0), c10 = at(u0 + 1, v0), c01 = at(u0, v0 + 1),
                 c11 = at(u0 + 1, v0 + 1);
  uint32_t out = 0;
  for (int shift = 0; shift < 24; shift += 8) {
    const auto ch = [&](uint32_t c) { return float((c >> shift) & 0xff); };
    const float value = (1 - a) * (1 - b) * ch(c00) + a * (1 - b) * ch(c10) +
                        (1 - a) * b * ch(c01) + a * b * ch(c11);
    out |= uint32_t(std::lround(std::clamp(value, 0.f, 255.f))) << shift;
  }
  return out;
}

}  // namespace

bool SameCamera(const PinholeCamera& c, const PinholeCamera& d, const Pose3d& T_color_depth) {
  return c.width == d.width && c.height == d.height && c.fx == d.fx && c.fy == d.fy &&
         c.cx == d.cx && c.cy == d.cy && T_color_depth.matrix().isIdentity(1e-9);
}

ColorImage RegisterColorToDepth(const ColorImage& color, const PinholeCamera& color_camera,
                                const DepthImage& depth, const PinholeCamera& depth_camera,
                                const Pose3d& T_color_depth) {
  if (SameCamera(color_camera, depth_camera, T_color_depth)) return color;
  ColorImage out(depth_camera.width, depth_camera.height, 0u);
  const Pose3f T = T_color_depth.cast<float>();
  // Pixels just outside the last centre still sample the edge (half a pixel either way).
  const float u_max = float(color.width) - 0.5f, v_max = float(color.height) - 0.5f;
  for (int v = 0; v < depth_camera.height; ++v) {
    for (int u = 0; u < depth_camera.width; ++u) {
      const float z = depth.empty() ? 0.f : depth.at(u, v);
      const bool valid = z > 0.f && std::isfinite(z);
      const Eigen::Vector3f p_C = T * depth_camera.Unproject(float(u), float(v), valid ? z : 1.f);
      if (!(p_C.z() > 0.f)) continue;
      const Eigen::Vector2f px = color_camera.Project(p_C);
      if (!(px.x() >= -0.5f && px.x() <= u_max && px.y() >= -0.5f && px.y() <= v_max)) continue;
      out.at(u, v) = Sample(color, px.x(), px.y());
    }
  }
  return out;
}

}  // namespace voxplan
