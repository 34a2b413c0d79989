#pragma once
// Whole-map numbers for an exploration run's time series (Xu 2017's uncertainty over time): how
// much of a fixed region of space the planning map has not observed yet, and the mean
// uncertainty of its surface. Both read the map's per-block masks, cheap enough for every row.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "planning/planning_map.h"

namespace voxplan {

// Voxel columns (global voxel x, y) over a range of voxel heights, counted block by block.
class ColumnRegion {
 public:
  // `columns` in any order, duplicates counted once; voxels z_begin <= z < z_end (global voxel
  // z), empty when z_end <= z_begin.
  ColumnRegion(const std::vector<Eigen::Vector2i>& columns, int z_begin, int z_end);

  size_t voxels() const { return voxels_; }
  // The region's voxels that are neither free nor occupied in `map` (a voxel of a block the map
  // lacks is unobserved): popcounts of the blocks' free / occupied masks over the region.
  size_t CountUnobserved(const PlanningMap& map) const;

 private:
  struct BlockColumn {
    int32_t bx = 0, by = 0;
    uint64_t columns = 0;  // bit 8y + x: the block's voxel columns in the region (BlockMask's)
  };
  std::vector<BlockColumn> blocks_;  // sorted by (by, bx)
  int z_begin_ = 0, z_end_ = 0;
  size_t voxels_ = 0;
};

// The mean of min(1, 1 / TSDF weight) over the map's surface voxels (the uncertainty the planners
// see: vp_surface_voxel.uncertainty); NaN without any. Summed by weight value, so the result does
// not depend on the order the blocks are stored in.
double MeanSurfaceUncertainty(const PlanningMap& map);

}  // namespace voxplan
