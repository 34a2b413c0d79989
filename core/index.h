#pragma once
// Strong index types and every floor-division conversion between them. Voxel g covers
// [g * s, (g + 1) * s) on each axis, so its centre is (g + 0.5) * s; a block holds 8^3 voxels.
#include <Eigen/Core>
#include <cmath>
#include <compare>
#include <cstdint>

namespace voxplan {

inline constexpr int kBlockShift = 3;
inline constexpr int kBlockSide = 1 << kBlockShift;  // 8
inline constexpr int kBlockMask = kBlockSide - 1;
inline constexpr int kBlockVoxels = kBlockSide * kBlockSide * kBlockSide;  // 512

struct BlockIndex {
  int32_t x = 0, y = 0, z = 0;
  // z-major order (z, then y, then x) so sorted blocks are visited row by row in memory order.
  friend constexpr auto operator<=>(const BlockIndex& a, const BlockIndex& b) {
    if (auto c = a.z <=> b.z; c != 0) return c;
    if (auto c = a.y <=> b.y; c != 0) return c;
    return a.x <=> b.x;
  }
  friend constexpr bool operator==(const BlockIndex&, const BlockIndex&) = default;
};

// A voxel inside its block, each coordinate in [0, 8).
struct VoxelIndex {
  int32_t x = 0, y = 0, z = 0;
  friend constexpr bool operator==(const VoxelIndex&, const VoxelIndex&) = default;
};

struct GlobalVoxelIndex {
  int32_t x = 0, y = 0, z = 0;
  friend constexpr auto operator<=>(const GlobalVoxelIndex& a, const GlobalVoxelIndex& b) {
    if (auto c = a.z <=> b.z; c != 0) return c;
    if (auto c = a.y <=> b.y; c != 0) return c;
    return a.x <=> b.x;
  }
  friend constexpr bool operator==(const GlobalVoxelIndex&, const GlobalVoxelIndex&) = default;
};

// Floor division by the block side: an arithmetic shift, correct for negative coordinates.
constexpr BlockIndex BlockOf(GlobalVoxelIndex g) {
  return {g.x >> kBlockShift, g.y >> kBlockShift, g.z >> kBlockShift};
}
constexpr VoxelIndex LocalOf(GlobalVoxelIndex g) {
  return {g.x & kBlockMask, g.y & kBlockMask, g.z & kBlockMask};
}
constexpr GlobalVoxelIndex GlobalOf(BlockIndex b, VoxelIndex v) {
  return {b.x * kBlockSide + v.x, b.y * kBlockSide + v.y, b.z * kBlockSide + v.z};
}
// x varies fastest, so an x-row of 8 voxels is contiguous (one SIMD register of floats).
constexpr int LinearIndex(VoxelIndex v) { return v.x + kBlockSide * (v.y + kBlockSide * v.z); }
constexpr int LinearIndex(int x, int y, int z) { return x + kBlockSide * (y + kBlockSide * z); }
constexpr VoxelIndex VoxelOfLinear(int i) {
  return {i & kBlockMask, (i >> kBlockShift) & kBlockMask, i >> (2 * kBlockShift)};
}

// floor() as an int without a libm call (portable x86-64 builds have no SSE4.1 round
// instruction, and std::floor then costs a function call). Exact for |x| < 2^31.
constexpr int32_t FloorToInt(float x) {
  const int32_t i = int32_t(x);
  return i - int32_t(x < float(i));
}

inline GlobalVoxelIndex VoxelAt(const Eigen::Vector3f& p_W, float voxel_size_m) {
  const float inv = 1.0f / voxel_size_m;
  return {FloorToInt(p_W.x() * inv), FloorToInt(p_W.y() * inv), FloorToInt(p_W.z() * inv)};
}
inline BlockIndex BlockAt(const Eigen::Vector3f& p_W, float block_size_m) {
  const float inv = 1.0f / block_size_m;
  return {FloorToInt(p_W.x() * inv), FloorToInt(p_W.y() * inv), FloorToInt(p_W.z() * inv)};
}
inline Eigen::Vector3f VoxelCenter(GlobalVoxelIndex g, float voxel_size_m) {
  return {(float(g.x) + 0.5f) * voxel_size_m, (float(g.y) + 0.5f) * voxel_size_m,
          (float(g.z) + 0.5f) * voxel_size_m};
}
inline Eigen::Vector3f BlockOrigin(BlockIndex b, float block_size_m) {
  return {float(b.x) * block_size_m, float(b.y) * block_size_m, float(b.z) * block_size_m};
}

// Block coordinates are packed 21 bits each: +-2^20 blocks, 42 km at 5 mm voxels.
inline constexpr int32_t kMaxBlockCoord = (1 << 20) - 1;
constexpr bool InPackRange(BlockIndex b) {
  return b.x >= -kMaxBlockCoord && b.x <= kMaxBlockCoord && b.y >= -kMaxBlockCoord &&
         b.y <= kMaxBlockCoord && b.z >= -kMaxBlockCoord && b.z <= kMaxBlockCoord;
}
constexpr uint64_t PackBlockIndex(BlockIndex b) {
  constexpr uint64_t m = (1u << 21) - 1;
  return (uint64_t(uint32_t(b.x)) & m) | ((uint64_t(uint32_t(b.y)) & m) << 21) |
         ((uint64_t(uint32_t(b.z)) & m) << 42);
}
constexpr BlockIndex UnpackBlockIndex(uint64_t k) {
  auto sext = [](uint64_t v) { return int32_t(uint32_t(v << 11)) >> 11; };
  return {sext(k & 0x1fffff), sext((k >> 21) & 0x1fffff), sext((k >> 42) & 0x1fffff)};
}

}  // namespace voxplan
