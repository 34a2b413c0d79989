#pragma once
// The voxel block: a plain 8^3 structure of arrays, 7 bytes per voxel with colour.
// TSDF is stored normalised by the truncation distance as 16-bit fixed point (step 1/32767 of
// the truncation, about 1.2 um at 4 cm); weight as 16-bit fixed point in 1/128 steps.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/index.h"

namespace voxplan {

inline constexpr float kTsdfScale = 32767.0f;
inline constexpr float kWeightScale = 128.0f;
inline constexpr float kMaxWeight = 65535.0f / kWeightScale;  // 511.99

struct TsdfBlock {
  int16_t tsdf[kBlockVoxels];     // normalised signed distance in [-1, 1], fixed point
  uint16_t weight[kBlockVoxels];  // fusion weight, fixed point; 0 = never observed
  uint8_t r[kBlockVoxels];
  uint8_t g[kBlockVoxels];
  uint8_t b[kBlockVoxels];
};
static_assert(std::is_trivially_copyable_v<TsdfBlock>);
static_assert(sizeof(TsdfBlock) == 7 * kBlockVoxels);

inline float DecodeTsdf(int16_t v) { return float(v) * (1.0f / kTsdfScale); }
inline int16_t EncodeTsdf(float tsdf) {
  return int16_t(std::nearbyint(std::clamp(tsdf, -1.0f, 1.0f) * kTsdfScale));
}
inline float DecodeWeight(uint16_t w) { return float(w) * (1.0f / kWeightScale); }
inline uint16_t EncodeWeight(float w) {
  return uint16_t(std::nearbyint(std::clamp(w, 0.0f, kMaxWeight) * kWeightScale));
}

// A fresh block: unobserved, TSDF +1 (free), black.
void ResetBlock(TsdfBlock& block);

}  // namespace voxplan
