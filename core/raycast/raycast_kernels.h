#pragma once
// Inner kernels of the TSDF ray caster (core/raycast/), each as a portable scalar reference
// and an SSE2 version (x86-64's baseline, so no runtime CPU check is needed). Kept in a header
// so that the caster inlines them and the tests can check the two against each other.
// A cell position `frac` is four floats: x, y, z in [0, 1] and one that is read but unused.
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "core/block.h"
#include "core/image.h"
#include "core/index.h"

#if defined(__SSE2__) && !defined(VOXPLAN_RAYCAST_NO_SSE2)  // the define: check the scalar paths
#include <emmintrin.h>
#define VOXPLAN_RAYCAST_SSE2 1
#else
#define VOXPLAN_RAYCAST_SSE2 0
#endif

namespace voxplan::raycast_detail {

// Corner k of a trilinear cell is voxel base + (k & 1, (k >> 1) & 1, k >> 2); inside one block
// that is a fixed offset from the base voxel's linear index.
inline constexpr int kCornerOffset[8] = {0,
                                         1,
                                         kBlockSide,
                                         kBlockSide + 1,
                                         kBlockSide* kBlockSide,
                                         kBlockSide* kBlockSide + 1,
                                         kBlockSide* kBlockSide + kBlockSide,
                                         kBlockSide* kBlockSide + kBlockSide + 1};

// The eight corners of a cell whose base voxel i0 has local coordinates < 7 on each axis:
// decoded TSDF (every corner, observed or not) and a bit per corner with weight >= min.
inline uint8_t LoadCornersScalar(const TsdfBlock& block, int i0, uint32_t min_weight_fixed,
                                 float tsdf[8]) {
  unsigned observed = 0;
  for (int k = 0; k < 8; ++k) {
    const int i = i0 + kCornerOffset[k];
    observed |= unsigned(uint32_t(block.weight[i]) >= min_weight_fixed) << k;
    tsdf[k] = DecodeTsdf(block.tsdf[i]);
  }
  return uint8_t(observed);
}

// The same for a cell across block faces: corner k is voxel index[k] of *block[k].
inline uint8_t LoadCornersAcrossScalar(const TsdfBlock* const block[8], const int index[8],
                                       uint32_t min_weight_fixed, float tsdf[8]) {
  unsigned observed = 0;
  for (int k = 0; k < 8; ++k) {
    observed |= unsigned(uint32_t(block[k]->weight[index[k]]) >= min_weight_fixed) << k;
    tsdf[k] = DecodeTsdf(block[k]->tsdf[index[k]]);
  }
  return uint8_t(observed);
}

#if VOXPLAN_RAYCAST_SSE2
// The four x-pairs of 16-bit values of a cell, in corner order: (y, z) = (0,0) (1,0) (0,1) (1,1).
inline __m128i LoadPairs16(const void* base, int i0) {
  const auto* p = static_cast<const uint16_t*>(base) + i0;
  auto pair = [p](int offset) {
    int32_t v;
    std::memcpy(&v, p + offset, sizeof(v));
    return v;
  };
  return _mm_set_epi32(pair(kCornerOffset[6]), pair(kCornerOffset[4]), pair(kCornerOffset[2]),
                       pair(0));
}

// Eight corners' weights and distances, 16 bits each in corner order, decoded as
// LoadCornersScalar does; min_weight_fixed at most 65535.
inline uint8_t DecodeCornersSse2(__m128i weight, __m128i t, uint32_t min_weight_fixed,
                                 float tsdf[8]) {
  // Unsigned weight >= min as a signed compare: flip the sign bits of both sides.
  const __m128i flip = _mm_set1_epi16(int16_t(0x8000));
  const __m128i min_minus_one = _mm_set1_epi16(int16_t((min_weight_fixed - 1) ^ 0x8000u));
  const __m128i observed = _mm_cmpgt_epi16(_mm_xor_si128(weight, flip), min_minus_one);
  // Sign-extend to 32 bits: the value in the high half, then an arithmetic shift.
  const __m128i lo = _mm_srai_epi32(_mm_unpacklo_epi16(t, t), 16);
  const __m128i hi = _mm_srai_epi32(_mm_unpackhi_epi16(t, t), 16);
  const __m128 scale = _mm_set1_ps(1.0f / kTsdfScale);
  _mm_storeu_ps(tsdf, _mm_mul_ps(_mm_cvtepi32_ps(lo), scale));
  _mm_storeu_ps(tsdf + 4, _mm_mul_ps(_mm_cvtepi32_ps(hi), scale));
  return uint8_t(_mm_movemask_epi8(_mm_packs_epi16(observed, _mm_setzero_si128())));
}

inline uint8_t LoadCornersSse2(const TsdfBlock& block, int i0, uint32_t min_weight_fixed,
                               float tsdf[8]) {
  // A minimum above 65535 is never met.
  if (min_weight_fixed > 65535u) return LoadCornersScalar(block, i0, min_weight_fixed, tsdf);
  return DecodeCornersSse2(LoadPairs16(block.weight, i0), LoadPairs16(block.tsdf, i0),
                           min_weight_fixed, tsdf);
}

inline uint8_t LoadCornersAcrossSse2(const TsdfBlock* const block[8], const int index[8],
                                     uint32_t min_weight_fixed, float tsdf[8]) {
  if (min_weight_fixed > 65535u)
    return LoadCornersAcrossScalar(block, index, min_weight_fixed, tsdf);
  auto gather = [&](auto field) {
    return _mm_setr_epi16(
        int16_t((block[0]->*field)[index[0]]), int16_t((block[1]->*field)[index[1]]),
        int16_t((block[2]->*field)[index[2]]), int16_t((block[3]->*field)[index[3]]),
        int16_t((block[4]->*field)[index[4]]), int16_t((block[5]->*field)[index[5]]),
        int16_t((block[6]->*field)[index[6]]), int16_t((block[7]->*field)[index[7]]));
  };
  return DecodeCornersSse2(gather(&TsdfBlock::weight), gather(&TsdfBlock::tsdf), min_weight_fixed,
                           tsdf);
}
#endif

inline uint8_t LoadCorners(const TsdfBlock& block, int i0, uint32_t min_weight_fixed,
                           float tsdf[8]) {
#if VOXPLAN_RAYCAST_SSE2
  return LoadCornersSse2(block, i0, min_weight_fixed, tsdf);
#else
  return LoadCornersScalar(block, i0, min_weight_fixed, tsdf);
#endif
}

inline uint8_t LoadCornersAcross(const TsdfBlock* const block[8], const int index[8],
                                 uint32_t min_weight_fixed, float tsdf[8]) {
#if VOXPLAN_RAYCAST_SSE2
  return LoadCornersAcrossSse2(block, index, min_weight_fixed, tsdf);
#else
  return LoadCornersAcrossScalar(block, index, min_weight_fixed, tsdf);
#endif
}

// The trilinear interpolant of a cell's corner values at frac (each in [0, 1]) and its
// gradient, in value per voxel.
inline float ValueAndGradientScalar(const float t[8], const float frac[4], float gradient[3]) {
  const float fx = frac[0], fy = frac[1], fz = frac[2];
  const float x00 = t[0] + fx * (t[1] - t[0]);
  const float x10 = t[2] + fx * (t[3] - t[2]);
  const float x01 = t[4] + fx * (t[5] - t[4]);
  const float x11 = t[6] + fx * (t[7] - t[6]);
  const float y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
  gradient[0] = (1 - fy) * (1 - fz) * (t[1] - t[0]) + fy * (1 - fz) * (t[3] - t[2]) +
                (1 - fy) * fz * (t[5] - t[4]) + fy * fz * (t[7] - t[6]);
  gradient[1] = (1 - fx) * (1 - fz) * (t[2] - t[0]) + fx * (1 - fz) * (t[3] - t[1]) +
                (1 - fx) * fz * (t[6] - t[4]) + fx * fz * (t[7] - t[5]);
  gradient[2] = (1 - fx) * (1 - fy) * (t[4] - t[0]) + fx * (1 - fy) * (t[5] - t[1]) +
                (1 - fx) * fy * (t[6] - t[2]) + fx * fy * (t[7] - t[3]);
  return y0 + fz * (y1 - y0);
}

#if VOXPLAN_RAYCAST_SSE2
// The same as four 4-term dot products over the cell's x-, y- and z-edges; rounds differently
// (a few ulp).
inline float ValueAndGradientSse2(const float t[8], const float frac[4], float gradient[3]) {
  const __m128 lo = _mm_loadu_ps(t), hi = _mm_loadu_ps(t + 4);  // z = 0 and z = 1 faces
  const __m128 f = _mm_loadu_ps(frac);
  const __m128 fx = _mm_shuffle_ps(f, f, _MM_SHUFFLE(0, 0, 0, 0));
  const __m128 fy = _mm_shuffle_ps(f, f, _MM_SHUFFLE(1, 1, 1, 1));
  const __m128 fz = _mm_shuffle_ps(f, f, _MM_SHUFFLE(2, 2, 2, 2));
  // Lane weights (1 - f or f) as a + b f, with a and b constant per lane.
  auto lerp_weights = [](__m128 a, __m128 b, __m128 x) { return _mm_add_ps(a, _mm_mul_ps(b, x)); };
  const __m128 one_zero = _mm_set_ps(0.f, 1.f, 0.f, 1.f),
               sign_alt = _mm_set_ps(1.f, -1.f, 1.f, -1.f);
  const __m128 one_one = _mm_set_ps(0.f, 0.f, 1.f, 1.f),
               sign_pair = _mm_set_ps(1.f, 1.f, -1.f, -1.f);
  const __m128 wx = lerp_weights(one_zero, sign_alt, fx);  // per corner of a face, x weight
  const __m128 wy = lerp_weights(one_one, sign_pair, fy);
  const __m128 wz = lerp_weights(one_one, sign_pair, fz);  // per edge pair, z weight
  const __m128 wy_edge = lerp_weights(one_zero, sign_alt, fy);
  const __m128 d_z = _mm_sub_ps(hi, lo);  // edges along z: corners k and k + 4
  const __m128 d_x =
      _mm_sub_ps(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1)),
                 _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0)));  // 1-0 3-2 5-4 7-6
  const __m128 d_y =
      _mm_sub_ps(_mm_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 2, 3, 2)),
                 _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(1, 0, 1, 0)));  // 2-0 3-1 6-4 7-5
  const __m128 wxy = _mm_mul_ps(wx, wy);
  __m128 value = _mm_mul_ps(wxy, _mm_add_ps(lo, _mm_mul_ps(fz, d_z)));
  __m128 gx = _mm_mul_ps(_mm_mul_ps(wy_edge, wz), d_x);
  __m128 gy = _mm_mul_ps(_mm_mul_ps(wx, wz), d_y);
  __m128 gz = _mm_mul_ps(wxy, d_z);
  _MM_TRANSPOSE4_PS(value, gx, gy, gz);
  alignas(16) float sums[4];  // value, gradient x, y, z
  _mm_store_ps(sums, _mm_add_ps(_mm_add_ps(value, gx), _mm_add_ps(gy, gz)));
  gradient[0] = sums[1];
  gradient[1] = sums[2];
  gradient[2] = sums[3];
  return sums[0];
}
#endif

inline float ValueAndGradient(const float t[8], const float frac[4], float gradient[3]) {
#if VOXPLAN_RAYCAST_SSE2
  return ValueAndGradientSse2(t, frac, gradient);
#else
  return ValueAndGradientScalar(t, frac, gradient);
#endif
}

// Trilinear colour of a cell whose eight corners are all observed, from their colours in
// corner order; frac is the position inside the cell. Weights are normalised by their sum.
inline uint32_t BlendCornerColorsScalar(const uint8_t r8[8], const uint8_t g8[8],
                                        const uint8_t b8[8], const float frac[4]) {
  const float fx = frac[0], fy = frac[1], fz = frac[2];
  float r = 0.f, g = 0.f, b = 0.f, sum_w = 0.f;
  for (int k = 0; k < 8; ++k) {
    const float w =
        ((k & 1) ? fx : 1 - fx) * (((k >> 1) & 1) ? fy : 1 - fy) * ((k >> 2) ? fz : 1 - fz);
    r += w * float(r8[k]);
    g += w * float(g8[k]);
    b += w * float(b8[k]);
    sum_w += w;
  }
  if (!(sum_w > 0.f)) return 0;
  const float inv = 1.f / sum_w;
  auto to8 = [inv](float c) { return uint8_t(std::clamp(c * inv + 0.5f, 0.f, 255.f)); };
  return PackRgb(to8(r), to8(g), to8(b));
}

// The same for a cell inside one block, base voxel i0.
inline uint32_t BlendColorScalar(const TsdfBlock& block, int i0, const float frac[4]) {
  uint8_t r[8], g[8], b[8];
  for (int k = 0; k < 8; ++k) {
    r[k] = block.r[i0 + kCornerOffset[k]];
    g[k] = block.g[i0 + kCornerOffset[k]];
    b[k] = block.b[i0 + kCornerOffset[k]];
  }
  return BlendCornerColorsScalar(r, g, b, frac);
}

#if VOXPLAN_RAYCAST_SSE2
// The blend of three channels, eight bytes each in corner order in the low half of a register.
// Sums in another order than the scalar one, so a channel may differ from it by 1.
inline uint32_t BlendChannelsSse2(__m128i r8, __m128i g8, __m128i b8, const float frac[4]) {
  const __m128 f = _mm_loadu_ps(frac);
  const __m128 fx = _mm_shuffle_ps(f, f, _MM_SHUFFLE(0, 0, 0, 0));
  const __m128 fy = _mm_shuffle_ps(f, f, _MM_SHUFFLE(1, 1, 1, 1));
  const __m128 fz = _mm_shuffle_ps(f, f, _MM_SHUFFLE(2, 2, 2, 2));
  // Weights of corners 0-3 and 4-7, multiplied in the scalar order (x, then y, then z); each
  // factor (1 - f or f) as a + b f with a and b constant per lane.
  const __m128 wx =
      _mm_add_ps(_mm_set_ps(0.f, 1.f, 0.f, 1.f), _mm_mul_ps(_mm_set_ps(1.f, -1.f, 1.f, -1.f), fx));
  const __m128 wy =
      _mm_add_ps(_mm_set_ps(0.f, 0.f, 1.f, 1.f), _mm_mul_ps(_mm_set_ps(1.f, 1.f, -1.f, -1.f), fy));
  const __m128 wxy = _mm_mul_ps(wx, wy);
  const __m128 w_lo = _mm_mul_ps(wxy, _mm_sub_ps(_mm_set1_ps(1.f), fz));
  const __m128 w_hi = _mm_mul_ps(wxy, fz);
  const __m128i zero = _mm_setzero_si128();
  auto weighted = [&](__m128i c8) {
    const __m128i c16 = _mm_unpacklo_epi8(c8, zero);
    const __m128 lo = _mm_cvtepi32_ps(_mm_unpacklo_epi16(c16, zero));
    const __m128 hi = _mm_cvtepi32_ps(_mm_unpackhi_epi16(c16, zero));
    return _mm_add_ps(_mm_mul_ps(lo, w_lo), _mm_mul_ps(hi, w_hi));
  };
  __m128 r = weighted(r8), g = weighted(g8), b = weighted(b8);
  __m128 w = _mm_add_ps(w_lo, w_hi);
  _MM_TRANSPOSE4_PS(r, g, b, w);
  const __m128 sums = _mm_add_ps(_mm_add_ps(r, g), _mm_add_ps(b, w));  // (r, g, b, sum_w)
  const float sum_w = _mm_cvtss_f32(_mm_shuffle_ps(sums, sums, _MM_SHUFFLE(3, 3, 3, 3)));
  if (!(sum_w > 0.f)) return 0;
  const __m128 scaled = _mm_add_ps(_mm_mul_ps(sums, _mm_set1_ps(1.f / sum_w)), _mm_set1_ps(0.5f));
  const __m128 clamped = _mm_min_ps(_mm_max_ps(scaled, _mm_setzero_ps()), _mm_set1_ps(255.f));
  alignas(16) int32_t c[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(c), _mm_cvttps_epi32(clamped));
  return PackRgb(uint8_t(c[0]), uint8_t(c[1]), uint8_t(c[2]));
}

inline uint32_t BlendCornerColorsSse2(const uint8_t r8[8], const uint8_t g8[8], const uint8_t b8[8],
                                      const float frac[4]) {
  auto load = [](const uint8_t* c) { return _mm_loadl_epi64(reinterpret_cast<const __m128i*>(c)); };
  return BlendChannelsSse2(load(r8), load(g8), load(b8), frac);
}

inline uint32_t BlendColorSse2(const TsdfBlock& block, int i0, const float frac[4]) {
  auto pair = [i0](const uint8_t* c, int offset) {
    uint16_t v;
    std::memcpy(&v, c + i0 + offset, sizeof(v));
    return int(v);
  };
  // The four x-pairs of one channel, in corner order.
  auto channel = [&](const uint8_t* c) {
    __m128i v = _mm_cvtsi32_si128(pair(c, 0) | (pair(c, kCornerOffset[2]) << 16));
    v = _mm_insert_epi16(v, pair(c, kCornerOffset[4]), 2);
    return _mm_insert_epi16(v, pair(c, kCornerOffset[6]), 3);
  };
  return BlendChannelsSse2(channel(block.r), channel(block.g), channel(block.b), frac);
}
#endif

inline uint32_t BlendCornerColors(const uint8_t r8[8], const uint8_t g8[8], const uint8_t b8[8],
                                  const float frac[4]) {
#if VOXPLAN_RAYCAST_SSE2
  return BlendCornerColorsSse2(r8, g8, b8, frac);
#else
  return BlendCornerColorsScalar(r8, g8, b8, frac);
#endif
}

inline uint32_t BlendColor(const TsdfBlock& block, int i0, const float frac[4]) {
#if VOXPLAN_RAYCAST_SSE2
  return BlendColorSse2(block, i0, frac);
#else
  return BlendColorScalar(block, i0, frac);
#endif
}

}  // namespace voxplan::raycast_detail
