#pragma once
// Internal to core/raycast/: splatting the map's blocks, and their bricks of negative voxels,
// into a cast's range images. Inline, so that march_avx2.cpp builds the same code a second time
// for AVX2 CPUs (CullChunkAvx2, SplatChunkAvx2) and range_image.cpp the portable one.
#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/block.h"
#include "core/block_map.h"
#include "core/camera.h"
#include "core/index.h"
#include "core/pose.h"
#include "core/raycast/raycast_internal.h"

namespace voxplan::raycast_detail {

// Bricks of kBrickSide^3 voxels: the unit at which negative voxels (behind a surface) are
// splatted into the surface range image. kBrickSide = 2 gives 64 bricks, one bit each.
inline constexpr int kBrickSide = 2;
inline constexpr int kBricksPerSide = kBlockSide / kBrickSide;
inline constexpr int kBricks = kBricksPerSide * kBricksPerSide * kBricksPerSide;
static_assert(kBricks == 64);

// Bit (bx + 4 by + 16 bz) set when brick (bx, by, bz) holds a voxel with a negative distance.
// Fresh voxels are +1, so a negative one has been observed; its weight is not read (half the
// bytes): under a raised RaycastParams::min_weight the mask only grows, which keeps the bound it
// feeds a bound. Depends on the block only, not the camera; a compare and a movemask per x-row.
[[gnu::always_inline]] inline uint64_t NegativeBrickMask(const TsdfBlock& block) {
  uint64_t mask = 0;
  for (int row = 0; row < kBlockSide * kBlockSide; ++row) {
    const int16_t* tsdf = block.tsdf + row * kBlockSide;
#if defined(__SSE2__)
    const __m128i zero = _mm_setzero_si128();
    const __m128i t = _mm_loadu_si128(reinterpret_cast<const __m128i*>(tsdf));
    const unsigned bits =
        unsigned(_mm_movemask_epi8(_mm_packs_epi16(_mm_cmplt_epi16(t, zero), zero)));
#else
    unsigned bits = 0;
    for (int x = 0; x < kBlockSide; ++x) bits |= unsigned(tsdf[x] < 0) << x;
#endif
    if (!bits) continue;
    const unsigned pairs = (bits | (bits >> 1)) & 0x55u;  // bit 2k: voxel 2k or 2k + 1
    const unsigned bricks_x =
        (pairs & 1u) | ((pairs >> 1) & 2u) | ((pairs >> 2) & 4u) | ((pairs >> 3) & 8u);
    const int y = row & kBlockMask, z = row >> kBlockShift;
    mask |= uint64_t(bricks_x) << (kBricksPerSide * (y / kBrickSide) +
                                   kBricksPerSide * kBricksPerSide * (z / kBrickSide));
  }
  return mask;
}

// Pixels a box can cover: [u_lo, u_hi] x [v_lo, v_hi], whole pixels clipped to the image.
struct PixelRange {
  float u_lo, u_hi, v_lo, v_hi;
};

// The pixels that the part at z >= z_near of the camera-aligned box centre_C +- half_extent
// can project to, half a pixel beyond to absorb rounding; false when none can. Over the box,
// x / z is largest at the near face where x > 0 and at the far face otherwise (so for y).
[[gnu::always_inline]] inline bool ProjectBox(const PinholeCamera& camera,
                                              const Eigen::Vector3f& centre_C,
                                              const Eigen::Vector3f& half_extent, float z_near,
                                              PixelRange* pixels) {
  const float z_front = std::max(centre_C.z() - half_extent.z(), z_near);
  const float z_back = centre_C.z() + half_extent.z();
  if (!(z_front <= z_back)) return false;
  const float inv_front = 1.f / z_front, inv_back = 1.f / z_back;
  constexpr float kPixelMargin = 0.5f;
  auto range = [&](float c, float e, float f, float principal, int size, float* lo, float* hi) {
    const float t_hi = (c + e) * (c + e >= 0.f ? inv_front : inv_back);
    const float t_lo = (c - e) * (c - e >= 0.f ? inv_back : inv_front);
    const float a = f * t_lo + principal, b = f * t_hi + principal;
    *lo = std::max(std::ceil(std::min(a, b) - kPixelMargin), 0.f);
    *hi = std::min(std::floor(std::max(a, b) + kPixelMargin), float(size - 1));
    return *lo <= *hi;
  };
  return range(centre_C.x(), half_extent.x(), camera.fx, camera.cx, camera.width, &pixels->u_lo,
               &pixels->u_hi) &&
         range(centre_C.y(), half_extent.y(), camera.fy, camera.cy, camera.height, &pixels->v_lo,
               &pixels->v_hi);
}

// Floats a chunk's surface image holds beyond its last cell, for MinRow.
inline constexpr size_t kSurfaceRowPad = 3;

// row[x] = min(row[x], z) for x in [lo, hi]. A brick covers a few cells of a row, so four are
// taken at a time (those outside the range keep their value); row[hi + 3] must exist.
[[gnu::always_inline]] inline void MinRow(float* row, int lo, int hi, float z) {
#if defined(__SSE2__)
  const __m128 zs = _mm_set1_ps(z);
  for (int x = lo; x <= hi; x += 4) {
    const __m128i lane = _mm_add_epi32(_mm_set1_epi32(x), _mm_set_epi32(3, 2, 1, 0));
    const __m128 in_range = _mm_castsi128_ps(_mm_cmplt_epi32(lane, _mm_set1_epi32(hi + 1)));
    const __m128 old = _mm_loadu_ps(row + x);
    _mm_storeu_ps(row + x, _mm_or_ps(_mm_and_ps(in_range, _mm_min_ps(old, zs)),
                                     _mm_andnot_ps(in_range, old)));
  }
#else
  for (int x = lo; x <= hi; ++x) row[x] = std::min(row[x], z);
#endif
}

// A visible block: its negative bricks are still to be splatted.
struct VisibleBlock {
  const TsdfBlock* block;
  BlockIndex index;
  Eigen::Vector3f p0_C;
  float z_lo;       // the block's nearest depth, at least z_near
  uint64_t bricks;  // NegativeBrickMask
};

// A part of the map's blocks, splatted into its own images (min and max are order-independent,
// so the parts cannot change the result).
struct Chunk {
  std::vector<float> z_min, z_max, surface_z_min;
  std::vector<VisibleBlock> visible;
};

// The negative-brick masks of the visible blocks by block index, for the neighbour tests of
// SplatBricks.
class BrickMaskTable {
 public:
  void Build(const std::vector<Chunk>& chunks) {
    for (const Chunk& chunk : chunks)
      for (const VisibleBlock& v : chunk.visible) {
        if (!v.bricks) continue;
        index_.Insert(v.index, uint32_t(masks_.size()));
        masks_.push_back(v.bricks);
      }
  }
  // 0 for a block that is not visible or holds no negative voxel.
  uint64_t Find(BlockIndex b) const {
    // Indices beyond the packable range would alias; no visible block is there.
    const uint32_t i = InPackRange(b) ? index_.Find(b) : BlockMap::kNoSlot;
    return i == BlockMap::kNoSlot ? 0 : masks_[i];
  }

 private:
  BlockMap index_;  // block -> its place in masks_
  std::vector<uint64_t> masks_;
};

// Interior bricks. Where a ray first meets the negative bricks, it enters one, B, through a
// face that the camera sees, and the point lies on the brick beyond that face too. If that
// brick is negative, its splat bounds the ray as well as B's; repeating the step moves towards
// the camera, so it ends at a splatted brick. Hence a negative brick whose neighbours across
// every face the camera sees are negative need not be splatted, provided it lies beyond z_near
// (so that rays enter it from outside). Bricks of a block are bits bx + 4 by + 16 bz: along
// axis a a brick is kBrickStride[a] bits on, and kFace0[a] holds those with coordinate 0.
inline constexpr int kBrickStride[3] = {1, kBricksPerSide, kBricks / kBricksPerSide};
inline constexpr uint64_t kFace0[3] = {0x1111111111111111ull, 0x000f000f000f000full, 0xffffull};
// Bricks within this fraction of a brick of the camera's plane along an axis count as seen
// from both sides (more neighbours asked for, never fewer).
inline constexpr float kSideMargin = 0.01f;

// What splatting blocks into a range image needs for one cast: the camera, the pose and the
// block and brick geometry in the camera frame.
struct Splatter {
  const PinholeCamera& camera;
  Pose3f T_C_W;
  Eigen::Vector3f camera_W;
  float block_m, z_near, z_far;
  int cols, surface_cols;
  size_t num_cells, num_surface_cells;
  // One voxel along each block axis, in the camera frame; half the extent of a block's and a
  // brick's cube along each camera axis; from a block's origin to its centre and to its first
  // brick's centre.
  Eigen::Vector3f voxel_x, voxel_y, voxel_z, block_half_extent, brick_half_extent,
      to_block_centre_C, to_brick_centre_C;

  // Splats blocks [first, last) into the chunk's block-range images and lists the visible ones
  // with their negative bricks.
  [[gnu::always_inline]] inline void CullBlocks(const BlockIndex* blocks,
                                                const TsdfBlock* const* data, size_t first,
                                                size_t last, Chunk& chunk) const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    chunk.z_min.assign(num_cells, kInf);
    chunk.z_max.assign(num_cells, -kInf);
    std::vector<VisibleBlock>& visible = chunk.visible;
    visible.clear();
    for (size_t k = first; k < last; ++k) {
      const Eigen::Vector3f p0_C = T_C_W * BlockOrigin(blocks[k], block_m);
      const Eigen::Vector3f centre_C = p0_C + to_block_centre_C;
      PixelRange pixels;
      const float z_box = centre_C.z() - block_half_extent.z();  // nearest depth of the box
      if (z_box > z_far || !ProjectBox(camera, centre_C, block_half_extent, z_near, &pixels))
        continue;
      const float z_lo = std::max(z_box, z_near), z_hi = centre_C.z() + block_half_extent.z();
      for (int cy = int(pixels.v_lo) / kRangeCell; cy <= int(pixels.v_hi) / kRangeCell; ++cy)
        for (int cx = int(pixels.u_lo) / kRangeCell; cx <= int(pixels.u_hi) / kRangeCell; ++cx) {
          const size_t cell = size_t(cy) * size_t(cols) + size_t(cx);
          chunk.z_min[cell] = std::min(chunk.z_min[cell], z_lo);
          chunk.z_max[cell] = std::max(chunk.z_max[cell], z_hi);
        }
      visible.push_back({data[k], blocks[k], p0_C, z_lo, 0});
    }
    // Blocks lie scattered over the pool, so each would wait on its distances line by line:
    // those of a block a few places ahead are prefetched.
    constexpr size_t kAhead = 4;
    for (size_t j = 0; j < visible.size(); ++j) {
      if (j + kAhead < visible.size()) {
        const char* tsdf = reinterpret_cast<const char*>(visible[j + kAhead].block->tsdf);
        constexpr size_t kCacheLine = 64;
        for (size_t line = 0; line < sizeof(TsdfBlock::tsdf); line += kCacheLine)
          __builtin_prefetch(tsdf + line);
      }
      visible[j].bricks = NegativeBrickMask(*visible[j].block);
    }
  }

  // The bricks of `v` that need not be splatted (see kBrickStride): negative, with negative
  // neighbours across every face the camera sees.
  uint64_t InteriorBricks(const VisibleBlock& v, const BrickMaskTable& table) const {
    const uint64_t negative = v.bricks;
    // The camera in the block's brick units.
    const Eigen::Vector3f t =
        (camera_W - BlockOrigin(v.index, block_m)) * (float(kBricksPerSide) / block_m);
    uint64_t interior = negative;
    for (int a = 0; a < 3 && interior; ++a) {
      const int stride = kBrickStride[a];
      const uint64_t face0 = kFace0[a], face_last = face0 << ((kBricksPerSide - 1) * stride);
      // Bricks whose face towards -a (+a) the camera sees.
      uint64_t sees_minus = 0, sees_plus = 0;
      for (int k = 0; k < kBricksPerSide; ++k) {
        if (t[a] < float(k) + kSideMargin) sees_minus |= face0 << (k * stride);
        if (t[a] > float(k + 1) - kSideMargin) sees_plus |= face0 << (k * stride);
      }
      // Per brick, whether its neighbour towards -a (+a) is negative: in the block, or the
      // facing brick of the next block, looked up only when a candidate needs it.
      BlockIndex next = v.index;
      uint64_t minus = (negative << stride) & ~face0;
      if (interior & sees_minus & face0) {
        (&next.x)[a] -= 1;
        minus |= (table.Find(next) & face_last) >> ((kBricksPerSide - 1) * stride);
        (&next.x)[a] += 1;
      }
      interior &= ~sees_minus | minus;
      uint64_t plus = (negative >> stride) & ~face_last;
      if (interior & sees_plus & face_last) {
        (&next.x)[a] += 1;
        plus |= (table.Find(next) & face0) << ((kBricksPerSide - 1) * stride);
      }
      interior &= ~sees_plus | plus;
    }
    return interior;
  }

  // Splats the negative bricks of the chunk's visible blocks into its surface image, but for
  // interior ones.
  [[gnu::always_inline]] inline void SplatBricks(const BrickMaskTable& table, Chunk& chunk) const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    // Padded so that a row of cells is updated four at a time (see MinRow).
    chunk.surface_z_min.assign(num_surface_cells + kSurfaceRowPad, kInf);
    for (const VisibleBlock& v : chunk.visible) {
      if (!v.bricks) continue;
      const uint64_t interior = InteriorBricks(v, table);
      // Each other brick splats the near depth of its cube's camera-aligned bounding box (a
      // lower bound of its voxels' cubes) over the pixels the box can project to (the whole
      // block's where the box reaches z_near).
      const Eigen::Vector3f brick0_C = v.p0_C + to_brick_centre_C;
      for (uint64_t bricks = v.bricks; bricks; bricks &= bricks - 1) {
        const int i = std::countr_zero(bricks);
        const int bx = i % kBricksPerSide, by = (i / kBricksPerSide) % kBricksPerSide,
                  bz = i / (kBricksPerSide * kBricksPerSide);
        const Eigen::Vector3f c_C =
            brick0_C +
            float(kBrickSide) * (float(bx) * voxel_x + float(by) * voxel_y + float(bz) * voxel_z);
        const float z_front = c_C.z() - brick_half_extent.z();
        // Interior bricks clearly beyond z_near: rays reach them through a splatted one.
        if ((interior >> i) & 1 && z_front > z_near + brick_half_extent.z()) continue;
        const float surface_z = std::max(z_front, v.z_lo);
        PixelRange pixels;
        if (!ProjectBox(camera, c_C, brick_half_extent, z_near, &pixels)) continue;
        const int cx_lo = int(pixels.u_lo) / kSurfaceCell, cx_hi = int(pixels.u_hi) / kSurfaceCell;
        for (int cy = int(pixels.v_lo) / kSurfaceCell; cy <= int(pixels.v_hi) / kSurfaceCell; ++cy)
          MinRow(chunk.surface_z_min.data() + size_t(cy) * size_t(surface_cols), cx_lo, cx_hi,
                 surface_z);
      }
    }
  }
};

// The splatting of one cast's chunks, portable (range_image.cpp) and for AVX2 CPUs
// (march_avx2.cpp), where std::ceil and std::floor are one instruction (SSE4.1's round) instead
// of a dozen; the results are the same.
void CullChunk(const Splatter& splatter, const BlockIndex* blocks, const TsdfBlock* const* data,
               size_t first, size_t last, Chunk& chunk);
void SplatChunk(const Splatter& splatter, const BrickMaskTable& table, Chunk& chunk);
void CullChunkAvx2(const Splatter& splatter, const BlockIndex* blocks, const TsdfBlock* const* data,
                   size_t first, size_t last, Chunk& chunk);
void SplatChunkAvx2(const Splatter& splatter, const BrickMaskTable& table, Chunk& chunk);

}  // namespace voxplan::raycast_detail
