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

VOXPLAN_AVX2 void IntegrateBlockSimd(const FrameView& f, BlockIndex index, TsdfBlock& block) {
  const float s = f.voxel_size_m;
  const float ox = float(index.x * kBlockSide) * s, oy = float(index.y * kBlockSide) * s,
              oz = float(index.z * kBlockSide) * s;
  const __m256 lane = _mm256_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f);
  const __m256 px = _mm256_add_ps(Splat(ox), _mm256_mul_ps(lane, Splat(s)));
  const __m256 r0 = Splat(f.r[0]), r3 = Splat(f.r[3]), r6 = Splat(f.r[6]);
  const __m256 zero = _mm256_setzero_ps(), one = Splat(1.0f), minus_one = Splat(-1.0f);
  const __m256 half = Splat(0.5f);
  const __m256 max_u = Splat(float(f.width)), max_v = Splat(float(f.height));
  const __m256 inv_tsdf_scale = Splat(1.0f / kTsdfScale), inv_w_scale = Splat(1.0f / kWeightScale);
  const __m256i width = _mm256_set1_epi32(f.width);
  const __m256i byte_mask = _mm256_set1_epi32(0xff);

  for (int z = 0; z < kBlockSide; ++z) {
    const float pz = oz + (float(z) + 0.5f) * s;
    for (int y = 0; y < kBlockSide; ++y) {
      const float py = oy + (float(y) + 0.5f) * s;
      // The y and z terms are the same for the whole row; add them in the scalar order.
      const __m256 cx_ =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r0, px), Splat(f.r[1] * py)),
                                      Splat(f.r[2] * pz)),
                        Splat(f.t[0]));
      const __m256 cy_ =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r3, px), Splat(f.r[4] * py)),
                                      Splat(f.r[5] * pz)),
                        Splat(f.t[1]));
      const __m256 cz_ =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(r6, px), Splat(f.r[7] * py)),
                                      Splat(f.r[8] * pz)),
                        Splat(f.t[2]));
      __m256 valid = _mm256_cmp_ps(cz_, zero, _CMP_GT_OQ);
      if (_mm256_testz_ps(valid, valid)) continue;
      const __m256 inv_z = _mm256_div_ps(one, cz_);
      const __m256 uf = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(Splat(f.fx), cx_), inv_z), Splat(f.cx)), half);
      const __m256 vf = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(Splat(f.fy), cy_), inv_z), Splat(f.cy)), half);
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(uf, zero, _CMP_GE_OQ));
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(uf, max_u, _CMP_LT_OQ));
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(vf, zero, _CMP_GE_OQ));
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(vf, max_v, _CMP_LT_OQ));
      if (_mm256_testz_ps(valid, valid)) continue;
      // Invalid lanes gather pixel 0 (masked off anyway) so no index is out of range.
      const __m256i pixel =
          _mm256_and_si256(_mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(vf), width),
                                            _mm256_cvttps_epi32(uf)),
                           _mm256_castps_si256(valid));
      const __m256 d = _mm256_mask_i32gather_ps(zero, f.depth, pixel, valid, 4);
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(d, Splat(f.min_depth_m), _CMP_GE_OQ));
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(d, Splat(f.max_depth_m), _CMP_LE_OQ));
      const __m256 sdf = _mm256_sub_ps(d, cz_);
      valid = _mm256_and_ps(valid, _mm256_cmp_ps(sdf, Splat(-f.trunc_m), _CMP_GE_OQ));
      if (_mm256_testz_ps(valid, valid)) continue;

      const __m256 tsdf = _mm256_min_ps(one, _mm256_mul_ps(sdf, Splat(f.inv_trunc)));
      const __m256 w_obs = f.depth_weighting ? _mm256_div_ps(one, _mm256_mul_ps(d, d)) : one;

      const int i = LinearIndex(0, y, z);
      const __m128i old_t16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&block.tsdf[i]));
      const __m128i old_w16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&block.weight[i]));
      const __m256 old_t =
          _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepi16_epi32(old_t16)), inv_tsdf_scale);
      const __m256 old_w =
          _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(old_w16)), inv_w_scale);
      const __m256 sum_w = _mm256_add_ps(old_w, w_obs);
      const __m256 inv_sum_w = _mm256_div_ps(one, sum_w);  // one division for all four
      const __m256 new_t = _mm256_mul_ps(
          _mm256_add_ps(_mm256_mul_ps(old_t, old_w), _mm256_mul_ps(tsdf, w_obs)), inv_sum_w);
      const __m256 new_w = _mm256_min_ps(sum_w, Splat(f.max_weight));
      const __m256i t32 = _mm256_cvtps_epi32(
          _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(new_t, minus_one), one), Splat(kTsdfScale)));
      const __m256i w32 = _mm256_cvtps_epi32(_mm256_mul_ps(new_w, Splat(kWeightScale)));
      // Keep the old value in lanes that saw nothing.
      const __m128i mask16 = PackI32ToI16(_mm256_castps_si256(valid));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(&block.tsdf[i]),
                       _mm_blendv_epi8(old_t16, PackI32ToI16(t32), mask16));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(&block.weight[i]),
                       _mm_blendv_epi8(old_w16, PackI32ToU16(w32), mask16));

      if (!f.color) continue;
      const __m256 cmask = _mm256_and_ps(valid, _mm256_cmp_ps(sdf, Splat(f.trunc_m), _CMP_LT_OQ));
      if (_mm256_testz_ps(cmask, cmask)) continue;
      const __m256i c =
          _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(f.color),
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

}  // namespace voxplan::internal
