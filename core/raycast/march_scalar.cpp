// The scalar reference march: rays a sample at a time, four interleaved so that their memory
// latencies overlap, each sign change refined on the trilinear interpolant (Refine, shared with
// the packet march's fallback). march_avx2.cpp must give the same bytes.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "core/raycast/march.h"

namespace voxplan::raycast_detail {
namespace {

constexpr int kLanes = 4;  // rays the scalar march interleaves

// The scalar march (MarchInterleaved, a sample per Step); crossings go to RayCaster::Cross.
class ScalarCaster : public RayCaster {
 public:
  ScalarCaster(const TsdfVolume& volume, const RaycastParams& params,
               const Eigen::Vector3f& origin_W, const Eigen::Vector3f& d0_W,
               const Eigen::Vector3f& du_W, const Eigen::Vector3f& dv_W)
      : RayCaster(volume, params, origin_W, d0_W, du_W, dv_W) {
#if VOXPLAN_RAYCAST_SSE2
    origin_vox_lanes_ = _mm_set_ps(0.f, origin_vox_.z(), origin_vox_.y(), origin_vox_.x());
#endif
  }

  void March(const RayTask* tasks, size_t num_tasks, const BatchWriter& write) override {
    MarchInterleaved(tasks, num_tasks, write);
  }

 private:
  // Takes one sample of the nearest voxel; true when the ray is finished and ray.result final.
  // A sign change from positive to negative is refined on the trilinear interpolant.
  bool Step(Ray& ray) {
    if (!(ray.z <= ray.z_end)) return true;
#if VOXPLAN_RAYCAST_SSE2
    // The sample's voxel in SSE2 lanes (x, y, z, 0): the same products, sums and floors.
    const __m128 p = _mm_add_ps(origin_vox_lanes_, _mm_mul_ps(_mm_set1_ps(ray.z), ray.dir_vox));
    const __m128i truncated = _mm_cvttps_epi32(p);
    const __m128i g =
        _mm_add_epi32(truncated, _mm_castps_si128(_mm_cmplt_ps(p, _mm_cvtepi32_ps(truncated))));
    const __m128i b_lanes = _mm_srai_epi32(g, kBlockShift);
    // Each ray keeps its own last block: interleaved rays would evict a shared one.
    if (_mm_movemask_epi8(_mm_cmpeq_epi32(b_lanes, ray.block_lanes)) != 0xffff) {
      ray.block_lanes = b_lanes;
      alignas(16) int32_t v[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(v), b_lanes);
      ray.block_index = BlockIndex{v[0], v[1], v[2]};
      ray.block = sampler_.Find(ray.block_index);
    }
#else
    const Eigen::Vector3f p = origin_vox_ + ray.z * ray.dir_vox;
    const GlobalVoxelIndex g{FloorToInt(p.x()), FloorToInt(p.y()), FloorToInt(p.z())};
    if (!SameBlock(BlockOf(g), ray.block_index)) {
      ray.block_index = BlockOf(g);
      ray.block = sampler_.Find(ray.block_index);
    }
#endif
    const TsdfBlock* block = ray.block;
    if (!block) {
      // Jump to where the ray leaves this unallocated block (nudged past the face).
      const float block_m = sampler_.voxel_m() * kBlockSide;
      const BlockIndex& b = ray.block_index;
      float z_exit = std::numeric_limits<float>::infinity();
      for (int a = 0; a < 3; ++a) {
        const float d = ray.dir_W[a];
        if (d == 0.f) continue;  // never leaves through this axis' faces
        const int32_t face = (&b.x)[a] + (d > 0.f ? 1 : 0);
        z_exit = std::min(z_exit, (float(face) * block_m - origin_W_[a]) / d);
      }
      ray.z = std::max(z_exit, ray.z) + 0.01f * ray.voxel_z;
      ray.have_prev = false;
      return false;
    }
#if VOXPLAN_RAYCAST_SSE2
    // LinearIndex as a multiply-add of 16-bit halves (the high halves are zero).
    const __m128i terms = _mm_madd_epi16(_mm_and_si128(g, _mm_set1_epi32(kBlockMask)),
                                         _mm_set_epi32(0, kBlockSide * kBlockSide, kBlockSide, 1));
    const __m128i pairs = _mm_add_epi32(terms, _mm_srli_si128(terms, 8));
    const int i = _mm_cvtsi128_si32(_mm_add_epi32(pairs, _mm_srli_si128(pairs, 4)));
#else
    const int i = LinearIndex(LocalOf(g));
#endif
    if (!sampler_.Observed(*block, i)) {
      ray.z += ray.voxel_z;
      ray.have_prev = false;
      return false;
    }
    ray.result.status = RayStatus::kFree;  // at least: an observed voxel was met
    const int16_t tsdf = block->tsdf[i];
    if (tsdf == 0 && ray.have_prev && ray.prev_tsdf > 0) {
      // On the surface after a positive sample, which stays the crossing's start: a run of
      // zeros along a grazing ray can end where the interpolant is well past its zero.
      ray.z += ray.voxel_z;
      return false;
    }
    if (ray.have_prev && (ray.prev_tsdf >= 0) != (tsdf >= 0)) {
      if (tsdf >= 0) {  // back face: entered from behind a surface
        if (params_.stop_at_back_faces) return true;
        ray.have_prev = false;  // march on into the free space beyond
        ray.z += ray.voxel_z;
        return false;
      }
      if (Cross(ray.dir_W, ray.prev_z, ray.z, ray.prev_tsdf, tsdf, ray.voxel_z, &ray.result))
        return true;
      // The nearest values disagree with the interpolant (noise): keep marching.
    }
    ray.have_prev = true;
    ray.prev_z = ray.z;
    ray.prev_tsdf = tsdf;
    ray.z += std::max(float(tsdf) * ray.step_scale_z, ray.voxel_z);
    return false;
  }

  // Marches the tasks' rays a sample at a time, kLanes of them interleaved so that their memory
  // latencies overlap; write(pixel, result, dir_W) receives each ray's result.
  void MarchInterleaved(const RayTask* tasks, size_t num_tasks, const BatchWriter& write) {
    size_t next = 0;
    auto start_next = [&](Ray* ray) {
      if (next == num_tasks) return false;
      const RayTask& task = tasks[next++];
      Start(Direction(task), task.z_begin, task.z_end, ray);
      ray->z_skipped = task.z_skipped;
      ray->z_begin = task.z_begin;
      ray->pixel = task.pixel;
      return true;
    };
    Ray rays[kLanes];
    bool live[kLanes];
    int num_live = 0;
    for (int l = 0; l < kLanes; ++l) num_live += (live[l] = start_next(&rays[l]));
    while (num_live > 0)
      for (int l = 0; l < kLanes; ++l) {
        if (!live[l] || !Step(rays[l])) continue;
        if (rays[l].result.status == RayStatus::kUnobserved && rays[l].z_skipped >= 0.f) {
          Start(rays[l].dir_W, rays[l].z_skipped, rays[l].z_begin, &rays[l]);
          rays[l].z_skipped = -1.f;
          continue;
        }
        write(rays[l].pixel, rays[l].result, rays[l].dir_W);
        if (!start_next(&rays[l])) live[l] = false, --num_live;
      }
  }

#if VOXPLAN_RAYCAST_SSE2
  __m128 origin_vox_lanes_;
#endif
};

}  // namespace

bool RayCaster::Sample(const Eigen::Vector3f& dir_W, float z, Cell* cell, float* tsdf,
                       Eigen::Vector3f* gradient) {
  const bool complete = sampler_.Gather(origin_W_ + z * dir_W, cell);
  *tsdf = cell->ValueAndGradient(gradient);
  return complete;
}

// The nearest voxels changed sign between z_a (value nearest_a >= 0) and z_b (nearest_b < 0).
// Finds the zero of the trilinear interpolant: Newton steps from the linear guess (the cell
// gradient comes with the values, and the second step usually reuses the cell), else a
// bracket moved until it straddles a zero and narrowed by regula falsi. Returns false when
// the interpolant has no zero here. Without `newton`, straight to the bracket: for a caller
// whose Newton steps (the same as these) left their path.
bool RayCaster::Refine(const Eigen::Vector3f& dir_W, float z_a, float z_b, float nearest_a,
                       float nearest_b, float voxel_z, RayResult* result, bool newton) {
  Cell cell;
  const float z_guess = z_a + (z_b - z_a) * nearest_a / (nearest_a - nearest_b);
  // The slope of the normalised TSDF along the ray must be clearly negative: a head-on ray
  // sees -voxel/trunc per voxel, a grazing one almost nothing.
  const float max_slope = MaxSlope();
  const float dq_dz = sampler_.inv_voxel();  // voxel-grid units per metre of z
  float z = z_guess;
  Eigen::Vector3f gradient;
  bool converged = false;
  for (int k = 0; newton && k < kNewtonIterations; ++k) {
    float f = 0.f;
    if (!Sample(dir_W, z, &cell, &f, &gradient)) break;
    const float slope = gradient.dot(dir_W) * dq_dz;  // per metre of z
    if (!(slope * voxel_z < max_slope)) break;
    const float dz = -f / slope;
    if (!(z + dz > z_a - voxel_z && z + dz < z_b + voxel_z)) break;
    // The last step is not re-sampled: the gradient and colour barely change over it.
    z += dz;
    if (k + 1 == kNewtonIterations || std::abs(dz) < kConvergedVoxels * voxel_z) {
      converged = true;
      break;
    }
  }
  if (!converged) {
    if (!Bracket(dir_W, z_a, z_b, voxel_z, &cell, &z)) {
      if (cell.loaded && cell.complete()) return false;
      // Unobserved corners around the crossing: the nearest values are all there is.
      z = z_guess;
    }
    float f = 0.f;
    Sample(dir_W, z, &cell, &f, &gradient);  // the cell at the final point
  }
  result->status = RayStatus::kHit;
  result->z = z;
  if (params_.with_normals) {
    const float norm = gradient.norm();
    result->normal_W =
        norm > 0.f ? Eigen::Vector3f(gradient / norm) : Eigen::Vector3f(kNaN, kNaN, kNaN);
  }
  if (params_.with_color) result->color = CellColor(cell);
  return true;
}

// Regula falsi on the trilinear interpolant. False when a cell is incomplete (`cell` then
// holds it) or no zero is bracketed within kMaxBracketShifts voxels.
bool RayCaster::Bracket(const Eigen::Vector3f& dir_W, float z_a, float z_b, float voxel_z,
                        Cell* cell, float* z_out) {
  float f_a = 0.f, f_b = 0.f;
  Eigen::Vector3f gradient;  // unused here
  auto sample = [&](float z, float* f) { return Sample(dir_W, z, cell, f, &gradient); };
  if (!sample(z_a, &f_a) || !sample(z_b, &f_b)) return false;
  for (int k = 0; f_a < 0.f && k < kMaxBracketShifts; ++k) {
    z_b = z_a, f_b = f_a;
    z_a -= voxel_z;
    if (!sample(z_a, &f_a)) return false;
  }
  for (int k = 0; f_b >= 0.f && k < kMaxBracketShifts; ++k) {
    z_a = z_b, f_a = f_b;
    z_b += voxel_z;
    if (!sample(z_b, &f_b)) return false;
  }
  if (!(f_a >= 0.f && f_b < 0.f)) return false;
  for (int k = 0; k < kSecantIterations; ++k) {
    const float z = z_a + (z_b - z_a) * f_a / (f_a - f_b);
    float f = 0.f;
    if (!sample(z, &f)) break;
    if (f >= 0.f)
      z_a = z, f_a = f;
    else
      z_b = z, f_b = f;
  }
  *z_out = z_a + (z_b - z_a) * f_a / (f_a - f_b);
  return true;
}

std::unique_ptr<RayCaster> MakeScalarCaster(const TsdfVolume& volume, const RaycastParams& params,
                                            const Eigen::Vector3f& origin_W,
                                            const Eigen::Vector3f& d0_W,
                                            const Eigen::Vector3f& du_W,
                                            const Eigen::Vector3f& dv_W) {
  return std::make_unique<ScalarCaster>(volume, params, origin_W, d0_W, du_W, dv_W);
}

}  // namespace voxplan::raycast_detail
