#pragma once
// Ray casting of the hashed TSDF from a camera: depth, world vertices, normals and colour per
// pixel. Rays skip unallocated space a block at a time, march the band with steps bounded by
// the stored distance, refine the zero crossing by trilinear interpolation; parallel over image
// tiles and deterministic. Unobserved voxels never stop a ray; pixels whose ray met no
// observed voxel are reported as unobserved.
#include <Eigen/Core>
#include <cstdint>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/volume.h"

namespace voxplan {

struct RaycastParams {
  float min_depth_m = 0.1f;
  float max_depth_m = 5.0f;
  float min_weight = 0.5f;  // voxels with less weight count as unobserved
  // A ray entering a surface from behind (negative to positive) stops there as kFree, as
  // tracking wants; renders from outside a room march on to see its inside.
  bool stop_at_back_faces = true;
  // Outputs a caller may not need: without them the colour (or normal) image stays 0 (NaN).
  bool with_color = true;
  bool with_normals = true;
  // March rays in AVX2 packets where the CPU has AVX2; false: the scalar reference march. Both
  // give identical images.
  bool simd = true;
};

enum class RayStatus : uint8_t {
  kUnobserved = 0,  // met no observed voxel between min and max depth
  kHit = 1,         // crossed a surface (positive to negative)
  kFree = 2,        // met only observed free space (or a back face: negative to positive)
};

struct RaycastImages {
  DepthImage depth;                 // z along the optical axis, metres; 0 unless kHit
  Image<Eigen::Vector3f> vertex_W;  // hit point in world; NaN unless kHit
  Image<Eigen::Vector3f> normal_W;  // unit outward normal in world; NaN unless kHit (or off)
  ColorImage color;                 // interpolated voxel colour; 0 unless kHit (or off)
  Image<uint8_t> status;            // RayStatus
};

// Whether RaycastParams::simd marches AVX2 packets here (an x86-64 build on a CPU with AVX2).
bool RaycastSimdAvailable();

RaycastImages Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
                      const RaycastParams& params = {});
// The same, into images that are reused when their size matches the camera (no allocation per
// frame). An invalid camera gives empty images; a non-finite pose, all unobserved.
void Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
             const RaycastParams& params, RaycastImages& images);

}  // namespace voxplan
