#pragma once
// Internal to fusion/: what one block update needs from a frame, and the two kernels that share
// this contract. Both compute every voxel with the same float operations in the same order
// (no FMA: the target sets -ffp-contract=off), so their outputs are bit-identical.
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "core/block.h"
#include "fusion/integrate.h"

namespace voxplan::internal {

struct FrameView {
  const float* depth = nullptr;
  const uint32_t* color = nullptr;  // nullptr: no colour update
  int width = 0, height = 0;
  float fx = 0, fy = 0, cx = 0, cy = 0;
  float r[9];  // R_C_W row-major
  float t[3];  // t_C_W
  float min_depth_m = 0, max_depth_m = 0;
  // Readings in (max_depth_m, clear_depth_m] update the voxels up to max_depth_m only, and of
  // those only the unobserved or free ones (stored +1); clear_depth_m <= max_depth_m: none.
  float clear_depth_m = 0;
  float trunc_m = 0, inv_trunc = 0;
  float voxel_size_m = 0;
  float max_weight = 0;
  bool depth_weighting = false;
};

void IntegrateBlockScalar(const FrameView& frame, BlockIndex index, TsdfBlock& block);
void IntegrateBlockSimd(const FrameView& frame, BlockIndex index, TsdfBlock& block);

// One depth row of the truncation-band walk, in block units: pixel u's ray is
// (row + du * u) * z + origin, and its band runs from z = max(d - trunc, 1e-3) to d + trunc.
struct BandRow {
  const float* depth = nullptr;
  int width = 0;
  float row[3], du[3], origin[3];
  float trunc_m = 0, min_depth_m = 0, max_depth_m = 0;
};

// A pixel that walks its band: its column and the band's ends in block units.
struct BandCandidate {
  int u;
  float a[3], b[3];
};

// The band's ends of pixel u, with the float operations of BandRowCandidatesSimd.
inline BandCandidate BandEnds(const BandRow& r, int u, float d) {
  const float ta = std::max(d - r.trunc_m, 1e-3f), tb = d + r.trunc_m;
  BandCandidate c;
  c.u = u;
  for (int k = 0; k < 3; ++k) {
    const float dir = r.row[k] + r.du[k] * float(u);
    c.a[k] = dir * ta + r.origin[k];
    c.b[k] = dir * tb + r.origin[k];
  }
  return c;
}

// Writes to `out` the band ends of the valid pixels of the row whose end blocks differ from
// those of the pixel just before (when that one is valid), and returns their count: the rest
// add no block. Adds the row's valid pixels to *valid. The SIMD filter is exact (the same
// arithmetic as BandEnds), so both give the same candidates.
int BandRowCandidatesScalar(const BandRow& r, BandCandidate* out, size_t* valid);
int BandRowCandidatesSimd(const BandRow& r, BandCandidate* out, size_t* valid);

}  // namespace voxplan::internal
