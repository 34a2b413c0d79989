// AVX2 kernel: one x-row of 8 voxels per step, the same arithmetic as the scalar reference in
// the same order (mul and add, never FMA), so both produce identical bytes. Compiled for AVX2
// by a function attribute; ResolveKernel only picks it when the CPU has AVX2.
#include <immintrin.h>

#include "fusion/integrate_kernel.h"

namespace voxplan::internal {

namespace {

#define VOXPLAN_AVX2 __attribute__((target("avx2")))

VOXPLAN_AVX2 inline __m256 Splat(float v) { return _mm256_set1_ps(v); }

// Narrows 8 int32 to 8 int16 / uint16 with saturation, keeping lane order.
VOXPLAN_AVX2 inline __m128i PackI32ToI16(__m256i v) {
  return _mm_packs_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
}
VOXPLAN_AVX2 inline __m128i PackI32ToU16(__m256i v) {
  return _mm_packus_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
}

}  // namespace

namespace {

// Whether every voxel centre of the block lies in front of the camera and projects into the
// image: a box in front of the camera projects into the convex hull of its corners'
// projections, so the 8 corners of the box of voxel centres decide it (with over a pixel of
// margin for rounding), and the kernel can then drop its per-row bounds checks.
bool CentresProjectInside(const FrameView& f, float ox, float oy, float oz) {
  const float lo = 0.5f * f.voxel_size_m, hi = 7.5f * f.voxel_size_m;
  for (int c = 0; c < 8; ++c) {
    const float px = ox + ((c & 1) ? hi : lo), py = oy + ((c & 2) ? hi : lo),
                pz = oz + ((c & 4) ? hi : lo);
    const float x = f.r[0] * px + f.r[1] * py + f.r[2] * pz + f.t[0];
    const float y = f.r[3] * px + f.r[4] * py + f.r[5] * pz + f.t[1];
    const float z = f.r[6] * px + f.r[7] * py + f.r[8] * pz + f.t[2];
    if (!(z > 1e-3f)) return false;
    const float u = f.fx * x / z + f.cx, v = f.fy * y / z + f.cy;
    if (!(u >= 1.0f && u <= float(f.width) - 2.0f && v >= 1.0f && v <= float(f.height) - 2.0f))
      return false;
  }
  return true;
}

// The kernel; kInside: CentresProjectInside holds, so no lane needs the bounds checks;
// kClearing: readings beyond max depth clear (FrameView::clear_depth_m), a separate copy so that
// the usual path carries none of it. Frame values are copied into locals first: the colour stores
// (uint8_t) may alias anything, and would otherwise make the compiler reload them from `f` on
// every row.
template <bool kInside, bool kClearing>
VOXPLAN_AVX2 void UpdateBlock(const FrameView& f, BlockIndex index, TsdfBlock& block) {
  const float s = f.voxel_size_m;
  const float ox = float(index.x * kBlockSide) * s, oy = float(index.y * kBlockSide) * s,
              oz = float(index.z * kBlockSide) * s;
  const float* const depth = f.depth;
  const uint32_t* const color = f.color;
  const bool depth_weighting = f.depth_weighting;
  const __m256 lane = _mm256_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f);
  const __m256 px = _mm256_add_ps(Splat(ox), _mm256_mul_ps(lane, Splat(s)));
  // The x terms of the projection, the same for every row of the block.
  const __m256 r0x = _mm256_mul_ps(Splat(f.r[0]), px), r3x = _mm256_mul_ps(Splat(f.r[3]), px),
               r6x = _mm256_mul_ps(Splat(f.r[6]), px);
  // The y and z terms of the projection, per row and per slice, as the scalar kernel rounds
  // them.
  float ry[3][kBlockSide], rz[3][kBlockSide];
  for (int j = 0; j < kBlockSide; ++j) {
    const float py = oy + (float(j) + 0.5f) * s, pz = oz + (float(j) + 0.5f) * s;
    for (int k = 0; k < 3; ++k) {
      ry[k][j] = f.r[3 * k + 1] * py;
      rz[k][j] = f.r[3 * k + 2] * pz;
    }
  }
  const __m256 t0 = Splat(f.t[0]), t1 = Splat(f.t[1]), t2 = Splat(f.t[2]);
  const __m256 fx = Splat(f.fx), fy = Splat(f.fy), cx = Splat(f.cx), cy = Splat(f.cy);
  const __m256 zero = _mm256_setzero_ps(), one = Splat(1.0f), minus_one = Splat(-1.0f);
  const __m256 half = Splat(0.5f);
  const __m256 max_u = Splat(float(f.width)), max_v = Splat(float(f.height));
  const __m256 min_d = Splat(f.min_depth_m), max_d = Splat(f.max_depth_m);
  const __m256 clear_d = Splat(f.clear_depth_m);
  const __m256 trunc = Splat(f.trunc_m), minus_trunc = Splat(-f.trunc_m);
  const __m256 inv_trunc = Splat(f.inv_trunc), max_weight = Splat(f.max_weight);
  const __m256 inv_tsdf_scale = Splat(1.0f / kTsdfScale), inv_w_scale = Splat(1.0f / kWeightScale);
  const __m256 tsdf_scale = Splat(kTsdfScale), w_scale = Splat(kWeightScale);
  const __m256i width = _mm256_set1_epi32(f.width);
  const __m256i byte_mask = _mm256_set1_epi32(0xff);

  for (int z = 0; z < kBlockSide; ++z) {
    const __m256 rz0 = Splat(rz[0][z]), rz1 = Splat(rz[1][z]), rz2 = Splat(rz[2][z]);
    for (int y = 0; y < kBlockSide; ++y) {
      // ((r0 x + r1 y) + r2 z) + t, in the scalar order.
      const __m256 cx_ = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(r0x, Splat(ry[0][y])), rz0), t0);
      const __m256 cy_ = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(r3x, Splat(ry[1][y])), rz1), t1);
      const __m256 cz_ = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(r6x, Splat(ry[2][y])), rz2), t2);
      __m256 valid;
      if constexpr (!kInside) {
        valid = _mm256_cmp_ps(cz_, zero, _CMP_GT_OQ);
        if (_mm256_testz_ps(valid, valid)) continue;
      }
      const __m256 inv_z = _mm256_div_ps(one, cz_);
      const __m256 uf =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(fx, cx_), inv_z), cx), half);
      const __m256 vf =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(fy, cy_), inv_z), cy), half);
      __m256i pixel = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(vf), width),
                                       _mm256_cvttps_epi32(uf));
      __m256 d;
      if constexpr (kInside) {
        d = _mm256_i32gather_ps(depth, pixel, 4);
      } else {
        valid = _mm256_and_ps(valid, _mm256_cmp_ps(uf, zero, _CMP_GE_OQ));
        valid = _mm256_and_ps(valid, _mm256_cmp_ps(uf, max_u, _CMP_LT_OQ));
        valid = _mm256_and_ps(valid, _mm256_cmp_ps(vf, zero, _CMP_GE_OQ));
        valid = _mm256_and_ps(valid, _mm256_cmp_ps(vf, max_v, _CMP_LT_OQ));
        if (_mm256_testz_ps(valid, valid)) continue;
        // Invalid lanes gather pixel 0 (masked off anyway) so no index is out of range.
        pixel = _mm256_and_si256(pixel, _mm256_castps_si256(valid));
        d = _mm256_mask_i32gather_ps(zero, depth, pixel, valid, 4);
      }
      // Lanes with a reading (in the image, not too near), then those fused as usual.
      __m256 seen = _mm256_cmp_ps(d, min_d, _CMP_GE_OQ);
      if constexpr (!kInside) seen = _mm256_and_ps(valid, seen);
      const __m256 in_range = _mm256_cmp_ps(d, max_d, _CMP_LE_OQ);
      valid = _mm256_and_ps(seen, in_range);
      if constexpr (kClearing) {  // as the scalar kernel: beyond max depth, free space up to it
        const __m256 clears = _mm256_and_ps(_mm256_cmp_ps(d, clear_d, _CMP_LE_OQ),
                                            _mm256_cmp_ps(cz_, max_d, _CMP_LE_OQ));
        valid = _mm256_or_ps(valid, _mm256_and_ps(seen, clears));
      }
      const __m256 sdf = _mm256_sub_ps(d, cz_);
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(sdf, minus_trunc, _CMP_GE_OQ));
      if (_mm256_testz_ps(valid, valid)) continue;

      const __m256 tsdf = _mm256_min_ps(one, _mm256_mul_ps(sdf, inv_trunc));
      const __m256 w_obs = depth_weighting ? _mm256_div_ps(one, _mm256_mul_ps(d, d)) : one;

      const int i = LinearIndex(0, y, z);
      const __m128i old_t16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&block.tsdf[i]));
      const __m128i old_w16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&block.weight[i]));
      if constexpr (kClearing) {  // as the scalar kernel: clearing leaves surfaces alone
        const __m256 free = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_cvtepi16_epi32(old_t16), _mm256_set1_epi32(int32_t(kTsdfScale))));
        valid = _mm256_and_ps(valid, _mm256_or_ps(in_range, free));
        if (_mm256_testz_ps(valid, valid)) continue;
      }
      const __m256 old_t =
          _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepi16_epi32(old_t16)), inv_tsdf_scale);
      const __m256 old_w =
          _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(old_w16)), inv_w_scale);
      const __m256 sum_w = _mm256_add_ps(old_w, w_obs);
      const __m256 inv_sum_w = _mm256_div_ps(one, sum_w);  // one division for all four
      const __m256 new_t = _mm256_mul_ps(
          _mm256_add_ps(_mm256_mul_ps(old_t, old_w), _mm256_mul_ps(tsdf, w_obs)), inv_sum_w);
      const __m256 new_w = _mm256_min_ps(sum_w, max_weight);
      const __m256i t32 = _mm256_cvtps_epi32(
          _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(new_t, minus_one), one), tsdf_scale));
      const __m256i w32 = _mm256_cvtps_epi32(_mm256_mul_ps(new_w, w_scale));
      // Keep the old value in lanes that saw nothing.
      const __m128i mask16 = PackI32ToI16(_mm256_castps_si256(valid));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(&block.tsdf[i]),
                       _mm_blendv_epi8(old_t16, PackI32ToI16(t32), mask16));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(&block.weight[i]),
                       _mm_blendv_epi8(old_w16, PackI32ToU16(w32), mask16));

      if (!color) continue;
      __m256 cmask = _mm256_and_ps(valid, _mm256_cmp_ps(sdf, trunc, _CMP_LT_OQ));
      if constexpr (kClearing) cmask = _mm256_and_ps(cmask, in_range);
      if (_mm256_testz_ps(cmask, cmask)) continue;
      const __m256i c =
          _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(color),
                                      pixel, _mm256_castps_si256(cmask), 4);
      // Colour: blend 8 new bytes into the old ones where the lane is in the band.
      const __m128i cmask16 = PackI32ToI16(_mm256_castps_si256(cmask));
      const __m128i cmask8 = _mm_packs_epi16(cmask16, cmask16);
      uint8_t* channels[3] = {&block.r[i], &block.g[i], &block.b[i]};
      for (int k = 0; k < 3; ++k) {
        const __m256 obs =
            _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(c, 8 * k), byte_mask));
        const __m128i old8 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(channels[k]));
        const __m256 old_c = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(old8));
        const __m256 new_c = _mm256_mul_ps(
            _mm256_add_ps(_mm256_mul_ps(old_c, old_w), _mm256_mul_ps(obs, w_obs)), inv_sum_w);
        const __m128i new16 = PackI32ToU16(_mm256_cvtps_epi32(new_c));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(channels[k]),
                         _mm_blendv_epi8(old8, _mm_packus_epi16(new16, new16), cmask8));
      }
    }
  }
}

}  // namespace

VOXPLAN_AVX2 void IntegrateBlockSimd(const FrameView& f, BlockIndex index, TsdfBlock& block) {
  const float s = f.voxel_size_m;
  const bool inside =
      CentresProjectInside(f, float(index.x * kBlockSide) * s, float(index.y * kBlockSide) * s,
                           float(index.z * kBlockSide) * s);
  const bool clearing = f.clear_depth_m > f.max_depth_m;
  if (inside && clearing)
    UpdateBlock<true, true>(f, index, block);
  else if (inside)
    UpdateBlock<true, false>(f, index, block);
  else if (clearing)
    UpdateBlock<false, true>(f, index, block);
  else
    UpdateBlock<false, false>(f, index, block);
}

VOXPLAN_AVX2 int BandRowCandidatesSimd(const BandRow& r, BandCandidate* out, size_t* valid_count) {
  const __m256 lane = _mm256_setr_ps(0.f, 1.f, 2.f, 3.f, 4.f, 5.f, 6.f, 7.f);
  const __m256 lo = Splat(r.min_depth_m), hi = Splat(r.max_depth_m), trunc = Splat(r.trunc_m);
  const __m256 eps = Splat(1e-3f);
  // Rotated by one lane: lane i holds lane i - 1, lane 0 lane 7, which the blend below
  // replaces by lane 7 of the previous chunk (still in lane 0 of its rotation).
  const __m256i rotate = _mm256_setr_epi32(7, 0, 1, 2, 3, 4, 5, 6);
  // Block coordinates stay floats (floor()ed): equal floats are equal integers.
  __m256 last[6];
  for (__m256& l : last) l = _mm256_setzero_ps();
  __m256 last_valid = _mm256_setzero_ps();
  int n = 0, u0 = 0, valid_pixels = 0;
  for (; u0 + 8 <= r.width; u0 += 8) {
    const __m256 d = _mm256_loadu_ps(r.depth + u0);
    const __m256 valid =
        _mm256_and_ps(_mm256_cmp_ps(d, lo, _CMP_GE_OQ), _mm256_cmp_ps(d, hi, _CMP_LE_OQ));
    const __m256 u = _mm256_add_ps(Splat(float(u0)), lane);
    const __m256 ta = _mm256_max_ps(_mm256_sub_ps(d, trunc), eps);
    const __m256 tb = _mm256_add_ps(d, trunc);
    __m256 same = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    __m256 ends[6];  // a x, b x, a y, b y, a z, b z
    for (int k = 0; k < 3; ++k) {
      const __m256 dir = _mm256_add_ps(Splat(r.row[k]), _mm256_mul_ps(Splat(r.du[k]), u));
      ends[2 * k] = _mm256_add_ps(_mm256_mul_ps(dir, ta), Splat(r.origin[k]));
      ends[2 * k + 1] = _mm256_add_ps(_mm256_mul_ps(dir, tb), Splat(r.origin[k]));
      for (int e = 2 * k; e < 2 * k + 2; ++e) {
        const __m256 cur = _mm256_floor_ps(ends[e]);
        const __m256 rotated = _mm256_permutevar8x32_ps(cur, rotate);
        const __m256 prev = _mm256_blend_ps(rotated, last[e], 0x01);
        same = _mm256_and_ps(same, _mm256_cmp_ps(cur, prev, _CMP_EQ_OQ));
        last[e] = rotated;
      }
    }
    const __m256 rotated_valid = _mm256_permutevar8x32_ps(valid, rotate);
    const __m256 prev_valid = _mm256_blend_ps(rotated_valid, last_valid, 0x01);
    last_valid = rotated_valid;
    valid_pixels += __builtin_popcount(unsigned(_mm256_movemask_ps(valid)));
    const __m256 keep = _mm256_andnot_ps(_mm256_and_ps(same, prev_valid), valid);
    const unsigned mask = unsigned(_mm256_movemask_ps(keep));
    if (mask == 0) continue;
    alignas(32) float e[6][8];
    for (int k = 0; k < 6; ++k) _mm256_store_ps(e[k], ends[k]);
    for (unsigned m = mask; m; m &= m - 1) {
      const int j = __builtin_ctz(m);
      out[n++] = {u0 + j, {e[0][j], e[2][j], e[4][j]}, {e[1][j], e[3][j], e[5][j]}};
    }
  }
  // The last few pixels: all valid ones are candidates (a superset is fine).
  for (; u0 < r.width; ++u0) {
    if (r.depth[u0] >= r.min_depth_m && r.depth[u0] <= r.max_depth_m) {
      out[n++] = BandEnds(r, u0, r.depth[u0]);
      ++valid_pixels;
    }
  }
  *valid_count += size_t(valid_pixels);
  return n;
}

}  // namespace voxplan::internal
