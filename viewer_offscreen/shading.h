#pragma once
// CPU shading of ray-cast surfaces into RGB images: Phong with a headlight, normals, surface
// colour and a depth colour map. Inputs are plain per-pixel images, so the same code serves the
// TSDF raycaster (core/raycast.h) and mesh renders (depth + colour, normals from depth).
#include <Eigen/Core>
#include <string>
#include <string_view>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/status.h"

namespace voxplan {

enum class ShadeMode { kShaded, kNormals, kColour, kDepth };

// "shaded", "normals", "colour" (or "color"), "depth".
Result<ShadeMode> ParseShadeMode(std::string_view name);
const char* ShadeModeName(ShadeMode mode);

// What a renderer saw per pixel. A pixel is a hit where depth > 0 and finite.
struct SurfaceImages {
  DepthImage depth;                 // z along the optical axis, metres; 0 on a miss
  Image<Eigen::Vector3f> vertex_W;  // hit point in world (empty: computed from depth on demand)
  Image<Eigen::Vector3f> normal_W;  // unit normal in world; NaN where unknown
  ColorImage color;                 // surface colour; empty when the surface has none
};

struct ShadeParams {
  float ambient = 0.25f;
  float diffuse = 0.7f;
  float specular = 0.2f;
  float shininess = 24.0f;
  uint32_t background = PackRgb(48, 48, 48);  // missed pixels (depth mode: black)
  uint32_t neutral = PackRgb(190, 190, 190);  // surface colour when the surface has none
  // Depth colour map range, metres; near_m >= far_m picks it from the image (1st..99th
  // percentile of the valid depths).
  float depth_near_m = 0.0f;
  float depth_far_m = 0.0f;
};

// Shades `surface` as seen by `camera` at T_W_C. Refuses images whose sizes disagree with each
// other or with the camera.
Result<ColorImage> Shade(const SurfaceImages& surface, const PinholeCamera& camera,
                         const Pose3f& T_W_C, ShadeMode mode, const ShadeParams& params = {});

// World points of every valid depth pixel (NaN elsewhere).
Image<Eigen::Vector3f> VerticesFromDepth(const DepthImage& depth, const PinholeCamera& camera,
                                         const Pose3f& T_W_C);
// Normals by the cross product of neighbour differences, taking on each axis the neighbour
// with the smaller depth jump so edges do not smear; turned to face the camera at
// `camera_centre_W`. NaN where a pixel has no valid neighbour on some axis.
Image<Eigen::Vector3f> NormalsFromVertices(const Image<Eigen::Vector3f>& vertex_W,
                                           const Eigen::Vector3f& camera_centre_W);

// Viridis (perceptually uniform, lightness rising with t) at t in [0, 1], clamped.
uint32_t ViridisColor(float t);

}  // namespace voxplan
