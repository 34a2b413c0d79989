#include "fusion/integrate.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>
#include <utility>

#include "core/bounds.h"
#include "core/parallel.h"
#include "core/stopwatch.h"
#include "fusion/integrate_kernel.h"
#include "fusion/integrate_view.h"

namespace voxplan {

namespace {

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

}  // namespace

Status IntegrateParams::Validate() const {
  VOXPLAN_RETURN_IF_ERROR(
      bounds::CheckRange("min depth", min_depth_m, 0.0, bounds::kDepthMaxM, "m"));
  VOXPLAN_RETURN_IF_ERROR(
      bounds::CheckRange("max depth", max_depth_m, 0.0, bounds::kDepthMaxM, "m"));
  if (!(max_depth_m > min_depth_m))
    return InvalidArgument("depth range must satisfy min < max, got [" +
                           std::to_string(min_depth_m) + ", " + std::to_string(max_depth_m) + "]");
  if (carve_free_space)
    VOXPLAN_RETURN_IF_ERROR(
        bounds::CheckRange("carve ray spacing", carve_ray_spacing_blocks, 0.01, 16.0, "blocks"));
  // The range is (0, kMaxWeight]: 0 itself is refused below.
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("max weight", max_weight, 0.0, kMaxWeight));
  if (max_weight == 0.f) return InvalidArgument("max weight must be positive");
  if (shard.ranks < 1 || shard.ranks > kMaxShardRanks || shard.rank >= shard.ranks)
    return InvalidArgument("shard rank " + std::to_string(shard.rank) + " of " +
                           std::to_string(shard.ranks) + " ranks is out of range (1 to " +
                           std::to_string(kMaxShardRanks) + " ranks)");
  return Status::Ok();
}

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

// The farthest reading that clears the free space in front of max depth (readings beyond max
// depth up to it, so every finite one), or 0: none clears.
float ClearDepth(const IntegrateParams& params) {
  return params.carve_free_space && params.clear_beyond_max_depth
             ? std::numeric_limits<float>::max()
             : 0.f;
}

// Carving ray tiles: square, small enough that rays through neighbouring tile corners are at
// most carve_ray_spacing_blocks apart at max depth, and at most 64 pixels.
int CarveTileSide(const PinholeCamera& camera, const IntegrateParams& params,
                  const VolumeParams& volume_params) {
  const float f_min = std::min(std::abs(camera.fx), std::abs(camera.fy));
  const float block_m = volume_params.voxel_size_m * kBlockSide;
  const float side = params.carve_ray_spacing_blocks * block_m * f_min / params.max_depth_m;
  return std::clamp(int(side), 1, 64);
}

// Block keys whose integer order is BlockIndex order (z, then y, then x): one sort of the keys
// gives the sorted blocks. Coordinates are offset into [1, 2^21) (InPackRange).
constexpr int32_t kKeyOffset = 1 << 20;
constexpr uint64_t OrderedKey(BlockIndex b) {
  return (uint64_t(b.z + kKeyOffset) << 42) | (uint64_t(b.y + kKeyOffset) << 21) |
         uint64_t(b.x + kKeyOffset);
}
constexpr BlockIndex FromOrderedKey(uint64_t k) {
  constexpr uint64_t m = (uint64_t(1) << 21) - 1;
  return {int32_t(k & m) - kKeyOffset, int32_t((k >> 21) & m) - kKeyOffset,
          int32_t(k >> 42) - kKeyOffset};
}

// Sorted runs of keys in (one per task, without duplicates), sorted blocks out. Their tasks
// already sorted them, so they are merged pairwise, the pairs of a round in parallel.
std::vector<BlockIndex> MergeToSortedBlocks(std::vector<std::vector<uint64_t>>& runs) {
  while (runs.size() > 1) {
    std::vector<std::vector<uint64_t>> merged((runs.size() + 1) / 2);
    ParallelFor(runs.size() / 2, 1, [&](size_t begin, size_t end) {
      for (size_t pair = begin; pair < end; ++pair) {
        const auto& x = runs[2 * pair];
        const auto& y = runs[2 * pair + 1];
        std::vector<uint64_t>& out = merged[pair];
        out.resize(x.size() + y.size());
        out.erase(std::set_union(x.begin(), x.end(), y.begin(), y.end(), out.begin()), out.end());
      }
    });
    if (runs.size() % 2) merged.back() = std::move(runs.back());
    runs = std::move(merged);
  }
  std::vector<BlockIndex> blocks;
  if (runs.empty()) return blocks;
  blocks.resize(runs[0].size());
  std::transform(runs[0].begin(), runs[0].end(), blocks.begin(), FromOrderedKey);
  return blocks;
}

// Per-task key collection: neighbouring rays hit the same blocks, so a direct-mapped cache
// drops most repeats; the task then sorts its keys into a run for MergeToSortedBlocks.
class KeyCollector {
 public:
  KeyCollector() : cache_(size_t(1) << kCacheBits, ~0ull) {}
  void Add(BlockIndex block) {
    if (!InPackRange(block)) return;
    const uint64_t key = OrderedKey(block);
    // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring blocks apart.
    uint64_t& slot = cache_[(key * 0x9E3779B97F4A7C15ull) >> (64 - kCacheBits)];
    if (slot == key) return;
    slot = key;
    keys_.push_back(key);
  }
  void MoveInto(std::vector<std::vector<uint64_t>>& runs, std::mutex& mutex) {
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
    std::lock_guard<std::mutex> lock(mutex);
    runs.push_back(std::move(keys_));
  }

 private:
  static constexpr int kCacheBits = 12;  // 32 KiB: fits the L1/L2 cache
  std::vector<uint64_t> cache_;
  std::vector<uint64_t> keys_;
};

// Pairs of band end blocks seen lately: a direct-mapped cache, so a pair may be forgotten (and
// walked again), never wrongly remembered.
class EndPairCache {
 public:
  EndPairCache() : slots_(size_t(1) << kBits) {}
  void Clear() { std::fill(slots_.begin(), slots_.end(), Slot{}); }
  // False when the pair is in the cache; else remembers it.
  bool Insert(BlockIndex a, BlockIndex b) {
    if (!InPackRange(a) || !InPackRange(b)) return true;
    const uint64_t ka = OrderedKey(a), kb = OrderedKey(b);
    Slot& slot =
        slots_[((ka * 0x9E3779B97F4A7C15ull) ^ (kb * 0xC2B2AE3D27D4EB4Full)) >> (64 - kBits)];
    if (slot.a == ka && slot.b == kb) return false;
    slot = {ka, kb};
    return true;
  }

 private:
  static constexpr int kBits = 10;
  struct Slot {
    uint64_t a = ~0ull, b = ~0ull;  // never a key: keys use 63 bits
  };
  std::vector<Slot> slots_;
};

// The band of every valid pixel, or with `carve` everything from min depth through the band.
// [begin, end) of `units` work units: part `part.rank` of `part.ranks` equal shares in order.
std::pair<size_t, size_t> ShareOf(size_t units, const ShardSpec& part) {
  return {units * part.rank / part.ranks, units * (part.rank + 1) / part.ranks};
}

// With `part`, only that share of the image's work units (row tasks; with carving, corner rows)
// is walked: the union of every part's blocks is the whole set.
std::vector<BlockIndex> CollectBlocks(ImageView<float> depth, const PinholeCamera& camera,
                                      const Pose3f& T_W_C, const IntegrateParams& params,
                                      const VolumeParams& volume_params, bool carve,
                                      size_t* valid_pixels = nullptr, const ShardSpec& part = {}) {
  const float trunc = volume_params.trunc_m;
  const float inv_block = 1.0f / (volume_params.voxel_size_m * kBlockSide);
  // Work in block units: a pixel's ray is dir(u, v) * z + origin, with dir linear in u and v.
  const Eigen::Matrix3f R_b = T_W_C.linear() * inv_block;
  const Eigen::Vector3f origin_b = T_W_C.translation() * inv_block;
  const Eigen::Vector3f du_b = R_b.col(0) / camera.fx;
  const Eigen::Vector3f dv_b = R_b.col(1) / camera.fy;
  const Eigen::Vector3f d0_b = R_b.col(2) - du_b * camera.cx - dv_b * camera.cy;

  std::vector<std::vector<uint64_t>> runs;
  std::mutex runs_mutex;
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
    // A reading beyond max depth that clears carves up to max depth.
    const float clear = ClearDepth(params);
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
            const float x = ((d >= lo) & (d <= hi)) ? d : ((d >= lo) & (d <= clear)) ? hi : 0.f;
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
    // Plain variables, not a structured binding: clang 14 cannot capture those in a lambda.
    const std::pair<size_t, size_t> corner_rows = ShareOf(size_t(tiles_v) + 1, part);
    const size_t first_corner_row = corner_rows.first, end_corner_row = corner_rows.second;
    ParallelFor(end_corner_row - first_corner_row, 1, [&](size_t begin, size_t end) {
      KeyCollector collector;
      auto add = [&](BlockIndex b) { collector.Add(b); };
      for (size_t cv = first_corner_row + begin; cv < first_corner_row + end; ++cv) {
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
      collector.MoveInto(runs, runs_mutex);
    });
    return MergeToSortedBlocks(runs);
  }

  // Per row, a filter (exact, SIMD where available) keeps the pixels whose band end blocks
  // differ from their left neighbour's; only those walk their band.
  const auto candidates = ResolveKernel(params.kernel) == Kernel::kSimd
                              ? internal::BandRowCandidatesSimd
                              : internal::BandRowCandidatesScalar;
  constexpr size_t kRowsPerTask = 16;
  const size_t tasks = (size_t(depth.height) + kRowsPerTask - 1) / kRowsPerTask;
  const std::pair<size_t, size_t> share = ShareOf(tasks, part);
  const size_t first_task = share.first, end_task = share.second;
  ParallelFor(end_task - first_task, 1, [&](size_t share_begin, size_t share_end) {
    const size_t begin = first_task + share_begin, end = first_task + share_end;
    KeyCollector collector;
    auto add = [&](BlockIndex b) { collector.Add(b); };
    EndPairCache walked;
    std::vector<internal::BandCandidate> kept(size_t(depth.width));
    size_t task_valid = 0;
    internal::BandRow row;
    row.width = depth.width;
    row.trunc_m = trunc;
    row.min_depth_m = params.min_depth_m;
    row.max_depth_m = params.max_depth_m;
    for (int k = 0; k < 3; ++k) {
      row.du[k] = du_b[k];
      row.origin[k] = origin_b[k];
    }
    for (size_t task = begin; task < end; ++task) {
      // Rows below one another mostly repeat the bands' end blocks: a pair of end blocks already
      // walked in this task (as the row filter does along a row) is not walked again. Per task,
      // so that the result does not depend on how tasks are split among threads.
      walked.Clear();
      const int v_end = std::min<int>(depth.height, int((task + 1) * kRowsPerTask));
      for (int v = int(task * kRowsPerTask); v < v_end; ++v) {
        const Eigen::Vector3f row_b = d0_b + dv_b * float(v);
        for (int k = 0; k < 3; ++k) row.row[k] = row_b[k];
        row.depth = &depth.data[size_t(v) * size_t(depth.width)];
        const int n = candidates(row, kept.data(), &task_valid);
        for (int i = 0; i < n; ++i) {
          const internal::BandCandidate& c = kept[size_t(i)];
          const BlockIndex ba{FloorToInt(c.a[0]), FloorToInt(c.a[1]), FloorToInt(c.a[2])};
          const BlockIndex bb{FloorToInt(c.b[0]), FloorToInt(c.b[1]), FloorToInt(c.b[2])};
          if (!walked.Insert(ba, bb)) continue;
          // The band is about a block long at 1 cm voxels: mostly it stays in one block or
          // crosses one face, and then the traversal is exactly {ba, bb} without stepping.
          const int steps = std::abs(ba.x - bb.x) + std::abs(ba.y - bb.y) + std::abs(ba.z - bb.z);
          if (steps <= 1) {
            add(ba);
            if (steps == 1) add(bb);
          } else {
            ForEachBlockOnSegment(Eigen::Vector3f(c.a[0], c.a[1], c.a[2]),
                                  Eigen::Vector3f(c.b[0], c.b[1], c.b[2]), 1.0f, add);
          }
        }
      }
    }
    if (valid_pixels) {
      std::lock_guard<std::mutex> lock(runs_mutex);
      *valid_pixels += task_valid;
    }
    collector.MoveInto(runs, runs_mutex);
  });
  return MergeToSortedBlocks(runs);
}

// Past the memory budget: keeps the blocks that exist (in band order), so the update and the
// touched list skip the refused ones.
void DropRefused(std::vector<BlockIndex>& band, std::vector<TsdfBlock*>& blocks) {
  size_t kept = 0;
  for (size_t i = 0; i < band.size(); ++i) {
    if (!blocks[i]) continue;
    band[kept] = band[i];
    blocks[kept] = blocks[i];
    ++kept;
  }
  band.resize(kept);
  blocks.resize(kept);
}

}  // namespace

std::vector<BlockIndex> BlocksInTruncationBand(const DepthImage& depth, const PinholeCamera& camera,
                                               const Pose3f& T_W_C, const IntegrateParams& params,
                                               const VolumeParams& volume_params) {
  return CollectBlocks(ViewOf(depth), camera, T_W_C, params, volume_params, false);
}

std::vector<BlockIndex> BlocksToUpdate(const DepthImage& depth, const PinholeCamera& camera,
                                       const Pose3f& T_W_C, const IntegrateParams& params,
                                       const VolumeParams& volume_params) {
  return CollectBlocks(ViewOf(depth), camera, T_W_C, params, volume_params,
                       params.carve_free_space);
}

Result<IntegrateStats> IntegrateFrame(const DepthImage& depth, const ColorImage& color,
                                      const PinholeCamera& camera, const Pose3f& T_W_C,
                                      const IntegrateParams& params, TsdfVolume& volume) {
  return IntegrateFrame(ViewOf(depth), ViewOf(color), camera, T_W_C, params, volume);
}

Result<IntegrateStats> IntegrateFrame(ImageView<float> depth, ImageView<uint32_t> color,
                                      const PinholeCamera& camera, const Pose3f& T_W_C,
                                      const IntegrateParams& params, TsdfVolume& volume) {
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  VOXPLAN_RETURN_IF_ERROR(volume.params().Validate());
  if (!camera.Valid()) return InvalidArgument("camera intrinsics are invalid");
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckIntrinsics(camera));
  if (depth.width != camera.width || depth.height != camera.height)
    return InvalidArgument("depth image is " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + " but the camera is " +
                           std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!color.empty() && (color.width != depth.width || color.height != depth.height))
    return InvalidArgument("colour image size differs from the depth image size");
  if (depth.empty()) return InvalidArgument("depth image has no pixels");
  if (!T_W_C.matrix().allFinite()) return InvalidArgument("camera pose has NaN or infinite values");

  IntegrateStats stats;
  Stopwatch clock;
  size_t valid_pixels = 0;
  std::vector<BlockIndex> band;
  size_t* const count_valid = params.carve_free_space ? nullptr : &valid_pixels;
  if (params.band_exchange && !params.shard.whole()) {
    // This rank's share of the walk, then every rank's finds that it owns.
    const std::vector<BlockIndex> walked =
        CollectBlocks(depth, camera, T_W_C, params, volume.params(), params.carve_free_space,
                      count_valid, params.shard);
    stats.collect_ms = clock.ElapsedMs();
    Result<std::vector<BlockIndex>> owned = params.band_exchange->Exchange(walked);
    if (!owned.ok()) return owned.status();
    band = std::move(*owned);
    stats.exchange_ms = clock.ElapsedMs() - stats.collect_ms;
  } else {
    band = CollectBlocks(depth, camera, T_W_C, params, volume.params(), params.carve_free_space,
                         count_valid);
    if (!params.shard.whole())
      band.erase(std::remove_if(band.begin(), band.end(),
                                [&](BlockIndex b) { return !params.shard.Owns(b); }),
                 band.end());
    stats.collect_ms = clock.ElapsedMs();
  }
  // Look the blocks up in parallel (concurrent finds are safe); only the missing ones are
  // allocated, serially, in band order.
  std::vector<TsdfBlock*> blocks(band.size());
  ParallelFor(band.size(), 1024, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) blocks[i] = volume.FindBlock(band[i]);
  });
  for (size_t i = 0; i < band.size(); ++i) {
    if (blocks[i]) continue;
    blocks[i] = volume.AllocateWithinBudget(band[i]);
    if (blocks[i]) {
      ++stats.blocks_allocated;
    } else {
      ++stats.blocks_refused;
    }
  }
  if (stats.blocks_refused > 0) DropRefused(band, blocks);
  stats.blocks_in_band = band.size();
  stats.allocate_ms = clock.ElapsedMs();

  clock.Restart();
  internal::FrameView f;
  f.depth = depth.data;
  f.color = (params.integrate_color && !color.empty()) ? color.data : nullptr;
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
  f.clear_depth_m = ClearDepth(params);
  f.trunc_m = volume.trunc_m();
  f.inv_trunc = 1.0f / volume.trunc_m();
  f.voxel_size_m = volume.voxel_size_m();
  f.max_weight = params.max_weight;
  f.depth_weighting = params.weighting == Weighting::kDepthDependent;

  const auto kernel = ResolveKernel(params.kernel) == Kernel::kSimd
                          ? internal::IntegrateBlockSimd
                          : internal::IntegrateBlockScalar;
  ParallelFor(band.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      // Pool blocks are scattered and a frame's band outgrows the cache at 5 mm: fetch the next
      // block (for writing) while this one is updated.
      constexpr size_t kCacheLine = 64;
      if (i + 1 < end) {
        const char* next = reinterpret_cast<const char*>(blocks[i + 1]);
        for (size_t o = 0; o < sizeof(TsdfBlock); o += kCacheLine) __builtin_prefetch(next + o, 1);
      }
      kernel(f, band[i], *blocks[i]);
    }
  });
  stats.update_ms = clock.ElapsedMs();
  if (params.carve_free_space) {
    // Branch-free, so it vectorises.
    uint32_t valid = 0;
    const size_t n = size_t(depth.width) * size_t(depth.height);
    for (size_t i = 0; i < n; ++i) {
      const float d = depth.data[i];
      valid += uint32_t(d >= params.min_depth_m) & uint32_t(d <= params.max_depth_m);
    }
    valid_pixels = valid;
  }
  stats.valid_pixels = valid_pixels;
  stats.touched_blocks = std::move(band);
  return stats;
}

}  // namespace voxplan
