// The reference kernel: readable, one voxel at a time. The SIMD kernel must match it bit for bit.
#include <cmath>

#include "fusion/integrate_kernel.h"

namespace voxplan::internal {

void IntegrateBlockScalar(const FrameView& f, BlockIndex index, TsdfBlock& block) {
  const float s = f.voxel_size_m;
  const float ox = float(index.x * kBlockSide) * s, oy = float(index.y * kBlockSide) * s,
              oz = float(index.z * kBlockSide) * s;
  for (int z = 0; z < kBlockSide; ++z) {
    const float pz = oz + (float(z) + 0.5f) * s;
    for (int y = 0; y < kBlockSide; ++y) {
      const float py = oy + (float(y) + 0.5f) * s;
      for (int x = 0; x < kBlockSide; ++x) {
        const float px = ox + (float(x) + 0.5f) * s;
        // World -> camera.
        const float cx_ = ((f.r[0] * px + f.r[1] * py) + f.r[2] * pz) + f.t[0];
        const float cy_ = ((f.r[3] * px + f.r[4] * py) + f.r[5] * pz) + f.t[1];
        const float cz_ = ((f.r[6] * px + f.r[7] * py) + f.r[8] * pz) + f.t[2];
        if (!(cz_ > 0.0f)) continue;
        const float inv_z = 1.0f / cz_;
        // Nearest pixel: floor(u + 0.5), i.e. truncation once u + 0.5 is known to be >= 0.
        const float uf = (f.fx * cx_) * inv_z + f.cx + 0.5f;
        const float vf = (f.fy * cy_) * inv_z + f.cy + 0.5f;
        if (!(uf >= 0.0f && uf < float(f.width) && vf >= 0.0f && vf < float(f.height))) continue;
        const int pixel = int(vf) * f.width + int(uf);
        const float d = f.depth[pixel];
        const bool in_range = d <= f.max_depth_m;
        if (!(d >= f.min_depth_m && (in_range || (d <= f.clear_depth_m && cz_ <= f.max_depth_m))))
          continue;
        const float sdf = d - cz_;
        if (!(sdf >= -f.trunc_m)) continue;
        const float tsdf = std::min(1.0f, sdf * f.inv_trunc);
        const float w_obs = f.depth_weighting ? 1.0f / (d * d) : 1.0f;

        const int i = LinearIndex(x, y, z);
        // A reading beyond the range clears only what is unobserved or free: its noise must not
        // erase a surface that readings in range put there.
        if (!in_range && block.tsdf[i] != int16_t(kTsdfScale)) continue;
        const float old_t = float(block.tsdf[i]) * (1.0f / kTsdfScale);
        const float old_w = float(block.weight[i]) * (1.0f / kWeightScale);
        const float sum_w = old_w + w_obs;
        const float inv_sum_w = 1.0f / sum_w;  // one division for TSDF and the three colours
        const float new_t = (old_t * old_w + tsdf * w_obs) * inv_sum_w;
        const float new_w = std::min(sum_w, f.max_weight);
        block.tsdf[i] =
            int16_t(std::nearbyint(std::min(std::max(new_t, -1.0f), 1.0f) * kTsdfScale));
        block.weight[i] = uint16_t(std::nearbyint(new_w * kWeightScale));
        // Colour only inside the band: farther voxels see free space, not this surface.
        if (f.color && sdf < f.trunc_m && in_range) {
          const uint32_t c = f.color[pixel];
          const float obs[3] = {float(c & 0xff), float((c >> 8) & 0xff), float((c >> 16) & 0xff)};
          uint8_t* ch[3] = {&block.r[i], &block.g[i], &block.b[i]};
          for (int k = 0; k < 3; ++k)
            *ch[k] = uint8_t(std::nearbyint((float(*ch[k]) * old_w + obs[k] * w_obs) * inv_sum_w));
        }
      }
    }
  }
}

int BandRowCandidatesScalar(const BandRow& r, BandCandidate* out, size_t* valid_count) {
  int n = 0;
  size_t valid_pixels = 0;
  bool prev_valid = false;
  BlockIndex prev_a, prev_b;
  for (int u = 0; u < r.width; ++u) {
    const float d = r.depth[u];
    const bool valid = d >= r.min_depth_m && d <= r.max_depth_m;
    if (valid) {
      ++valid_pixels;
      const BandCandidate c = BandEnds(r, u, d);
      const BlockIndex a{FloorToInt(c.a[0]), FloorToInt(c.a[1]), FloorToInt(c.a[2])};
      const BlockIndex b{FloorToInt(c.b[0]), FloorToInt(c.b[1]), FloorToInt(c.b[2])};
      if (!(prev_valid && a == prev_a && b == prev_b)) out[n++] = c;
      prev_a = a;
      prev_b = b;
    }
    prev_valid = valid;
  }
  *valid_count += valid_pixels;
  return n;
}

}  // namespace voxplan::internal
