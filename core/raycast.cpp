#include "core/raycast.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

#include "core/block_map.h"
#include "core/parallel.h"
#include "core/raycast_kernels.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// Packets of 8 rays marched in AVX2 lanes, chosen at run time where the CPU has AVX2 (the
// define: build without them).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(VOXPLAN_RAYCAST_NO_AVX2)
#include <immintrin.h>
#define VOXPLAN_RAYCAST_AVX2 1
#define VOXPLAN_TARGET_AVX2 __attribute__((target("avx2")))
#else
#define VOXPLAN_RAYCAST_AVX2 0
#endif

namespace voxplan {
namespace {

constexpr int kRangeCell = 8;    // pixels per side of a range-image cell
constexpr int kSurfaceCell = 2;  // pixels per side of a surface-range cell
constexpr int kTile = 16;        // pixels per side of one parallel work item
constexpr int kLanes = 4;        // rays the scalar march interleaves
constexpr int kPacket = 8;       // rays an AVX2 packet marches
constexpr int kPackets = 2;      // packets a worker marches side by side (overlaps latencies)
constexpr int kPacketLanes = kPacket * kPackets;
constexpr int kTilesPerBatch = 4;  // tiles whose rays feed one march (fewer idle lanes at the end)
// Step as a fraction of the stored distance: the nearest voxel's centre can be up to 0.87 voxel
// from the sample, and the negative band behind a surface is what catches an overshoot.
constexpr float kStepScale = 0.9f;
// Two Newton steps from the linear guess land within a hundredth of a voxel on a smooth
// surface; each further step costs a cell gather and changes the depth by less.
constexpr int kNewtonIterations = 2;
constexpr float kConvergedVoxels = 0.05f;   // a Newton step this small ends the search
constexpr float kMinSlopeFraction = 0.05f;  // of the head-on slope; below it, the ray grazes
constexpr int kSecantIterations = 3;
constexpr int kMaxBracketShifts = 2;  // voxels the trilinear bracket may move either way
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

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

// Bricks of kBrickSide^3 voxels: the unit at which negative voxels (behind a surface) are
// splatted into the surface range image. kBrickSide = 2 gives 64 bricks, one bit each.
constexpr int kBrickSide = 2;
constexpr int kBricksPerSide = kBlockSide / kBrickSide;
constexpr int kBricks = kBricksPerSide * kBricksPerSide * kBricksPerSide;
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

// The depth where marching starts: a voxel before min_depth, so that a surface just beyond it
// is approached from its positive side (crossings in front of min_depth are not reported).
float MarchStart(const TsdfVolume& volume, const RaycastParams& params) {
  return std::max(params.min_depth_m - volume.voxel_size_m(), 1e-3f);
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
constexpr size_t kSurfaceRowPad = 3;

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
constexpr int kBrickStride[3] = {1, kBricksPerSide, kBricks / kBricksPerSide};
constexpr uint64_t kFace0[3] = {0x1111111111111111ull, 0x000f000f000f000full, 0xffffull};
// Bricks within this fraction of a brick of the camera's plane along an axis count as seen
// from both sides (more neighbours asked for, never fewer).
constexpr float kSideMargin = 0.01f;

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

void CullChunk(const Splatter& splatter, const BlockIndex* blocks, const TsdfBlock* const* data,
               size_t first, size_t last, Chunk& chunk) {
  splatter.CullBlocks(blocks, data, first, last, chunk);
}
void SplatChunk(const Splatter& splatter, const BrickMaskTable& table, Chunk& chunk) {
  splatter.SplatBricks(table, chunk);
}

#if VOXPLAN_RAYCAST_AVX2
// The same code for AVX2 CPUs, where std::ceil and std::floor are one instruction (SSE4.1's
// round) instead of a dozen; the results are the same.
VOXPLAN_TARGET_AVX2 void CullChunkAvx2(const Splatter& splatter, const BlockIndex* blocks,
                                       const TsdfBlock* const* data, size_t first, size_t last,
                                       Chunk& chunk) {
  splatter.CullBlocks(blocks, data, first, last, chunk);
}
VOXPLAN_TARGET_AVX2 void SplatChunkAvx2(const Splatter& splatter, const BrickMaskTable& table,
                                        Chunk& chunk) {
  splatter.SplatBricks(table, chunk);
}
#endif

RangeImage BuildRangeImage(const TsdfVolume& volume, const PinholeCamera& camera,
                           const Pose3f& T_C_W, const RaycastParams& params) {
  RangeImage range;
  range.cols = (camera.width + kRangeCell - 1) / kRangeCell;
  range.rows = (camera.height + kRangeCell - 1) / kRangeCell;
  range.surface_cols = (camera.width + kSurfaceCell - 1) / kSurfaceCell;
  range.surface_rows = (camera.height + kSurfaceCell - 1) / kSurfaceCell;
  const size_t num_cells = size_t(range.cols) * size_t(range.rows);
  const size_t num_surface_cells = size_t(range.surface_cols) * size_t(range.surface_rows);

  std::vector<BlockIndex> blocks;
  std::vector<const TsdfBlock*> block_data;
  blocks.reserve(volume.num_blocks());
  block_data.reserve(volume.num_blocks());
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock& data) {
    blocks.push_back(b);
    block_data.push_back(&data);
  });
  // A chunk per thread at most: each holds whole images, set and merged serially.
  constexpr size_t kBlocksPerChunk = 1024;
  const size_t num_chunks =
      std::clamp<size_t>(blocks.size() / kBlocksPerChunk, 1, size_t(std::max(MaxThreads(), 1)));
  std::vector<Chunk> chunks(num_chunks);
  const float voxel_m = volume.voxel_size_m();
  const Eigen::Matrix3f R_C_W = T_C_W.linear();
  const Eigen::Vector3f voxel_x = R_C_W.col(0) * voxel_m, voxel_y = R_C_W.col(1) * voxel_m,
                        voxel_z = R_C_W.col(2) * voxel_m;
  const Eigen::Vector3f voxel_extent = voxel_x.cwiseAbs() + voxel_y.cwiseAbs() + voxel_z.cwiseAbs();
  const float block_m = volume.block_size_m();
  const Splatter splatter{
      camera,
      T_C_W,
      T_C_W.inverse().translation(),
      block_m,
      MarchStart(volume, params),
      params.max_depth_m,
      range.cols,
      range.surface_cols,
      num_cells,
      num_surface_cells,
      voxel_x,
      voxel_y,
      voxel_z,
      (0.5f * float(kBlockSide)) * voxel_extent,
      (0.5f * float(kBrickSide)) * voxel_extent,
      0.5f * (R_C_W.col(0) * block_m + R_C_W.col(1) * block_m + R_C_W.col(2) * block_m),
      (0.5f * float(kBrickSide)) * (voxel_x + voxel_y + voxel_z)};
#if VOXPLAN_RAYCAST_AVX2
  const bool avx2 = params.simd && RaycastSimdAvailable();
#endif
  ParallelFor(num_chunks, 1, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      const size_t first = blocks.size() * c / num_chunks;
      const size_t last = blocks.size() * (c + 1) / num_chunks;
#if VOXPLAN_RAYCAST_AVX2
      if (avx2) {
        CullChunkAvx2(splatter, blocks.data(), block_data.data(), first, last, chunks[c]);
        continue;
      }
#endif
      CullChunk(splatter, blocks.data(), block_data.data(), first, last, chunks[c]);
    }
  });
  BrickMaskTable table;
  table.Build(chunks);
  ParallelFor(num_chunks, 1, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
#if VOXPLAN_RAYCAST_AVX2
      if (avx2) {
        SplatChunkAvx2(splatter, table, chunks[c]);
        continue;
      }
#endif
      SplatChunk(splatter, table, chunks[c]);
    }
  });

  range.z_min = std::move(chunks[0].z_min);
  range.z_max = std::move(chunks[0].z_max);
  range.surface_z_min = std::move(chunks[0].surface_z_min);
  for (size_t c = 1; c < num_chunks; ++c) {
    const Chunk& chunk = chunks[c];
    for (size_t i = 0; i < num_cells; ++i) {
      range.z_min[i] = std::min(range.z_min[i], chunk.z_min[i]);
      range.z_max[i] = std::max(range.z_max[i], chunk.z_max[i]);
    }
    for (size_t i = 0; i < num_surface_cells; ++i)
      range.surface_z_min[i] = std::min(range.surface_z_min[i], chunk.surface_z_min[i]);
  }
  return range;
}

using raycast_detail::kCornerOffset;

// Read where a ray has no block: never observed.
const TsdfBlock kNoBlock{};

// The 2x2x2 voxel centres around a point, for trilinear interpolation of TSDF, colour and the
// gradient. Corner k is offset (k & 1, (k >> 1) & 1, k >> 2).
struct Cell {
  alignas(16) int32_t base[4] = {0, 0, 0, 0};        // the corner-0 voxel (x, y, z, 0)
  alignas(16) float frac[4] = {0.f, 0.f, 0.f, 0.f};  // position inside the cell, each in [0, 1)
  alignas(16) float tsdf[8];                         // normalised by the truncation distance
  const TsdfBlock* block[8];  // corner k's block (only block[0] when one_block)
  int index[8];               // corner k's voxel in it (only index[0] when one_block)
  bool loaded = false;        // tsdf and the corner addresses hold the corners of `base`
  bool one_block = false;     // all corners in block[0], at index[0] + kCornerOffset[k]
  uint8_t observed = 0;       // bit k: corner k observed

  bool complete() const { return observed == 0xff; }
  const TsdfBlock& CornerBlock(int k) const { return *block[one_block ? 0 : k]; }
  int CornerIndex(int k) const { return one_block ? index[0] + kCornerOffset[k] : index[k]; }
  // The trilinear interpolant at frac and its gradient (normalised TSDF per voxel).
  float ValueAndGradient(Eigen::Vector3f* gradient) const {
    return raycast_detail::ValueAndGradient(tsdf, frac, gradient->data());
  }
};

// a == b without a branch per coordinate: neighbouring rays' blocks often share x or y, which
// makes a short-circuit compare mispredict.
inline bool SameBlock(BlockIndex a, BlockIndex b) {
  return ((a.x ^ b.x) | (a.y ^ b.y) | (a.z ^ b.z)) == 0;
}

// Block lookups for one worker: a small direct-mapped cache (misses included) in front of the
// hash map, since neighbouring rays visit the same blocks.
class BlockCache {
 public:
  explicit BlockCache(const TsdfVolume& volume) : volume_(volume) {}

  const TsdfBlock* Find(BlockIndex b) {
    const uint32_t hash =
        uint32_t(b.x) * 0x8da6b343u ^ uint32_t(b.y) * 0xd8163841u ^ uint32_t(b.z) * 0xcb1ab31fu;
    Entry& e = entries_[hash >> (32 - kCacheBits)];
    if (!SameBlock(e.index, b)) {
      e.index = b;
      // Indices beyond the packable range would alias in the hash map; none is allocated.
      e.block = InPackRange(b) ? volume_.FindBlock(b) : nullptr;
    }
    return e.block;
  }

 private:
  static constexpr int kCacheBits = 8;
  struct Entry {
    BlockIndex index{kMaxBlockCoord + 1, 0, 0};  // out of range: no block, correctly
    const TsdfBlock* block = nullptr;
  };
  const TsdfVolume& volume_;
  Entry entries_[1 << kCacheBits];
};

class Sampler {
 public:
  Sampler(const TsdfVolume& volume, const RaycastParams& params)
      : cache_(volume),
        voxel_m_(volume.voxel_size_m()),
        inv_voxel_(1.f / volume.voxel_size_m()),
        trunc_m_(volume.trunc_m()),
        // DecodeWeight(w) = w / 128 exactly, so w >= ceil(min_weight * 128) is the same test.
        min_weight_fixed_(
            uint32_t(std::clamp(std::ceil(params.min_weight * kWeightScale), 1.f, 65536.f))) {}

  // The last block looked up (by the march or a gather) first: a refinement mostly reads the
  // block the march just sampled.
  const TsdfBlock* Find(BlockIndex b) {
    if (!SameBlock(b, last_index_)) {
      last_index_ = b;
      last_block_ = cache_.Find(b);
    }
    return last_block_;
  }
  uint32_t min_weight_fixed() const { return min_weight_fixed_; }
  // Find without the last-block shortcut, for lookups that alternate between rays.
  const TsdfBlock* FindUncached(BlockIndex b) { return cache_.Find(b); }
  bool Observed(const TsdfBlock& block, int i) const {
    return uint32_t(block.weight[i]) >= min_weight_fixed_;
  }

  // Points `cell` at p_W, reading the corners only when p_W left the cell it held. Unobserved
  // corners take the interpolation-weighted mean of the observed ones; returns whether all
  // eight were observed.
  [[gnu::always_inline]] bool Gather(const Eigen::Vector3f& p_W, Cell* cell) {
    // The cell's corner 0 and the position inside it, in voxel units.
#if VOXPLAN_RAYCAST_SSE2
    const __m128 q =
        _mm_sub_ps(_mm_mul_ps(_mm_set_ps(0.f, p_W.z(), p_W.y(), p_W.x()), _mm_set1_ps(inv_voxel_)),
                   _mm_set_ps(0.f, 0.5f, 0.5f, 0.5f));
    const __m128i truncated = _mm_cvttps_epi32(q);
    const __m128 truncated_f = _mm_cvtepi32_ps(truncated);
    const __m128i base = _mm_add_epi32(truncated, _mm_castps_si128(_mm_cmplt_ps(q, truncated_f)));
    _mm_store_ps(cell->frac, _mm_sub_ps(q, _mm_cvtepi32_ps(base)));
    const __m128i old_base = _mm_load_si128(reinterpret_cast<const __m128i*>(cell->base));
    if (cell->loaded && _mm_movemask_epi8(_mm_cmpeq_epi32(base, old_base)) == 0xffff)
      return cell->complete();
    _mm_store_si128(reinterpret_cast<__m128i*>(cell->base), base);
#else
    const Eigen::Vector3f q = p_W * inv_voxel_ - Eigen::Vector3f::Constant(0.5f);
    const int32_t base[3] = {FloorToInt(q.x()), FloorToInt(q.y()), FloorToInt(q.z())};
    for (int a = 0; a < 3; ++a) cell->frac[a] = q[a] - float(base[a]);
    if (cell->loaded && base[0] == cell->base[0] && base[1] == cell->base[1] &&
        base[2] == cell->base[2])
      return cell->complete();
    for (int a = 0; a < 3; ++a) cell->base[a] = base[a];
#endif
    cell->loaded = true;
    const GlobalVoxelIndex g{cell->base[0], cell->base[1], cell->base[2]};
    const VoxelIndex local = LocalOf(g);
    const BlockIndex b0 = BlockOf(g);
    unsigned observed = 0;
    if (local.x < kBlockMask && local.y < kBlockMask && local.z < kBlockMask) {
      // The common case: all eight corners in one block, at fixed offsets.
      const TsdfBlock* block = Find(b0);
      const int i0 = LinearIndex(local);
      cell->one_block = true;
      cell->block[0] = block;
      cell->index[0] = i0;
      if (block) observed = raycast_detail::LoadCorners(*block, i0, min_weight_fixed_, cell->tsdf);
      cell->observed = uint8_t(observed);
      if (cell->complete()) return true;
    }
    return GatherRest(cell);
  }

  // The blocks and voxel indices of the corners of the cell whose corner 0 is g, for a cell
  // across block faces. Only the neighbours the corners reach are looked up (two usually);
  // corner k lies in neighbour k & across, a missing block reads as never observed (kNoBlock).
  void CornersAcross(GlobalVoxelIndex g, const TsdfBlock* block[8], int index[8]) {
    const VoxelIndex local = LocalOf(g);
    const BlockIndex b0 = BlockOf(g);
    const bool ex = local.x == kBlockMask, ey = local.y == kBlockMask, ez = local.z == kBlockMask;
    const int across = int(ex) | int(ey) << 1 | int(ez) << 2;
    const TsdfBlock* neighbour[8];
    // The neighbours bypass the last-block shortcut, which keeps b0 for the next gather.
    auto find = [&](int dx, int dy, int dz) {
      const TsdfBlock* block = cache_.Find(BlockIndex{b0.x + dx, b0.y + dy, b0.z + dz});
      return block ? block : &kNoBlock;
    };
    const TsdfBlock* block0 = Find(b0);
    neighbour[0] = block0 ? block0 : &kNoBlock;
    if (ex) neighbour[1] = find(1, 0, 0);
    if (ey) neighbour[2] = find(0, 1, 0);
    if (ex && ey) neighbour[3] = find(1, 1, 0);
    if (ez) {
      neighbour[4] = find(0, 0, 1);
      if (ex) neighbour[5] = find(1, 0, 1);
      if (ey) neighbour[6] = find(0, 1, 1);
      if (ex && ey) neighbour[7] = find(1, 1, 1);
    }
    // One voxel further along each axis: the next voxel in the block, or the first one of the
    // neighbour (wrapped).
    const int step_x = ex ? 1 - kBlockSide : 1;
    const int step_y = (ey ? 1 - kBlockSide : 1) * kBlockSide;
    const int step_z = (ez ? 1 - kBlockSide : 1) * kBlockSide * kBlockSide;
    const int i0 = LinearIndex(local);
    for (int k = 0; k < 8; ++k) {
      block[k] = neighbour[k & across];
      index[k] = i0 + (k & 1 ? step_x : 0) + (k & 2 ? step_y : 0) + (k & 4 ? step_z : 0);
    }
  }

  // Gather's other cases, out of line: corners across block faces, unobserved corners.
  [[gnu::noinline]] bool GatherRest(Cell* cell) {
    const GlobalVoxelIndex g{cell->base[0], cell->base[1], cell->base[2]};
    const VoxelIndex local = LocalOf(g);
    unsigned observed = cell->observed;  // set by Gather in one block
    if (!(local.x < kBlockMask && local.y < kBlockMask && local.z < kBlockMask)) {
      cell->one_block = false;
      CornersAcross(g, cell->block, cell->index);
      observed = raycast_detail::LoadCornersAcross(cell->block, cell->index, min_weight_fixed_,
                                                   cell->tsdf);
    }
    cell->observed = uint8_t(observed);
    if (cell->complete()) return true;
    float sum = 0.f, sum_w = 0.f;
    for (int k = 0; k < 8; ++k)
      if (cell->observed & (1 << k)) sum += cell->tsdf[k], sum_w += 1.f;
    const float fill = sum_w > 0.f ? sum / sum_w : 1.f;
    for (int k = 0; k < 8; ++k)
      if (!(cell->observed & (1 << k))) cell->tsdf[k] = fill;
    return false;
  }

  float voxel_m() const { return voxel_m_; }
  float inv_voxel() const { return inv_voxel_; }
  float trunc_m() const { return trunc_m_; }

 private:
  BlockCache cache_;
  BlockIndex last_index_{kMaxBlockCoord + 1, 0, 0};
  const TsdfBlock* last_block_ = nullptr;
  float voxel_m_, inv_voxel_, trunc_m_;
  uint32_t min_weight_fixed_;
};

struct RayResult {
  RayStatus status = RayStatus::kUnobserved;
  float z = 0.f;
  Eigen::Vector3f normal_W = Eigen::Vector3f::Constant(kNaN);
  uint32_t color = 0;
};

// Trilinear colour over the observed corners.
uint32_t CellColor(const Cell& cell) {
  if (cell.complete()) {
    if (cell.one_block) return raycast_detail::BlendColor(*cell.block[0], cell.index[0], cell.frac);
    uint8_t r[8], g[8], b[8];
    for (int k = 0; k < 8; ++k) {
      r[k] = cell.block[k]->r[cell.index[k]];
      g[k] = cell.block[k]->g[cell.index[k]];
      b[k] = cell.block[k]->b[cell.index[k]];
    }
    return raycast_detail::BlendCornerColors(r, g, b, cell.frac);
  }
  const float fx = cell.frac[0], fy = cell.frac[1], fz = cell.frac[2];
  float r = 0.f, g = 0.f, b = 0.f, sum_w = 0.f;
  for (int k = 0; k < 8; ++k) {
    if (!(cell.observed & (1 << k))) continue;
    const float w =
        ((k & 1) ? fx : 1 - fx) * (((k >> 1) & 1) ? fy : 1 - fy) * ((k >> 2) ? fz : 1 - fz);
    const TsdfBlock& block = cell.CornerBlock(k);
    const int i = cell.CornerIndex(k);
    r += w * float(block.r[i]);
    g += w * float(block.g[i]);
    b += w * float(block.b[i]);
    sum_w += w;
  }
  if (!(sum_w > 0.f)) return 0;
  const float inv = 1.f / sum_w;
  auto to8 = [inv](float c) { return uint8_t(std::clamp(c * inv + 0.5f, 0.f, 255.f)); };
  return PackRgb(to8(r), to8(g), to8(b));
}

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

#if VOXPLAN_RAYCAST_AVX2
// Small AVX2 helpers of the packet march (functions, since lambdas would not get its target).
namespace avx2 {
VOXPLAN_TARGET_AVX2 inline __m256i Load(const void* p) {
  return _mm256_loadu_si256(static_cast<const __m256i*>(p));
}
VOXPLAN_TARGET_AVX2 inline __m256 LoadF(const float* p) { return _mm256_loadu_ps(p); }
VOXPLAN_TARGET_AVX2 inline __m256 Set(float x) { return _mm256_set1_ps(x); }
// DecodeTsdf of each lane.
VOXPLAN_TARGET_AVX2 inline __m256 Decode(__m256i t) {
  return _mm256_mul_ps(_mm256_cvtepi32_ps(t), _mm256_set1_ps(1.0f / kTsdfScale));
}
// A trilinear weight as the SSE2 kernels form it: f where `upper`, 1 - f otherwise, each as
// a + b f (the same roundings).
VOXPLAN_TARGET_AVX2 inline __m256 Lerp(bool upper, __m256 f) {
  return _mm256_add_ps(_mm256_set1_ps(upper ? 0.f : 1.f),
                       _mm256_mul_ps(_mm256_set1_ps(upper ? 1.f : -1.f), f));
}
// (v0 + v1) + (v2 + v3): a transposed SSE2 horizontal sum, lane by lane.
VOXPLAN_TARGET_AVX2 inline __m256 Sum4(const __m256 v[4]) {
  return _mm256_add_ps(_mm256_add_ps(v[0], v[1]), _mm256_add_ps(v[2], v[3]));
}
VOXPLAN_TARGET_AVX2 inline void Store(void* p, __m256i v) {
  _mm256_storeu_si256(static_cast<__m256i*>(p), v);
}
VOXPLAN_TARGET_AVX2 inline __m256i AndNot(__m256i a, __m256i b) {  // ~a & b
  return _mm256_andnot_si256(a, b);
}
VOXPLAN_TARGET_AVX2 inline __m256 Blend(__m256 no, __m256 yes, __m256i mask) {
  return _mm256_blendv_ps(no, yes, _mm256_castsi256_ps(mask));
}
// floor(p) as Sampler::Gather and Step compute it: truncate, minus one where that rounded up.
VOXPLAN_TARGET_AVX2 inline __m256i Floor(__m256 p) {
  const __m256i truncated = _mm256_cvttps_epi32(p);
  return _mm256_add_epi32(
      truncated, _mm256_castps_si256(_mm256_cmp_ps(p, _mm256_cvtepi32_ps(truncated), _CMP_LT_OQ)));
}
// The zero of the line through (z_a, f_a) and (z_b, f_b), as Refine and Bracket compute it.
VOXPLAN_TARGET_AVX2 inline __m256 Secant(__m256 z_a, __m256 z_b, __m256 f_a, __m256 f_b) {
  return _mm256_add_ps(
      z_a, _mm256_div_ps(_mm256_mul_ps(_mm256_sub_ps(z_b, z_a), f_a), _mm256_sub_ps(f_a, f_b)));
}
// The linear index inside its block of each lane's voxel g.
VOXPLAN_TARGET_AVX2 inline __m256i LinearIndex(const __m256i g[3]) {
  const __m256i mask = _mm256_set1_epi32(kBlockMask);
  return _mm256_add_epi32(
      _mm256_and_si256(g[0], mask),
      _mm256_add_epi32(_mm256_slli_epi32(_mm256_and_si256(g[1], mask), kBlockShift),
                       _mm256_slli_epi32(_mm256_and_si256(g[2], mask), 2 * kBlockShift)));
}
}  // namespace avx2
#endif

// A pixel whose ray has a depth range to march.
struct RayTask {
  size_t pixel;  // where the result goes (Raycast: the index in its batch's images)
  int u, v;
  float z_begin, z_end;
  // >= 0: [z_skipped, z_begin) was skipped (it holds no surface); marched as well when the march
  // from z_begin meets no observed voxel, so that the status says whether the ray met any.
  float z_skipped;
};

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
        step_scale_(kStepScale * volume.trunc_m() / kTsdfScale) {
#if VOXPLAN_RAYCAST_SSE2
    origin_vox_lanes_ = _mm_set_ps(0.f, origin_vox_.z(), origin_vox_.y(), origin_vox_.x());
#endif
  }

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
  template <class Write>
  void MarchInterleaved(const RayTask* tasks, size_t num_tasks, Write&& write) {
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

#if VOXPLAN_RAYCAST_AVX2
  // The same march over packets of kPacket rays in AVX2 lanes: every lane takes the sample Step
  // would take, with the same float operations in the same order (no FMA: the file is built
  // with -ffp-contract=off), so the images are identical to MarchInterleaved's. The steps have
  // no per-ray branch; block lookups and new rays are handled lane by lane. A lane that meets a
  // crossing hands it on and takes the next ray: crossings are refined kPacket at a time
  // (RefineCrossings). A worker marches kPackets packets in turn, so that one packet's loads
  // and lookups overlap another's.
  template <class Write>
  VOXPLAN_TARGET_AVX2 void MarchPackets(const RayTask* tasks, size_t num_tasks, Write&& write) {
    struct alignas(32) Lanes {
      float z[kPacketLanes], z_end[kPacketLanes], voxel_z[kPacketLanes], step_z[kPacketLanes],
          prev_z[kPacketLanes];
      float dir_vox[3][kPacketLanes], dir_W[3][kPacketLanes];
      int32_t block_index[3][kPacketLanes];
      int32_t prev_tsdf[kPacketLanes], tsdf[kPacketLanes];
      int32_t live[kPacketLanes], has_block[kPacketLanes], have_prev[kPacketLanes],
          met[kPacketLanes];  // 0 or -1
      const TsdfBlock* block[kPacketLanes];
      size_t pixel[kPacketLanes];
      float z_skipped[kPacketLanes], z_begin[kPacketLanes];
    } lanes;
    std::memset(&lanes, 0, sizeof(lanes));
    for (auto& block : lanes.block) block = &kNoBlock;
    for (auto& x : lanes.block_index[0]) x = kMaxBlockCoord + 1;  // out of range: no block
    // Starts lane l's march of the ray through `pixel` from z_begin to z_end. The lane keeps
    // its last block (index and pointer): the next ray, a nearby pixel's, often starts in it.
    auto start = [&](int l, const Eigen::Vector3f& dir_W, float z_begin, float z_end,
                     float z_skipped, size_t pixel) {
      Ray ray;
      Start(dir_W, z_begin, z_end, &ray);
      const Eigen::Vector3f dir_vox = dir_W * sampler_.inv_voxel();  // as Start computes it
      lanes.z[l] = ray.z, lanes.z_end[l] = ray.z_end;
      lanes.voxel_z[l] = ray.voxel_z, lanes.step_z[l] = ray.step_scale_z;
      for (int a = 0; a < 3; ++a) {
        lanes.dir_vox[a][l] = dir_vox[a];
        lanes.dir_W[a][l] = dir_W[a];
      }
      lanes.live[l] = -1, lanes.have_prev[l] = 0, lanes.met[l] = 0;
      lanes.pixel[l] = pixel;
      lanes.z_skipped[l] = z_skipped, lanes.z_begin[l] = z_begin;
    };
    // Crossings wait for refinement in `crossings`; a ray whose crossing had no zero resumes
    // its march from there once a lane is free, as if it had never stopped.
    Crossings crossings;
    std::vector<Resume>& resumes = resumes_;
    resumes.clear();
    size_t next = 0;
    auto start_next = [&](int l) {
      if (next < num_tasks) {
        const RayTask& task = tasks[next++];
        start(l, Direction(task), task.z_begin, task.z_end, task.z_skipped, task.pixel);
        return true;
      }
      if (!resumes.empty()) {
        const Resume r = resumes.back();
        resumes.pop_back();
        start(l, r.dir_W, r.z_b, r.z_end, -1.f, r.pixel);
        // The state Step leaves after a crossing without a zero: the negative sample is the
        // previous one, one step on.
        lanes.have_prev[l] = -1, lanes.met[l] = -1;
        lanes.prev_z[l] = r.z_b;
        lanes.prev_tsdf[l] = r.tsdf_b;
        lanes.z[l] = r.z_b + std::max(float(r.tsdf_b) * lanes.step_z[l], lanes.voxel_z[l]);
        return true;
      }
      lanes.live[l] = 0;
      return false;
    };
    // Results of a batch: written, or resumed where the crossing had no zero; lanes in `skip`
    // are not done yet.
    auto handle = [&](const Crossings& batch, unsigned found, const RayResult* results,
                      unsigned skip) {
      for (int j = 0; j < batch.count; ++j) {
        if ((skip >> j) & 1) continue;
        const Eigen::Vector3f dir_W(batch.dir_W[0][j], batch.dir_W[1][j], batch.dir_W[2][j]);
        if ((found >> j) & 1)
          write(batch.pixel[j], results[j], dir_W);
        else
          resumes.push_back(
              {dir_W, batch.z_b[j], batch.z_end[j], int16_t(batch.tsdf_b[j]), batch.pixel[j]});
      }
    };
    // Crossings whose Newton steps left their path wait in `brackets` for the bracket, which
    // is refined kPacket at a time too.
    Crossings brackets;
    auto refine_brackets = [&] {
      RayResult results[kPacket];
      handle(brackets, BracketCrossings(brackets, results), results, 0);
      brackets.count = 0;
    };
    auto refine = [&] {
      RayResult results[kPacket];
      unsigned deferred = 0;
      const unsigned found = RefineCrossings(crossings, results, &deferred);
      handle(crossings, found, results, deferred);
      for (; deferred; deferred &= deferred - 1) {
        brackets.Append(crossings, std::countr_zero(deferred));
        if (brackets.count == kPacket) refine_brackets();
      }
      crossings.count = 0;
    };
    // Lane l's ray ended with `result`: march the range it skipped when it met nothing observed
    // (as MarchInterleaved does), else write it and start the next ray. False when the lane is
    // left without a ray.
    auto finish = [&](int l, const Eigen::Vector3f& dir_W, const RayResult& result) {
      if (result.status == RayStatus::kUnobserved && lanes.z_skipped[l] >= 0.f) {
        start(l, dir_W, lanes.z_skipped[l], lanes.z_begin[l], -1.f, lanes.pixel[l]);
        return true;
      }
      write(lanes.pixel[l], result, dir_W);
      return start_next(l);
    };
    int num_live = 0;
    for (int l = 0; l < kPacketLanes; ++l) num_live += start_next(l);

    const __m256 origin_vox[3] = {_mm256_set1_ps(origin_vox_.x()), _mm256_set1_ps(origin_vox_.y()),
                                  _mm256_set1_ps(origin_vox_.z())};
    const __m256 origin_W[3] = {_mm256_set1_ps(origin_W_.x()), _mm256_set1_ps(origin_W_.y()),
                                _mm256_set1_ps(origin_W_.z())};
    const __m256 block_m = _mm256_set1_ps(sampler_.voxel_m() * kBlockSide);
    const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    const __m256i zero = _mm256_setzero_si256(), minus_one = _mm256_set1_epi32(-1);
    const __m256i min_weight_minus_one =
        _mm256_set1_epi32(int32_t(sampler_.min_weight_fixed()) - 1);
    const __m256i stop_at_back_faces = params_.stop_at_back_faces ? minus_one : zero;

    while (num_live > 0 || crossings.count > 0 || brackets.count > 0 || !resumes.empty()) {
      if (num_live == 0) {  // the last crossings, then the rays they resume
        if (crossings.count > 0) refine();
        if (brackets.count > 0) refine_brackets();
        for (int l = 0; l < kPacketLanes; ++l) num_live += start_next(l);
        continue;
      }
      for (int base = 0; base < kPacketLanes; base += kPacket) {  // lanes [base, base + 8)
        const __m256i live = avx2::Load(lanes.live + base);
        const __m256 z = avx2::LoadF(lanes.z + base);
        const __m256i in_range = _mm256_and_si256(
            live,
            _mm256_castps_si256(_mm256_cmp_ps(z, avx2::LoadF(lanes.z_end + base), _CMP_LE_OQ)));
        // The sample's voxel and block, as Step computes them.
        __m256i g[3], changed = zero;
        for (int a = 0; a < 3; ++a) {
          const __m256 p =
              _mm256_add_ps(origin_vox[a], _mm256_mul_ps(z, avx2::LoadF(lanes.dir_vox[a] + base)));
          g[a] = avx2::Floor(p);
          const __m256i b = _mm256_srai_epi32(g[a], kBlockShift);
          changed = _mm256_or_si256(
              changed, avx2::AndNot(_mm256_cmpeq_epi32(b, avx2::Load(lanes.block_index[a] + base)),
                                    minus_one));
          // Lanes out of range keep theirs, which stays their block's index for the next ray.
          avx2::Store(lanes.block_index[a] + base,
                      _mm256_blendv_epi8(avx2::Load(lanes.block_index[a] + base), b, in_range));
        }
        changed = _mm256_and_si256(changed, in_range);
        for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(changed)); bits; bits &= bits - 1) {
          const int l = base + std::countr_zero(unsigned(bits));
          const TsdfBlock* block = sampler_.FindUncached(BlockIndex{
              lanes.block_index[0][l], lanes.block_index[1][l], lanes.block_index[2][l]});
          lanes.has_block[l] = block ? -1 : 0;
          lanes.block[l] = block ? block : &kNoBlock;
        }
        // tsdf[i] and weight[i] of each lane's block, loaded lane by lane (faster here than two
        // AVX2 gathers).
        alignas(32) int32_t index[kPacket], lane_tsdf[kPacket], lane_weight[kPacket];
        avx2::Store(index, avx2::LinearIndex(g));
        for (int l = 0; l < kPacket; ++l) {
          const TsdfBlock& block = *lanes.block[base + l];
          lane_tsdf[l] = block.tsdf[index[l]];
          lane_weight[l] = block.weight[index[l]];
        }
        const __m256i tsdf = avx2::Load(lane_tsdf), weight = avx2::Load(lane_weight);

        const __m256i has_block = avx2::Load(lanes.has_block + base);
        const __m256i no_block = avx2::AndNot(has_block, in_range);
        const __m256i observed = _mm256_and_si256(_mm256_and_si256(in_range, has_block),
                                                  _mm256_cmpgt_epi32(weight, min_weight_minus_one));
        const __m256i unobserved = avx2::AndNot(observed, _mm256_and_si256(in_range, has_block));
        const __m256i have_prev = avx2::Load(lanes.have_prev + base);
        const __m256i prev_tsdf = avx2::Load(lanes.prev_tsdf + base);
        const __m256i tsdf_nonneg = _mm256_cmpgt_epi32(tsdf, minus_one);
        const __m256i cross = _mm256_and_si256(
            _mm256_and_si256(observed, have_prev),
            _mm256_xor_si256(_mm256_cmpgt_epi32(prev_tsdf, minus_one), tsdf_nonneg));
        // A zero after a positive sample: one voxel on, the positive one kept (as Step does).
        const __m256i on_surface = _mm256_and_si256(
            _mm256_and_si256(observed, have_prev),
            _mm256_and_si256(_mm256_cmpeq_epi32(tsdf, zero), _mm256_cmpgt_epi32(prev_tsdf, zero)));
        const __m256i back_face = _mm256_and_si256(cross, tsdf_nonneg);
        const __m256i stop = _mm256_and_si256(back_face, stop_at_back_faces);
        const __m256i front_face = avx2::AndNot(tsdf_nonneg, cross);  // refined below
        const __m256i advance = avx2::AndNot(_mm256_or_si256(cross, on_surface), observed);
        const __m256i one_voxel = _mm256_or_si256(unobserved, avx2::AndNot(stop, back_face));

        // Where a lane without a block leaves it (nudged past the face).
        __m256 z_exit = inf;
        for (int a = 0; a < 3; ++a) {
          const __m256 d = avx2::LoadF(lanes.dir_W[a] + base);
          const __m256i face = _mm256_sub_epi32(
              avx2::Load(lanes.block_index[a] + base),
              _mm256_castps_si256(_mm256_cmp_ps(d, _mm256_setzero_ps(), _CMP_GT_OQ)));
          __m256 t = _mm256_div_ps(
              _mm256_sub_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(face), block_m), origin_W[a]), d);
          t = _mm256_blendv_ps(t, inf, _mm256_cmp_ps(d, _mm256_setzero_ps(), _CMP_EQ_OQ));
          z_exit = _mm256_min_ps(t, z_exit);
        }
        const __m256 voxel_z = avx2::LoadF(lanes.voxel_z + base);
        const __m256 tsdf_f = _mm256_cvtepi32_ps(tsdf);
        __m256 z_next = z;
        z_next = avx2::Blend(
            z_next,
            _mm256_add_ps(_mm256_max_ps(z, z_exit), _mm256_mul_ps(_mm256_set1_ps(0.01f), voxel_z)),
            no_block);
        z_next =
            avx2::Blend(z_next, _mm256_add_ps(z, voxel_z), _mm256_or_si256(one_voxel, on_surface));
        z_next = avx2::Blend(
            z_next,
            _mm256_add_ps(
                z, _mm256_max_ps(voxel_z, _mm256_mul_ps(tsdf_f, avx2::LoadF(lanes.step_z + base)))),
            advance);
        _mm256_storeu_ps(lanes.z + base, z_next);
        _mm256_storeu_ps(lanes.prev_z + base,
                         avx2::Blend(avx2::LoadF(lanes.prev_z + base), z, advance));
        avx2::Store(lanes.prev_tsdf + base, _mm256_blendv_epi8(prev_tsdf, tsdf, advance));
        avx2::Store(lanes.tsdf + base, tsdf);
        // have_prev: set by an advance, cleared by a jump or a one-voxel step, kept otherwise (on
        // the surface too).
        const __m256i cleared = _mm256_or_si256(no_block, one_voxel);
        avx2::Store(lanes.have_prev + base,
                    _mm256_or_si256(advance, avx2::AndNot(cleared, have_prev)));
        avx2::Store(lanes.met + base, _mm256_or_si256(avx2::Load(lanes.met + base), observed));

        const __m256i done =
            _mm256_or_si256(avx2::AndNot(in_range, live), _mm256_or_si256(stop, front_face));
        const int front_bits = _mm256_movemask_ps(_mm256_castsi256_ps(front_face));
        for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(done)); bits; bits &= bits - 1) {
          const int l = base + std::countr_zero(unsigned(bits));
          if ((front_bits >> (l - base)) & 1) {
            // A crossing: queued for refinement, and the lane takes the next ray.
            const int j = crossings.count++;
            for (int a = 0; a < 3; ++a) crossings.dir_W[a][j] = lanes.dir_W[a][l];
            crossings.z_a[j] = lanes.prev_z[l], crossings.z_b[j] = lanes.z[l];
            crossings.tsdf_a[j] = lanes.prev_tsdf[l], crossings.tsdf_b[j] = lanes.tsdf[l];
            crossings.voxel_z[j] = lanes.voxel_z[l], crossings.z_end[j] = lanes.z_end[l];
            crossings.pixel[j] = lanes.pixel[l];
            for (int a = 0; a < 3; ++a) crossings.block_index[a][j] = lanes.block_index[a][l];
            crossings.block[j] = lanes.block[l];
            if (crossings.count == kPacket) refine();
            num_live -= !start_next(l);
            continue;
          }
          const Eigen::Vector3f dir_W(lanes.dir_W[0][l], lanes.dir_W[1][l], lanes.dir_W[2][l]);
          RayResult result;
          if (lanes.met[l]) result.status = RayStatus::kFree;
          num_live -= !finish(l, dir_W, result);
        }
      }
    }
  }

#endif

 private:
  // The least steep slope of the normalised TSDF per voxel along a ray that Newton steps follow
  // (Refine and RefineCrossings alike).
  float MaxSlope() const { return -kMinSlopeFraction * sampler_.voxel_m() / sampler_.trunc_m(); }

  bool Sample(const Eigen::Vector3f& dir_W, float z, Cell* cell, float* tsdf,
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
  bool Refine(const Eigen::Vector3f& dir_W, float z_a, float z_b, float nearest_a, float nearest_b,
              float voxel_z, RayResult* result, bool newton = true) {
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
  bool Bracket(const Eigen::Vector3f& dir_W, float z_a, float z_b, float voxel_z, Cell* cell,
               float* z_out) {
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

  // The nearest voxels changed sign from tsdf_a >= 0 at z_a to tsdf_b < 0 at z_b: true with
  // the refined hit (or kFree when it lies outside the depth limits), false when the
  // interpolant has no zero there.
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

#if VOXPLAN_RAYCAST_AVX2
  // Crossings the packet march found, refined kPacket at a time (RefineCrossings).
  struct alignas(32) Crossings {
    float dir_W[3][kPacket], z_a[kPacket], z_b[kPacket], voxel_z[kPacket], z_end[kPacket];
    int32_t tsdf_a[kPacket], tsdf_b[kPacket];
    int32_t block_index[3][kPacket];  // the block the march sampled at z_b
    const TsdfBlock* block[kPacket];
    size_t pixel[kPacket];
    int count = 0;

    // The lanes holding a crossing (all bits set), for AVX2 code.
    VOXPLAN_TARGET_AVX2 __m256i Lanes() const {
      return _mm256_cmpgt_epi32(_mm256_set1_epi32(count),
                                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    }

    // Appends crossing j of `other`.
    void Append(const Crossings& other, int j) {
      const int i = count++;
      for (int a = 0; a < 3; ++a) {
        dir_W[a][i] = other.dir_W[a][j];
        block_index[a][i] = other.block_index[a][j];
      }
      z_a[i] = other.z_a[j], z_b[i] = other.z_b[j], voxel_z[i] = other.voxel_z[j];
      z_end[i] = other.z_end[j];
      tsdf_a[i] = other.tsdf_a[j], tsdf_b[i] = other.tsdf_b[j];
      block[i] = other.block[j];
      pixel[i] = other.pixel[j];
    }
  };
  // A ray whose crossing had no zero, to march on from it.
  struct Resume {
    Eigen::Vector3f dir_W;
    float z_b, z_end;
    int16_t tsdf_b;
    size_t pixel;
  };

  // The cells a packet of crossings last sampled, lane by lane: corner 0, its block (first the
  // block the march last sampled), the corners of a cell across block faces; the corners'
  // distances and weights are in rows_, as x-pairs (corner 2p in the low 16 bits of pair p,
  // corner 2p + 1 in the high ones), loaded lane by lane into rows that AVX2 then reads.
  struct PacketCells {
    alignas(32) int32_t base[3][kPacket] = {}, i0[kPacket] = {}, block_index[3][kPacket];
    alignas(32) const TsdfBlock* block[kPacket];
    const TsdfBlock* across_block[kPacket][8];
    int across_index[kPacket][8];
    unsigned one_block = 0;  // bit l: lane l's cell lies in block[l]
    unsigned loaded = 0;     // bit l: lane l's rows hold its cell (else an earlier batch's)

    // No cell loaded yet; each lane's block the one the march sampled last.
    explicit PacketCells(const Crossings& c) {
      std::memcpy(block_index, c.block_index, sizeof(block_index));
      std::memcpy(block, c.block, sizeof(block));
    }
  };

  // Sample (Sampler::Gather, then ValueAndGradientSse2 lane by lane) at depth z on the rays of
  // the active lanes; the other lanes' cells stay. The value, the position in the cell and the
  // gradient are those of the active lanes; returns the lanes whose eight corners are observed.
  VOXPLAN_TARGET_AVX2 __m256i SampleCells(PacketCells& cells, const __m256 dir[3], __m256 z,
                                          __m256i active, __m256* value, __m256 frac[3],
                                          __m256 gradient[3]) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256(), minus_one = _mm256_set1_epi32(-1);
    __m256i g[3], changed = zero, moved = zero, inside_block = minus_one;
    for (int a = 0; a < 3; ++a) {
      const __m256 p = _mm256_add_ps(Set(origin_W_[a]), _mm256_mul_ps(z, dir[a]));
      const __m256 q = _mm256_sub_ps(_mm256_mul_ps(p, Set(sampler_.inv_voxel())), Set(0.5f));
      g[a] = Floor(q);
      frac[a] = _mm256_sub_ps(q, _mm256_cvtepi32_ps(g[a]));
      moved =
          _mm256_or_si256(moved, AndNot(_mm256_cmpeq_epi32(g[a], Load(cells.base[a])), minus_one));
      Store(cells.base[a], _mm256_blendv_epi8(Load(cells.base[a]), g[a], active));
      const __m256i b = _mm256_srai_epi32(g[a], kBlockShift);
      changed = _mm256_or_si256(
          changed, AndNot(_mm256_cmpeq_epi32(b, Load(cells.block_index[a])), minus_one));
      Store(cells.block_index[a], _mm256_blendv_epi8(Load(cells.block_index[a]), b, active));
      // All eight corners in the block: corner 0 below its last voxel on every axis.
      inside_block = _mm256_and_si256(
          inside_block, _mm256_cmpgt_epi32(_mm256_set1_epi32(kBlockMask),
                                           _mm256_and_si256(g[a], _mm256_set1_epi32(kBlockMask))));
    }
    Store(cells.i0, _mm256_blendv_epi8(Load(cells.i0), LinearIndex(g), active));
    changed = _mm256_and_si256(changed, active);
    for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(changed)); bits; bits &= bits - 1) {
      const int l = std::countr_zero(unsigned(bits));
      const TsdfBlock* found = sampler_.FindUncached(
          BlockIndex{cells.block_index[0][l], cells.block_index[1][l], cells.block_index[2][l]});
      cells.block[l] = found ? found : &kNoBlock;
    }
    // The corners of the lanes whose cell moved (LoadCorners, LoadCornersAcross).
    auto& tsdf_pairs = rows_.tsdf_pairs;
    auto& weight_pairs = rows_.weight_pairs;
    const unsigned active_bits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(active)));
    const unsigned inside_bits = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(inside_block)));
    unsigned load =
        (unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(moved))) | ~cells.loaded) & active_bits;
    cells.loaded |= active_bits;
    for (; load; load &= load - 1) {
      const int l = std::countr_zero(load);
      if ((inside_bits >> l) & 1) {
        cells.one_block |= 1u << l;
        const int16_t* tsdf = cells.block[l]->tsdf + cells.i0[l];
        const uint16_t* weight = cells.block[l]->weight + cells.i0[l];
        for (int p = 0; p < 4; ++p) {
          std::memcpy(&tsdf_pairs[p][l], tsdf + kCornerOffset[2 * p], sizeof(uint32_t));
          std::memcpy(&weight_pairs[p][l], weight + kCornerOffset[2 * p], sizeof(uint32_t));
        }
        continue;
      }
      cells.one_block &= ~(1u << l);
      const TsdfBlock** blocks = cells.across_block[l];
      const int* index = cells.across_index[l];
      sampler_.CornersAcross(GlobalVoxelIndex{cells.base[0][l], cells.base[1][l], cells.base[2][l]},
                             blocks, cells.across_index[l]);
      for (int p = 0; p < 4; ++p) {
        const int lo = 2 * p, hi = 2 * p + 1;
        tsdf_pairs[p][l] = uint32_t(uint16_t(blocks[lo]->tsdf[index[lo]])) |
                           uint32_t(uint16_t(blocks[hi]->tsdf[index[hi]])) << 16;
        weight_pairs[p][l] =
            uint32_t(blocks[lo]->weight[index[lo]]) | uint32_t(blocks[hi]->weight[index[hi]]) << 16;
      }
    }
    // Decoded as LoadCorners does.
    const __m256i min_weight_minus_one =
        _mm256_set1_epi32(int32_t(sampler_.min_weight_fixed()) - 1);
    __m256 t[8];
    __m256i complete = minus_one;
    const __m256i low16 = _mm256_set1_epi32(0xffff);
    for (int p = 0; p < 4; ++p) {
      const __m256i tsdf = Load(tsdf_pairs[p]), weight = Load(weight_pairs[p]);
      t[2 * p] = Decode(_mm256_srai_epi32(_mm256_slli_epi32(tsdf, 16), 16));
      t[2 * p + 1] = Decode(_mm256_srai_epi32(tsdf, 16));
      complete = _mm256_and_si256(
          complete, _mm256_and_si256(
                        _mm256_cmpgt_epi32(_mm256_and_si256(weight, low16), min_weight_minus_one),
                        _mm256_cmpgt_epi32(_mm256_srli_epi32(weight, 16), min_weight_minus_one)));
    }
    // ValueAndGradientSse2, lane by lane: edge j of four per axis, then the four summed in
    // pairs.
    const __m256 fx = frac[0], fy = frac[1], fz = frac[2];
    __m256 v[4], gx[4], gy[4], gz[4];
    for (int j = 0; j < 4; ++j) {
      const bool odd = j & 1, high = j >= 2;
      const __m256 wx = Lerp(odd, fx), wy = Lerp(high, fy), wz = Lerp(high, fz);
      const __m256 wy_edge = Lerp(odd, fy);
      const __m256 d_z = _mm256_sub_ps(t[j + 4], t[j]);
      static constexpr int kX[4][2] = {{1, 0}, {3, 2}, {5, 4}, {7, 6}};
      static constexpr int kY[4][2] = {{2, 0}, {3, 1}, {6, 4}, {7, 5}};
      const __m256 d_x = _mm256_sub_ps(t[kX[j][0]], t[kX[j][1]]);
      const __m256 d_y = _mm256_sub_ps(t[kY[j][0]], t[kY[j][1]]);
      const __m256 wxy = _mm256_mul_ps(wx, wy);
      v[j] = _mm256_mul_ps(wxy, _mm256_add_ps(t[j], _mm256_mul_ps(fz, d_z)));
      gx[j] = _mm256_mul_ps(_mm256_mul_ps(wy_edge, wz), d_x);
      gy[j] = _mm256_mul_ps(_mm256_mul_ps(wx, wz), d_y);
      gz[j] = _mm256_mul_ps(wxy, d_z);
    }
    *value = Sum4(v);
    gradient[0] = Sum4(gx), gradient[1] = Sum4(gy), gradient[2] = Sum4(gz);
    return complete;
  }

  // SampleCells for the bracket: a lane whose cell has an unobserved corner leaves `live` for
  // `scalar` (Cross then refines it itself).
  VOXPLAN_TARGET_AVX2 __m256 SampleLive(PacketCells& cells, const __m256 dir[3], __m256 z,
                                        __m256i* live, __m256i* scalar, __m256 frac[3],
                                        __m256 gradient[3]) {
    __m256 value;
    const __m256i complete = SampleCells(cells, dir, z, *live, &value, frac, gradient);
    *scalar = _mm256_or_si256(*scalar, avx2::AndNot(complete, *live));
    *live = _mm256_and_si256(*live, complete);
    return value;
  }

  // Cross for each of the crossings, as if called one by one: bit j of the result set when
  // crossing j has its result in results[j], clear when the interpolant has no zero there.
  // Refine runs in AVX2 lanes with the scalar code's float operations in its order, so the
  // results are the same bytes: two Newton steps on complete cells, then normal and colour. The
  // lanes that leave that path (a grazing slope, a step out of bounds, an unobserved corner)
  // are set in `deferred`, for BracketCrossings.
  VOXPLAN_TARGET_AVX2 unsigned RefineCrossings(const Crossings& c, RayResult results[kPacket],
                                               unsigned* deferred) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256();
    const __m256 dir[3] = {LoadF(c.dir_W[0]), LoadF(c.dir_W[1]), LoadF(c.dir_W[2])};
    const __m256 z_a = LoadF(c.z_a), z_b = LoadF(c.z_b), voxel_z = LoadF(c.voxel_z);
    const __m256 nearest_a = Decode(Load(c.tsdf_a)), nearest_b = Decode(Load(c.tsdf_b));
    const __m256 max_slope = Set(MaxSlope());
    const __m256 dq_dz = Set(sampler_.inv_voxel());
    const __m256i valid = c.Lanes();
    // Lanes on the Newton path (`ok`) and those done with their Newton steps.
    __m256i ok = valid, converged = zero;
    __m256 z = Secant(z_a, z_b, nearest_a, nearest_b);
    PacketCells cells(c);
    __m256 frac[3] = {}, gradient[3] = {};
    for (int k = 0; k < kNewtonIterations; ++k) {
      const __m256i active = AndNot(converged, ok);
      if (!_mm256_movemask_ps(_mm256_castsi256_ps(active))) break;
      __m256 f, f_new[3], g_new[3];
      const __m256i complete = SampleCells(cells, dir, z, active, &f, f_new, g_new);
      ok = AndNot(AndNot(complete, active), ok);
      // Refine's Newton step; Eigen's dot sums x + (y + z).
      const __m256 slope = _mm256_mul_ps(
          _mm256_add_ps(
              _mm256_mul_ps(g_new[0], dir[0]),
              _mm256_add_ps(_mm256_mul_ps(g_new[1], dir[1]), _mm256_mul_ps(g_new[2], dir[2]))),
          dq_dz);
      const __m256 dz = _mm256_div_ps(_mm256_sub_ps(_mm256_setzero_ps(), f), slope);
      const __m256 z_next = _mm256_add_ps(z, dz);
      const __m256 steep = _mm256_cmp_ps(_mm256_mul_ps(slope, voxel_z), max_slope, _CMP_LT_OQ);
      const __m256 inside =
          _mm256_and_ps(_mm256_cmp_ps(z_next, _mm256_sub_ps(z_a, voxel_z), _CMP_GT_OQ),
                        _mm256_cmp_ps(z_next, _mm256_add_ps(z_b, voxel_z), _CMP_LT_OQ));
      ok = AndNot(AndNot(_mm256_castps_si256(_mm256_and_ps(steep, inside)), active), ok);
      const __m256i stepped = _mm256_and_si256(active, ok);
      z = Blend(z, z_next, stepped);
      for (int a = 0; a < 3; ++a) {
        frac[a] = Blend(frac[a], f_new[a], stepped);
        gradient[a] = Blend(gradient[a], g_new[a], stepped);
      }
      const __m256 abs_dz = _mm256_andnot_ps(Set(-0.f), dz);
      const __m256i small = _mm256_castps_si256(
          _mm256_cmp_ps(abs_dz, _mm256_mul_ps(Set(kConvergedVoxels), voxel_z), _CMP_LT_OQ));
      converged = _mm256_or_si256(
          converged, k + 1 == kNewtonIterations ? stepped : _mm256_and_si256(stepped, small));
    }
    ok = _mm256_and_si256(ok, converged);

    *deferred = unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(AndNot(ok, valid))));
    return FinishCrossings(c, cells, ok, zero, z, frac, gradient, results);
  }

  // Refine's bracket (regula falsi on the trilinear interpolant, Bracket) for each of the
  // crossings, then normal and colour, in AVX2 lanes with the scalar code's float operations in
  // its order; bit j of the result as RefineCrossings'. A lane that meets an unobserved corner
  // is refined by Cross itself.
  VOXPLAN_TARGET_AVX2 unsigned BracketCrossings(const Crossings& c, RayResult results[kPacket]) {
    using namespace avx2;
    const __m256 dir[3] = {LoadF(c.dir_W[0]), LoadF(c.dir_W[1]), LoadF(c.dir_W[2])};
    const __m256 voxel_z = LoadF(c.voxel_z);
    __m256i live = c.Lanes();
    __m256i scalar = _mm256_setzero_si256();
    PacketCells cells(c);
    const __m256 zero_f = _mm256_setzero_ps();
    __m256 frac[3], gradient[3];
    __m256 za = LoadF(c.z_a), zb = LoadF(c.z_b);
    __m256 fa = SampleLive(cells, dir, za, &live, &scalar, frac, gradient);
    __m256 fb = SampleLive(cells, dir, zb, &live, &scalar, frac, gradient);
    // Moved back while f_a < 0, then on while f_b >= 0, a voxel at a time.
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < kMaxBracketShifts; ++k) {
        const __m256i shift = _mm256_and_si256(
            live, _mm256_castps_si256(side == 0 ? _mm256_cmp_ps(fa, zero_f, _CMP_LT_OQ)
                                                : _mm256_cmp_ps(fb, zero_f, _CMP_GE_OQ)));
        if (!_mm256_movemask_ps(_mm256_castsi256_ps(shift))) break;
        __m256i sampled = shift;
        if (side == 0) {
          zb = Blend(zb, za, shift), fb = Blend(fb, fa, shift);
          za = Blend(za, _mm256_sub_ps(za, voxel_z), shift);
          fa = Blend(fa, SampleLive(cells, dir, za, &sampled, &scalar, frac, gradient), sampled);
        } else {
          za = Blend(za, zb, shift), fa = Blend(fa, fb, shift);
          zb = Blend(zb, _mm256_add_ps(zb, voxel_z), shift);
          fb = Blend(fb, SampleLive(cells, dir, zb, &sampled, &scalar, frac, gradient), sampled);
        }
        live = AndNot(AndNot(sampled, shift), live);
      }
    const __m256i straddles = _mm256_castps_si256(_mm256_and_ps(
        _mm256_cmp_ps(fa, zero_f, _CMP_GE_OQ), _mm256_cmp_ps(fb, zero_f, _CMP_LT_OQ)));
    live = _mm256_and_si256(live, straddles);  // the others have no zero
    // Regula falsi; a lane meeting an unobserved corner goes to Cross.
    for (int k = 0; k < kSecantIterations; ++k) {
      const __m256 zr = Secant(za, zb, fa, fb);
      const __m256 f = SampleLive(cells, dir, zr, &live, &scalar, frac, gradient);
      const __m256 positive = _mm256_cmp_ps(f, zero_f, _CMP_GE_OQ);
      const __m256i to_a = _mm256_and_si256(live, _mm256_castps_si256(positive));
      const __m256i to_b = AndNot(_mm256_castps_si256(positive), live);
      za = Blend(za, zr, to_a), fa = Blend(fa, f, to_a);
      zb = Blend(zb, zr, to_b), fb = Blend(fb, f, to_b);
    }
    // The cell at the final point gives the gradient and the colour.
    const __m256 z_out = Secant(za, zb, fa, fb);
    SampleLive(cells, dir, z_out, &live, &scalar, frac, gradient);
    return FinishCrossings(c, cells, live, scalar, z_out, frac, gradient, results);
  }

  // The results of a batch of crossings: for the `ok` lanes the hit at z with the normal from
  // `gradient` and the colour of the cell at `frac`, for the `scalar` ones Cross; bit j of the
  // result as RefineCrossings'.
  VOXPLAN_TARGET_AVX2 unsigned FinishCrossings(const Crossings& c, const PacketCells& cells,
                                               __m256i ok, __m256i scalar, __m256 z,
                                               const __m256 frac[3], const __m256 gradient[3],
                                               RayResult results[kPacket]) {
    using namespace avx2;
    const __m256i zero = _mm256_setzero_si256();
    alignas(32) float z_out[kPacket], normal[3][kPacket];
    alignas(32) uint32_t color[kPacket];
    _mm256_store_ps(z_out, z);
    if (params_.with_normals) {
      const __m256 norm =
          _mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(gradient[0], gradient[0]),
                                       _mm256_add_ps(_mm256_mul_ps(gradient[1], gradient[1]),
                                                     _mm256_mul_ps(gradient[2], gradient[2]))));
      const __m256 positive = _mm256_cmp_ps(norm, _mm256_setzero_ps(), _CMP_GT_OQ);
      for (int a = 0; a < 3; ++a)
        _mm256_store_ps(normal[a],
                        _mm256_blendv_ps(Set(kNaN), _mm256_div_ps(gradient[a], norm), positive));
    }
    if (params_.with_color) {
      // BlendChannelsSse2, lane by lane: corner-pair j of each channel, the pairs summed in
      // pairs.
      const __m256 fx = frac[0], fy = frac[1], fz = frac[2];
      __m256 w_lo[4], w_hi[4];
      for (int j = 0; j < 4; ++j) {
        const __m256 wxy = _mm256_mul_ps(Lerp(j & 1, fx), Lerp(j >= 2, fy));
        w_lo[j] = _mm256_mul_ps(wxy, _mm256_sub_ps(Set(1.f), fz));
        w_hi[j] = _mm256_mul_ps(wxy, fz);
      }
      __m256 w[4];
      for (int j = 0; j < 4; ++j) w[j] = _mm256_add_ps(w_lo[j], w_hi[j]);
      const __m256 sum_w = Sum4(w);
      const __m256 inv = _mm256_div_ps(Set(1.f), sum_w);
      // The corners' colours as x-pairs (corner 2p in the low byte of pair p, 2p + 1 next).
      auto& color_pairs = rows_.color_pairs;
      for (int bits = _mm256_movemask_ps(_mm256_castsi256_ps(ok)); bits; bits &= bits - 1) {
        const int l = std::countr_zero(unsigned(bits));
        if ((cells.one_block >> l) & 1) {
          const uint8_t* channel[3] = {cells.block[l]->r, cells.block[l]->g, cells.block[l]->b};
          for (int ch = 0; ch < 3; ++ch)
            for (int p = 0; p < 4; ++p) {
              uint16_t pair;
              std::memcpy(&pair, channel[ch] + cells.i0[l] + kCornerOffset[2 * p], sizeof(pair));
              color_pairs[ch][p][l] = pair;
            }
          continue;
        }
        for (int p = 0; p < 4; ++p) {
          const TsdfBlock &lo = *cells.across_block[l][2 * p],
                          &hi = *cells.across_block[l][2 * p + 1];
          const int i_lo = cells.across_index[l][2 * p], i_hi = cells.across_index[l][2 * p + 1];
          color_pairs[0][p][l] = uint32_t(lo.r[i_lo]) | uint32_t(hi.r[i_hi]) << 8;
          color_pairs[1][p][l] = uint32_t(lo.g[i_lo]) | uint32_t(hi.g[i_hi]) << 8;
          color_pairs[2][p][l] = uint32_t(lo.b[i_lo]) | uint32_t(hi.b[i_hi]) << 8;
        }
      }
      __m256i rgb = zero;
      for (int ch = 0; ch < 3; ++ch) {
        __m256 corner[8], pair[4];
        for (int p = 0; p < 4; ++p) {
          const __m256i pairs = Load(color_pairs[ch][p]);
          corner[2 * p] = _mm256_cvtepi32_ps(_mm256_and_si256(pairs, _mm256_set1_epi32(0xff)));
          corner[2 * p + 1] = _mm256_cvtepi32_ps(_mm256_srli_epi32(pairs, 8));
        }
        for (int j = 0; j < 4; ++j)
          pair[j] = _mm256_add_ps(_mm256_mul_ps(corner[j], w_lo[j]),
                                  _mm256_mul_ps(corner[j + 4], w_hi[j]));
        const __m256 scaled = _mm256_add_ps(_mm256_mul_ps(Sum4(pair), inv), Set(0.5f));
        const __m256i c8 = _mm256_cvttps_epi32(
            _mm256_min_ps(_mm256_max_ps(scaled, _mm256_setzero_ps()), Set(255.f)));
        rgb = _mm256_or_si256(rgb, _mm256_slli_epi32(c8, 8 * ch));
      }
      const __m256i positive =
          _mm256_castps_si256(_mm256_cmp_ps(sum_w, _mm256_setzero_ps(), _CMP_GT_OQ));
      Store(color, _mm256_and_si256(rgb, positive));
    }

    const int ok_bits = _mm256_movemask_ps(_mm256_castsi256_ps(ok));
    const int scalar_bits = _mm256_movemask_ps(_mm256_castsi256_ps(scalar));
    unsigned found = 0;
    for (int j = 0; j < c.count; ++j) {
      const Eigen::Vector3f dir_W(c.dir_W[0][j], c.dir_W[1][j], c.dir_W[2][j]);
      RayResult& result = results[j];
      result = RayResult{};
      result.status = RayStatus::kFree;  // the march met observed voxels
      if ((scalar_bits >> j) & 1) {
        found |= unsigned(Cross(dir_W, c.z_a[j], c.z_b[j], int16_t(c.tsdf_a[j]),
                                int16_t(c.tsdf_b[j]), c.voxel_z[j], &result, /*newton=*/false))
                 << j;
        continue;
      }
      if (!((ok_bits >> j) & 1)) continue;  // the bracket found no zero
      found |= 1u << j;
      if (z_out[j] < params_.min_depth_m || z_out[j] > params_.max_depth_m) continue;  // kFree
      result.status = RayStatus::kHit;
      result.z = z_out[j];
      if (params_.with_normals) result.normal_W = {normal[0][j], normal[1][j], normal[2][j]};
      if (params_.with_color) result.color = color[j];
    }
    return found;
  }
#endif

  Sampler sampler_;
  RaycastParams params_;
#if VOXPLAN_RAYCAST_AVX2
  std::vector<Resume> resumes_;  // MarchPackets', kept for its capacity
  // RefineCrossings' rows of corner values, kept between batches (zeroing them per batch cost
  // 5 % of the refinement): a lane reads only what its own crossing loaded.
  struct alignas(32) Rows {
    uint32_t tsdf_pairs[4][kPacket] = {}, weight_pairs[4][kPacket] = {};
    uint32_t color_pairs[3][4][kPacket] = {};
  } rows_;
#endif
  Eigen::Vector3f origin_W_, d0_W_, du_W_, dv_W_, origin_vox_;
#if VOXPLAN_RAYCAST_SSE2
  __m128 origin_vox_lanes_;
#endif
  float step_scale_;  // stored fixed-point TSDF to a step in metres along the ray
};

// n pixels of an image row. Eigen's fixed-size vectors are plain floats, but not trivially
// copy-assignable by the letter of the type: memcpy through void*.
template <class T>
void CopyPixels(T* dst, const T* src, size_t n) {
  static_assert(std::is_standard_layout_v<T> && std::is_trivially_destructible_v<T>);
  constexpr size_t kRowBytes = kTile * sizeof(T);
#if defined(__SSE2__)
  // A whole tile row of whole cache lines (images start on one, so with a width divisible by
  // 16 every such row does) in streaming stores: the outputs, 10 MB at 640 x 480, are far
  // larger than the caches, and a plain store first reads each line in.
  if (kRowBytes % 64 == 0 && n == size_t(kTile) && reinterpret_cast<uintptr_t>(dst) % 64 == 0) {
    auto* d = static_cast<__m128i*>(static_cast<void*>(dst));
    const auto* s = static_cast<const __m128i*>(static_cast<const void*>(src));
    for (size_t k = 0; k < kRowBytes / 16; ++k) _mm_stream_si128(d + k, _mm_loadu_si128(s + k));
    return;
  }
#endif
  // Otherwise a whole row as a copy of known size, which the compiler inlines as vector moves:
  // a library call per row of 16 to 192 bytes cost more than the copy.
  if (n == size_t(kTile)) {
    std::memcpy(static_cast<void*>(dst), static_cast<const void*>(src), kRowBytes);
    return;
  }
  std::memcpy(static_cast<void*>(dst), static_cast<const void*>(src), n * sizeof(T));
}

}  // namespace

void Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
             const RaycastParams& params, RaycastImages& images) {
  if (!camera.Valid()) {
    images = RaycastImages{};
    return;
  }
  const int w = camera.width, h = camera.height;
  auto fit = [w, h](auto& image, auto fill) {
    if (image.width != w || image.height != h) image = std::decay_t<decltype(image)>(w, h, fill);
  };
  const Eigen::Vector3f nan3(kNaN, kNaN, kNaN);
  fit(images.depth, 0.f);
  fit(images.vertex_W, nan3);
  fit(images.normal_W, nan3);
  fit(images.color, uint32_t{0});
  fit(images.status, uint8_t(RayStatus::kUnobserved));

  const bool usable = T_W_C.matrix().allFinite() && params.min_depth_m <= params.max_depth_m &&
                      std::isfinite(params.min_depth_m) && std::isfinite(params.max_depth_m) &&
                      volume.num_blocks() > 0;
  const RangeImage range =
      usable ? BuildRangeImage(volume, camera, T_W_C.inverse(), params) : RangeImage{};
  const float z_start = MarchStart(volume, params);
  const Eigen::Matrix3f R_W_C = T_W_C.linear();
  const Eigen::Vector3f origin_W = T_W_C.translation();
  // The ray through pixel (u, v), scaled to unit optical depth: d0 + u du + v dv.
  const Eigen::Vector3f du_W = R_W_C.col(0) / camera.fx, dv_W = R_W_C.col(1) / camera.fy;
  const Eigen::Vector3f d0_W = R_W_C.col(2) - camera.cx * du_W - camera.cy * dv_W;
  // surface_z_min already bounds every negative voxel's cube, so the first sample in front of
  // it is never negative; half a voxel more absorbs rounding, and more only adds steps.
  const float surface_margin = 0.5f * volume.voxel_size_m();
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  static_assert(kTile % kRangeCell == 0 && kRangeCell % kSurfaceCell == 0);
  const float max_depth_m = params.max_depth_m;

  // Results go to a batch's own images first (a pixel's index there is its tile's place in
  // the batch, then its row and column in the tile) and then row by row to `images`: scattered
  // stores of a few bytes into images far larger than the caches were the slower way.
  constexpr int kBatchPixels = kTilesPerBatch * kTile * kTile;
  struct BatchImages {
    float depth[kBatchPixels];
    Eigen::Vector3f vertex_W[kBatchPixels], normal_W[kBatchPixels];
    uint32_t color[kBatchPixels];
    uint8_t status[kBatchPixels];
  };

#if VOXPLAN_RAYCAST_AVX2
  const bool packets = params.simd && RaycastSimdAvailable();
#endif
  ParallelFor(size_t(tiles_x) * size_t(tiles_y), kTilesPerBatch, [&](size_t begin, size_t end) {
    RayCaster caster(volume, params, origin_W, d0_W, du_W, dv_W);
    const RayResult unobserved;
    RayTask tasks[kBatchPixels];
    auto batch = std::make_unique<BatchImages>();
    BatchImages& out = *batch;
    auto write = [&](size_t i, const RayResult& ray, const Eigen::Vector3f& dir_W) {
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
    };
    for (size_t first = begin; first < end; first += kTilesPerBatch) {
      const size_t last = std::min(first + kTilesPerBatch, end);
      // First the pixels whose rays have a range to march, tile by tile and row by row; the
      // others are written as unobserved at once.
      size_t num_tasks = 0;
      for (size_t tile = first; tile < last; ++tile) {
        const int u0 = int(tile % size_t(tiles_x)) * kTile,
                  v0 = int(tile / size_t(tiles_x)) * kTile;
        const int u_end = std::min(u0 + kTile, w), v_end = std::min(v0 + kTile, h);
        for (int v = v0; v < v_end; ++v) {
          const size_t row_i = (tile - first) * kTile * kTile + size_t(v - v0) * kTile;
          auto write_unobserved = [&](int u_begin, int u_stop) {
            for (int u = u_begin; u < u_stop; ++u) write(row_i + size_t(u - u0), unobserved, d0_W);
          };
          if (!usable) {
            write_unobserved(u0, u_end);
            continue;
          }
          const size_t range_row = size_t(v / kRangeCell) * size_t(range.cols);
          const float* z_min_row = range.z_min.data() + range_row;
          const float* z_max_row = range.z_max.data() + range_row;
          const float* surface_row =
              range.surface_z_min.data() + size_t(v / kSurfaceCell) * size_t(range.surface_cols);
          // A range cell's pixels of the row share its depth range (tiles start on a cell edge).
          for (int u_cell = u0; u_cell < u_end; u_cell += kRangeCell) {
            const int u_cell_end = std::min(u_cell + kRangeCell, u_end);
            const float z_all = std::max(z_min_row[u_cell / kRangeCell], z_start);
            const float z_end = std::min(z_max_row[u_cell / kRangeCell], max_depth_m);
            if (!(z_all <= z_end)) {
              write_unobserved(u_cell, u_cell_end);
              continue;
            }
            for (int u = u_cell; u < u_cell_end; ++u) {
              // Start just in front of the nearest cube of a negative voxel: no crossing can end
              // before it.
              const float z_surface =
                  std::max(surface_row[u / kSurfaceCell] - surface_margin, z_all);
              const bool skip = z_surface <= z_end && z_surface > z_all;
              const float z_begin = skip ? z_surface : z_all, z_skipped = skip ? z_all : -1.f;
              tasks[num_tasks++] = {row_i + size_t(u - u0), u, v, z_begin, z_end, z_skipped};
            }
          }
        }
      }
#if VOXPLAN_RAYCAST_AVX2
      if (packets)
        caster.MarchPackets(tasks, num_tasks, write);
      else
#endif
        caster.MarchInterleaved(tasks, num_tasks, write);
      for (size_t tile = first; tile < last; ++tile) {
        const int u0 = int(tile % size_t(tiles_x)) * kTile,
                  v0 = int(tile / size_t(tiles_x)) * kTile;
        const size_t n = size_t(std::min(u0 + kTile, w) - u0);
        for (int v = v0; v < std::min(v0 + kTile, h); ++v) {
          const size_t i = (tile - first) * kTile * kTile + size_t(v - v0) * kTile;
          const size_t px = size_t(v) * size_t(w) + size_t(u0);
          CopyPixels(&images.status.data[px], &out.status[i], n);
          CopyPixels(&images.depth.data[px], &out.depth[i], n);
          CopyPixels(&images.vertex_W.data[px], &out.vertex_W[i], n);
          CopyPixels(&images.normal_W.data[px], &out.normal_W[i], n);
          CopyPixels(&images.color.data[px], &out.color[i], n);
        }
      }
    }
#if defined(__SSE2__)
    _mm_sfence();  // the streaming stores are weakly ordered: done before the work item ends
#endif
  });
}

bool RaycastSimdAvailable() {
#if VOXPLAN_RAYCAST_AVX2
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
#else
  return false;
#endif
}

RaycastImages Raycast(const TsdfVolume& volume, const PinholeCamera& camera, const Pose3f& T_W_C,
                      const RaycastParams& params) {
  RaycastImages images;
  Raycast(volume, camera, T_W_C, params, images);
  return images;
}

}  // namespace voxplan
