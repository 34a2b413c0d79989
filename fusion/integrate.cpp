#include "fusion/integrate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>

#include "core/parallel.h"
#include "fusion/integrate_kernel.h"

namespace voxplan {

namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Visits the blocks a world-space segment passes through (Amanatides & Woo traversal in block
// units), so the band along one pixel ray costs a few steps instead of many point samples.
template <typename F>
void ForEachBlockOnSegment(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float inv_block,
                           F&& visit) {
  const Eigen::Vector3f pa = a * inv_block, pb = b * inv_block;
  int cell[3] = {FloorToInt(pa.x()), FloorToInt(pa.y()), FloorToInt(pa.z())};
  const int last[3] = {FloorToInt(pb.x()), FloorToInt(pb.y()), FloorToInt(pb.z())};
  const Eigen::Vector3f dir = pb - pa;
  int step[3];
  float t_max[3], t_delta[3];
  for (int k = 0; k < 3; ++k) {
    step[k] = dir[k] > 0 ? 1 : (dir[k] < 0 ? -1 : 0);
    if (step[k] == 0) {
      t_max[k] = t_delta[k] = std::numeric_limits<float>::infinity();
    } else {
      const float boundary = float(cell[k] + (step[k] > 0 ? 1 : 0));
      t_max[k] = (boundary - pa[k]) / dir[k];
      t_delta[k] = float(step[k]) / dir[k];
    }
  }
  // Bounded: a segment crosses at most |dx|+|dy|+|dz|+1 cells; guards against float drift.
  const int max_steps =
      std::abs(last[0] - cell[0]) + std::abs(last[1] - cell[1]) + std::abs(last[2] - cell[2]) + 1;
  for (int i = 0; i < max_steps; ++i) {
    visit(BlockIndex{cell[0], cell[1], cell[2]});
    if (cell[0] == last[0] && cell[1] == last[1] && cell[2] == last[2]) break;
    const int k =
        (t_max[0] < t_max[1]) ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    cell[k] += step[k];
    t_max[k] += t_delta[k];
  }
}

Status ValidateParams(const IntegrateParams& p) {
  if (!(p.min_depth_m >= 0.f && p.max_depth_m > p.min_depth_m && std::isfinite(p.max_depth_m)))
    return InvalidArgument("depth range must satisfy 0 <= min < max, got [" +
                           std::to_string(p.min_depth_m) + ", " + std::to_string(p.max_depth_m) +
                           "]");
  if (p.carve_free_space && !(p.carve_ray_spacing_blocks > 0.f))
    return InvalidArgument("carve ray spacing must be positive, got " +
                           std::to_string(p.carve_ray_spacing_blocks));
  if (!(p.max_weight > 0.f && p.max_weight <= kMaxWeight))
    return InvalidArgument("max weight must be in (0, " + std::to_string(kMaxWeight) + "], got " +
                           std::to_string(p.max_weight));
  return Status::Ok();
}

}  // namespace

bool SimdKernelAvailable() {
#if defined(__x86_64__)
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

Kernel ResolveKernel(Kernel requested) {
  if (requested == Kernel::kAuto) return SimdKernelAvailable() ? Kernel::kSimd : Kernel::kScalar;
  if (requested == Kernel::kSimd && !SimdKernelAvailable()) return Kernel::kScalar;
  return requested;
}

const char* KernelName(Kernel kernel) {
  switch (kernel) {
    case Kernel::kAuto:
      return "auto";
    case Kernel::kScalar:
      return "scalar";
    case Kernel::kSimd:
      return "avx2";
  }
  return "?";
}

namespace {

// Carving ray tiles: square, small enough that rays through neighbouring tile corners are at
// most carve_ray_spacing_blocks apart at max depth, and at most 64 pixels.
int CarveTileSide(const PinholeCamera& camera, const IntegrateParams& params,
                  const VolumeParams& volume_params) {
  const float f_min = std::min(std::abs(camera.fx), std::abs(camera.fy));
  const float block_m = volume_params.voxel_size_m * kBlockSide;
  const float side = params.carve_ray_spacing_blocks * block_m * f_min / params.max_depth_m;
  return std::clamp(int(side), 1, 64);
}

// Keys in, sorted blocks out.
std::vector<BlockIndex> SortedBlocks(std::vector<uint64_t>& keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<BlockIndex> blocks(keys.size());
  std::transform(keys.begin(), keys.end(), blocks.begin(), UnpackBlockIndex);
  std::sort(blocks.begin(), blocks.end());
  return blocks;
}

// Per-task key collection: neighbouring rays hit the same blocks, so a small direct-mapped
// cache drops most repeats before the global sort.
class KeyCollector {
 public:
  KeyCollector() : cache_(size_t(1) << kCacheBits, ~0ull) {}
  void Add(BlockIndex block) {
    if (!InPackRange(block)) return;
    const uint64_t key = PackBlockIndex(block);
    // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring blocks apart.
    uint64_t& slot = cache_[(key * 0x9E3779B97F4A7C15ull) >> (64 - kCacheBits)];
    if (slot == key) return;
    slot = key;
    keys_.push_back(key);
  }
  void MoveInto(std::vector<uint64_t>& keys, std::mutex& mutex) {
    std::lock_guard<std::mutex> lock(mutex);
    keys.insert(keys.end(), keys_.begin(), keys_.end());
  }

 private:
  static constexpr int kCacheBits = 10;
  std::vector<uint64_t> cache_;
  std::vector<uint64_t> keys_;
};

// The band of every valid pixel, or with `carve` everything from min depth through the band.
std::vector<BlockIndex> CollectBlocks(const DepthImage& depth, const PinholeCamera& camera,
                                      const Pose3f& T_W_C, const IntegrateParams& params,
                                      const VolumeParams& volume_params, bool carve) {
  const float trunc = volume_params.trunc_m;
  const float inv_block = 1.0f / (volume_params.voxel_size_m * kBlockSide);
  // Work in block units: a pixel's ray is dir(u, v) * z + origin, with dir linear in u and v.
  const Eigen::Matrix3f R_b = T_W_C.linear() * inv_block;
  const Eigen::Vector3f origin_b = T_W_C.translation() * inv_block;
  const Eigen::Vector3f du_b = R_b.col(0) / camera.fx;
  const Eigen::Vector3f dv_b = R_b.col(1) / camera.fy;
  const Eigen::Vector3f d0_b = R_b.col(2) - du_b * camera.cx - dv_b * camera.cy;

  std::vector<uint64_t> keys;
  std::mutex keys_mutex;
  if (carve) {
    // Carving: square pixel tiles small enough that rays through neighbouring tile corners
    // are at most carve_ray_spacing_blocks apart at max depth, so the pencil of pixel rays
    // between them is much thinner than a block. One ray per tile corner (shared by up to four
    // tiles) from min depth to the farthest valid depth of those tiles plus the truncation
    // covers the free space and the band of every pixel, instead of one band walk per pixel.
    const int tile = CarveTileSide(camera, params, volume_params);
    const int tiles_u = (depth.width + tile - 1) / tile, tiles_v = (depth.height + tile - 1) / tile;
    // Farthest valid depth per tile: first per column over the tile's rows (element-wise, so
    // it vectorises), then per tile over its columns.
    std::vector<float> tile_max(size_t(tiles_u) * size_t(tiles_v), 0.f);
    const float lo = params.min_depth_m, hi = params.max_depth_m;
    ParallelFor(size_t(tiles_v), 1, [&](size_t begin, size_t end) {
      std::vector<float> column_max(size_t(depth.width));
      for (size_t tv = begin; tv < end; ++tv) {
        std::fill(column_max.begin(), column_max.end(), 0.f);
        const int v0 = int(tv) * tile, v1 = std::min(depth.height, v0 + tile);
        for (int v = v0; v < v1; ++v) {
          const float* __restrict depth_row = &depth.data[size_t(v) * size_t(depth.width)];
          float* __restrict cm = column_max.data();
          for (int u = 0; u < depth.width; ++u) {
            const float d = depth_row[u];
            const float x = ((d >= lo) & (d <= hi)) ? d : 0.f;
            cm[u] = cm[u] > x ? cm[u] : x;
          }
        }
        for (int tu = 0; tu < tiles_u; ++tu) {
          const int u0 = tu * tile, u1 = std::min(depth.width, u0 + tile);
          tile_max[tv * size_t(tiles_u) + size_t(tu)] =
              *std::max_element(&column_max[size_t(u0)], &column_max[size_t(u1)]);
        }
      }
    });
    const float start = std::max(params.min_depth_m, 1e-3f);
    ParallelFor(size_t(tiles_v) + 1, 1, [&](size_t begin, size_t end) {
      KeyCollector collector;
      auto add = [&](BlockIndex b) { collector.Add(b); };
      for (size_t cv = begin; cv < end; ++cv) {
        // Corner row cv lies between tile rows cv - 1 and cv, at pixel edge v = cv * tile - 0.5.
        const float v = std::min(float(int(cv) * tile), float(depth.height)) - 0.5f;
        for (int cu = 0; cu <= tiles_u; ++cu) {
          float d_end = 0.f;
          for (int tv = int(cv) - 1; tv <= int(cv); ++tv)
            for (int tu = cu - 1; tu <= cu; ++tu)
              if (tv >= 0 && tv < tiles_v && tu >= 0 && tu < tiles_u)
                d_end = std::max(d_end, tile_max[size_t(tv) * size_t(tiles_u) + size_t(tu)]);
          if (d_end == 0.f) continue;
          const float u = std::min(float(cu * tile), float(depth.width)) - 0.5f;
          const Eigen::Vector3f dir_b = d0_b + du_b * u + dv_b * v;
          ForEachBlockOnSegment(dir_b * start + origin_b, dir_b * (d_end + trunc) + origin_b, 1.0f,
                                add);
        }
      }
      collector.MoveInto(keys, keys_mutex);
    });
    return SortedBlocks(keys);
  }

  constexpr size_t kRowsPerTask = 8;
  const size_t tasks = (size_t(depth.height) + kRowsPerTask - 1) / kRowsPerTask;
  ParallelFor(tasks, 1, [&](size_t begin, size_t end) {
    KeyCollector collector;
    auto add = [&](BlockIndex b) { collector.Add(b); };
    for (size_t task = begin; task < end; ++task) {
      const int v_end = std::min<int>(depth.height, int((task + 1) * kRowsPerTask));
      for (int v = int(task * kRowsPerTask); v < v_end; ++v) {
        const Eigen::Vector3f row_b = d0_b + dv_b * float(v);
        const float* depth_row = &depth.data[size_t(v) * size_t(depth.width)];
        BlockIndex prev_a{kMaxBlockCoord + 1, 0, 0}, prev_b = prev_a;
        for (int u = 0; u < depth.width; ++u) {
          const float d = depth_row[u];
          if (!(d >= params.min_depth_m && d <= params.max_depth_m)) continue;
          const Eigen::Vector3f dir_b = row_b + du_b * float(u);
          const Eigen::Vector3f a = dir_b * std::max(d - trunc, 1e-3f) + origin_b;
          const Eigen::Vector3f b = dir_b * (d + trunc) + origin_b;
          const BlockIndex ba{FloorToInt(a.x()), FloorToInt(a.y()), FloorToInt(a.z())};
          const BlockIndex bb{FloorToInt(b.x()), FloorToInt(b.y()), FloorToInt(b.z())};
          // Neighbouring pixels mostly start and end in the same blocks as the previous one.
          if (ba == prev_a && bb == prev_b) continue;
          prev_a = ba;
          prev_b = bb;
          // The band is one block long: mostly it stays in one block or crosses one face, and
          // then the traversal is exactly {ba, bb} without stepping through it.
          const int steps = std::abs(ba.x - bb.x) + std::abs(ba.y - bb.y) + std::abs(ba.z - bb.z);
          if (steps <= 1) {
            add(ba);
            if (steps == 1) add(bb);
          } else {
            ForEachBlockOnSegment(a, b, 1.0f, add);
          }
        }
      }
    }
    collector.MoveInto(keys, keys_mutex);
  });
  return SortedBlocks(keys);
}

}  // namespace

std::vector<BlockIndex> BlocksInTruncationBand(const DepthImage& depth, const PinholeCamera& camera,
                                               const Pose3f& T_W_C, const IntegrateParams& params,
                                               const VolumeParams& volume_params) {
  return CollectBlocks(depth, camera, T_W_C, params, volume_params, false);
}

std::vector<BlockIndex> BlocksToUpdate(const DepthImage& depth, const PinholeCamera& camera,
                                       const Pose3f& T_W_C, const IntegrateParams& params,
                                       const VolumeParams& volume_params) {
  return CollectBlocks(depth, camera, T_W_C, params, volume_params, params.carve_free_space);
}

Result<IntegrateStats> IntegrateFrame(const DepthImage& depth, const ColorImage& color,
                                      const PinholeCamera& camera, const Pose3f& T_W_C,
                                      const IntegrateParams& params, TsdfVolume& volume) {
  VOXPLAN_RETURN_IF_ERROR(ValidateParams(params));
  if (!camera.Valid()) return InvalidArgument("camera intrinsics are invalid");
  if (depth.width != camera.width || depth.height != camera.height)
    return InvalidArgument("depth image is " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + " but the camera is " +
                           std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!color.empty() && (color.width != depth.width || color.height != depth.height))
    return InvalidArgument("colour image size differs from the depth image size");
  if (!T_W_C.matrix().allFinite()) return InvalidArgument("camera pose has NaN or infinite values");

  IntegrateStats stats;
  auto t0 = std::chrono::steady_clock::now();
  std::vector<BlockIndex> band = BlocksToUpdate(depth, camera, T_W_C, params, volume.params());
  std::vector<TsdfBlock*> blocks(band.size());
  for (size_t i = 0; i < band.size(); ++i) {
    bool created = false;
    blocks[i] = &volume.FindOrAllocate(band[i], &created);
    stats.blocks_allocated += created ? 1 : 0;
  }
  stats.blocks_in_band = band.size();
  stats.allocate_ms = MsSince(t0);

  t0 = std::chrono::steady_clock::now();
  internal::FrameView f;
  f.depth = depth.data.data();
  f.color = (params.integrate_color && !color.empty()) ? color.data.data() : nullptr;
  f.width = depth.width;
  f.height = depth.height;
  f.fx = camera.fx;
  f.fy = camera.fy;
  f.cx = camera.cx;
  f.cy = camera.cy;
  const Pose3f T_C_W = T_W_C.inverse();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) f.r[3 * r + c] = T_C_W.linear()(r, c);
    f.t[r] = T_C_W.translation()[r];
  }
  f.min_depth_m = params.min_depth_m;
  f.max_depth_m = params.max_depth_m;
  f.trunc_m = volume.trunc_m();
  f.inv_trunc = 1.0f / volume.trunc_m();
  f.voxel_size_m = volume.voxel_size_m();
  f.max_weight = params.max_weight;
  f.depth_weighting = params.weighting == Weighting::kDepthDependent;

  const auto kernel = ResolveKernel(params.kernel) == Kernel::kSimd
                          ? internal::IntegrateBlockSimd
                          : internal::IntegrateBlockScalar;
  ParallelFor(band.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) kernel(f, band[i], *blocks[i]);
  });
  stats.update_ms = MsSince(t0);
  // Branch-free, so it vectorises.
  uint32_t valid = 0;
  for (float d : depth.data)
    valid += uint32_t(d >= params.min_depth_m) & uint32_t(d <= params.max_depth_m);
  stats.valid_pixels = valid;
  stats.touched_blocks = std::move(band);
  return stats;
}

}  // namespace voxplan
