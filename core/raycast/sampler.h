#pragma once
// Internal to core/raycast/: what both marches read the map through: a worker's block lookups
// (a small cache in front of the hash map), the 2x2x2 cell around a point with its corners'
// distances (Sampler::Gather), and the cell's trilinear colour. Inline: called per sample.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/block.h"
#include "core/image.h"
#include "core/index.h"
#include "core/raycast.h"
#include "core/raycast/raycast_kernels.h"
#include "core/volume.h"

namespace voxplan::raycast_detail {

// Read where a ray has no block: never observed. Hidden, so that the -fPIC library addresses it
// directly rather than through the GOT (a load in the packet march's inner loops).
[[gnu::visibility("hidden")]] inline const TsdfBlock kNoBlock{};

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
      const TsdfBlock* found = cache_.Find(BlockIndex{b0.x + dx, b0.y + dy, b0.z + dz});
      return found ? found : &kNoBlock;
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

// Trilinear colour over the observed corners.
inline uint32_t CellColor(const Cell& cell) {
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

}  // namespace voxplan::raycast_detail
