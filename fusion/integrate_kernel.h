#pragma once
// Internal to fusion/: what one block update needs from a frame, and the two kernels that share
// this contract. Both compute every voxel with the same float operations in the same order
// (no FMA: the target sets -ffp-contract=off), so their outputs are bit-identical.
#include <Eigen/Core>
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
  float trunc_m = 0, inv_trunc = 0;
  float voxel_size_m = 0;
  float max_weight = 0;
  bool depth_weighting = false;
};

void IntegrateBlockScalar(const FrameView& frame, BlockIndex index, TsdfBlock& block);
void IntegrateBlockSimd(const FrameView& frame, BlockIndex index, TsdfBlock& block);

}  // namespace voxplan::internal
