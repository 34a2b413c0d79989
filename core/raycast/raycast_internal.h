#pragma once
// Internal to core/raycast/: what the driver, the range image and both marches share: the
// tiling and march constants, the range image, a ray's task and result, and a batch's
// images with the writer both marches call per ray.
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"
#include "core/raycast.h"
#include "core/volume.h"

// SSE2 is x86-64's baseline: the caster's SSE2 code needs no check of the CPU.
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace voxplan::raycast_detail {

inline constexpr int kRangeCell = 8;    // pixels per side of a range-image cell
inline constexpr int kSurfaceCell = 2;  // pixels per side of a surface-range cell
inline constexpr int kTile = 16;        // pixels per side of one parallel work item
// Tiles whose rays feed one march (fewer idle lanes at the end).
inline constexpr int kTilesPerBatch = 4;
// Step as a fraction of the stored distance: the nearest voxel's centre can be up to 0.87 voxel
// from the sample, and the negative band behind a surface is what catches an overshoot.
inline constexpr float kStepScale = 0.9f;
// Two Newton steps from the linear guess land within a hundredth of a voxel on a smooth
// surface; each further step costs a cell gather and changes the depth by less.
inline constexpr int kNewtonIterations = 2;
inline constexpr float kConvergedVoxels = 0.05f;   // a Newton step this small ends the search
inline constexpr float kMinSlopeFraction = 0.05f;  // of the head-on slope; below it, the ray grazes
inline constexpr int kSecantIterations = 3;
inline constexpr int kMaxBracketShifts = 2;  // voxels the trilinear bracket may move either way
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Per cell of kRangeCell^2 pixels, the depth range where the rays through it can meet an
// allocated block: rays skip everything in front of the nearest block at once.
struct RangeImage {
  int cols = 0, rows = 0;
  std::vector<float> z_min, z_max;  // z_min > z_max where no block projects
  // Per cell of kSurfaceCell^2 pixels, the nearest depth of the cubes of negative voxels: a surface
  // crossing can only end in such a cube, so rays that can hit start just in front of it.
  int surface_cols = 0, surface_rows = 0;
  std::vector<float> surface_z_min;
};

// The range image of a cast; `avx2` splats with the AVX2 builds of the splatting
// (march_avx2.cpp), which give the same images.
RangeImage BuildRangeImage(const TsdfVolume& volume, const PinholeCamera& camera,
                           const Pose3f& T_C_W, const RaycastParams& params, bool avx2);

// The depth where marching starts: a voxel before min_depth, so that a surface just beyond it
// is approached from its positive side (crossings in front of min_depth are not reported).
inline float MarchStart(const TsdfVolume& volume, const RaycastParams& params) {
  return std::max(params.min_depth_m - volume.voxel_size_m(), 1e-3f);
}

// A pixel whose ray has a depth range to march.
struct RayTask {
  size_t pixel;  // where the result goes (Raycast: the index in its batch's images)
  int u, v;
  float z_begin, z_end;
  // >= 0: [z_skipped, z_begin) was skipped (it holds no surface); marched as well when the march
  // from z_begin meets no observed voxel, so that the status says whether the ray met any.
  float z_skipped;
};

struct RayResult {
  RayStatus status = RayStatus::kUnobserved;
  float z = 0.f;
  Eigen::Vector3f normal_W = Eigen::Vector3f::Constant(kNaN);
  uint32_t color = 0;
};

// A batch's own images, where the marches write their results (a pixel's index there is its
// tile's place in the batch, then its row and column in the tile).
inline constexpr int kBatchPixels = kTilesPerBatch * kTile * kTile;
struct BatchImages {
  float depth[kBatchPixels];
  Eigen::Vector3f vertex_W[kBatchPixels], normal_W[kBatchPixels];
  uint32_t color[kBatchPixels];
  uint8_t status[kBatchPixels];
};

// write(i, result, dir_W): ray dir_W's result into pixel i of a batch's images. Inline: both
// marches call it once per ray. Holds references, as the driver's lambda it replaced captured
// them (the packet march's inlining, and so its speed, depends on it).
struct BatchWriter {
  BatchImages& out;
  const Eigen::Vector3f& origin_W;
  const Eigen::Vector3f& nan3;  // (NaN, NaN, NaN)

  void operator()(size_t i, const RayResult& ray, const Eigen::Vector3f& dir_W) const {
    out.status[i] = uint8_t(ray.status);
    if (ray.status == RayStatus::kHit) {
      out.depth[i] = ray.z;
      out.vertex_W[i] = origin_W + ray.z * dir_W;
      out.normal_W[i] = ray.normal_W;
      out.color[i] = ray.color;
    } else {
      out.depth[i] = 0.f;
      out.vertex_W[i] = nan3;
      out.normal_W[i] = nan3;
      out.color[i] = 0;
    }
  }
};

}  // namespace voxplan::raycast_detail
