#pragma once
// Internal to core/raycast/: what the two marches share: one ray's march state, and the
// caster both derive from (the worker's sampler, the rays' geometry, the scalar refinement of a
// crossing that the packet march falls back to), made by MakeScalarCaster or MakePacketCaster.
#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/block.h"
#include "core/index.h"
#include "core/raycast.h"
#include "core/raycast/raycast_internal.h"
#include "core/raycast/raycast_kernels.h"
#include "core/raycast/sampler.h"
#include "core/volume.h"

namespace voxplan::raycast_detail {

// One ray's march, advanced a sample at a time so that a worker can interleave several rays
// and overlap their memory latency. The ray is p(z) = origin + z * dir_W, with dir_W the
// camera ray scaled to unit optical depth, so z is the depth itself.
struct Ray {
#if VOXPLAN_RAYCAST_SSE2
  __m128 dir_vox;       // the ray in voxel units, lanes (x, y, z, 0)
  __m128i block_lanes;  // block_index in lanes (x, y, z, 0)
#else
  Eigen::Vector3f dir_vox;  // the ray in voxel units: p = origin_vox + z * dir_vox
#endif
  Eigen::Vector3f dir_W;
  float z = 0.f, z_end = 0.f;
  float voxel_z = 0.f;       // one voxel along the ray, in depth units
  float step_scale_z = 0.f;  // stored fixed-point TSDF to a step in depth units
  bool have_prev = false;    // previous sample observed, nothing unobserved since
  BlockIndex block_index{kMaxBlockCoord + 1, 0, 0};  // the last block this ray sampled
  const TsdfBlock* block = nullptr;
  float prev_z = 0.f;
  int16_t prev_tsdf = 0;
  size_t pixel = 0;
  float z_skipped = -1.f;  // as RayTask's
  float z_begin = 0.f;     // where the march began
  RayResult result;
};

// One worker's caster, kept over its batches (the block cache, the packet march's buffers).
class RayCaster {
 public:
  // Rays start at origin_W; the ray through pixel (u, v) is d0_W + u du_W + v dv_W.
  RayCaster(const TsdfVolume& volume, const RaycastParams& params, const Eigen::Vector3f& origin_W,
            const Eigen::Vector3f& d0_W, const Eigen::Vector3f& du_W, const Eigen::Vector3f& dv_W)
      : sampler_(volume, params),
        params_(params),
        origin_W_(origin_W),
        d0_W_(d0_W),
        du_W_(du_W),
        dv_W_(dv_W),
        origin_vox_(origin_W * sampler_.inv_voxel()),
        step_scale_(kStepScale * volume.trunc_m() / kTsdfScale) {}
  virtual ~RayCaster() = default;

  // Marches the tasks' rays; write(pixel, result, dir_W) receives each ray's result. One
  // virtual call per batch of rays: the calls per sample stay inside the march's own file.
  virtual void March(const RayTask* tasks, size_t num_tasks, const BatchWriter& write) = 0;

 protected:
  Eigen::Vector3f Direction(const RayTask& task) const {
    return d0_W_ + float(task.u) * du_W_ + float(task.v) * dv_W_;
  }

  // Starts marching the ray p(z) = origin + z * dir_W from z_begin to z_end.
  void Start(const Eigen::Vector3f& dir_W, float z_begin, float z_end, Ray* ray) const {
    const float inv_norm = 1.f / std::sqrt(dir_W.squaredNorm());
    ray->dir_W = dir_W;
    ray->z = z_begin;
    ray->z_end = z_end;
    ray->voxel_z = sampler_.voxel_m() * inv_norm;
    ray->step_scale_z = step_scale_ * inv_norm;
    ray->have_prev = false;
    ray->block_index = BlockIndex{kMaxBlockCoord + 1, 0, 0};
    ray->block = nullptr;
    ray->result = RayResult{};
#if VOXPLAN_RAYCAST_SSE2
    const Eigen::Vector3f dir_vox = dir_W * sampler_.inv_voxel();
    ray->dir_vox = _mm_set_ps(0.f, dir_vox.z(), dir_vox.y(), dir_vox.x());
    ray->block_lanes = _mm_set_epi32(0, 0, 0, ray->block_index.x);
#else
    ray->dir_vox = dir_W * sampler_.inv_voxel();
#endif
  }

  // The least steep slope of the normalised TSDF per voxel along a ray that Newton steps follow
  // (Refine and RefineCrossings alike).
  float MaxSlope() const { return -kMinSlopeFraction * sampler_.voxel_m() / sampler_.trunc_m(); }

  // The nearest voxels changed sign from tsdf_a >= 0 at z_a to tsdf_b < 0 at z_b: true with
  // the refined hit (or kFree when it lies outside the depth limits), false when the
  // interpolant has no zero there. Both marches call it; inline, as Refine is not.
  bool Cross(const Eigen::Vector3f& dir_W, float z_a, float z_b, int16_t tsdf_a, int16_t tsdf_b,
             float voxel_z, RayResult* result, bool newton = true) {
    if (!Refine(dir_W, z_a, z_b, DecodeTsdf(tsdf_a), DecodeTsdf(tsdf_b), voxel_z, result, newton))
      return false;
    if (result->z < params_.min_depth_m || result->z > params_.max_depth_m) {
      *result = RayResult{};
      result->status = RayStatus::kFree;
    }
    return true;
  }

  // The scalar refinement of a crossing (march_scalar.cpp, with the details).
  bool Refine(const Eigen::Vector3f& dir_W, float z_a, float z_b, float nearest_a, float nearest_b,
              float voxel_z, RayResult* result, bool newton);
  bool Bracket(const Eigen::Vector3f& dir_W, float z_a, float z_b, float voxel_z, Cell* cell,
               float* z_out);
  bool Sample(const Eigen::Vector3f& dir_W, float z, Cell* cell, float* tsdf,
              Eigen::Vector3f* gradient);

  Sampler sampler_;
  RaycastParams params_;
  Eigen::Vector3f origin_W_, d0_W_, du_W_, dv_W_, origin_vox_;
  float step_scale_;  // stored fixed-point TSDF to a step in metres along the ray
};

// The scalar reference march (march_scalar.cpp) and the AVX2 packet march (march_avx2.cpp;
// where it is not built, the scalar one), which give identical images.
std::unique_ptr<RayCaster> MakeScalarCaster(const TsdfVolume& volume, const RaycastParams& params,
                                            const Eigen::Vector3f& origin_W,
                                            const Eigen::Vector3f& d0_W,
                                            const Eigen::Vector3f& du_W,
                                            const Eigen::Vector3f& dv_W);
std::unique_ptr<RayCaster> MakePacketCaster(const TsdfVolume& volume, const RaycastParams& params,
                                            const Eigen::Vector3f& origin_W,
                                            const Eigen::Vector3f& d0_W,
                                            const Eigen::Vector3f& du_W,
                                            const Eigen::Vector3f& dv_W);

}  // namespace voxplan::raycast_detail
