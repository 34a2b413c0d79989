#pragma once
// OctoMap interop: the planning volume's occupancy as an OctoMap binary tree (.bt), readable by
// octovis and every OctoMap tool. One OctoMap leaf per observed voxel (same resolution, same
// grid: both put cell k at [k s, (k + 1) s)), occupied or free by ClassifyVoxel; unobserved
// voxels stay unknown.
#include <cstddef>
#include <string>

#include "core/status.h"
#include "core/volume.h"
#include "core/voxel_state.h"

namespace voxplan {

struct OctomapExportStats {
  size_t occupied_voxels = 0;
  size_t free_voxels = 0;
  size_t outside_range = 0;  // voxels beyond OctoMap's 2^16-cell key range, left out
  size_t tree_nodes = 0;     // after pruning
};

// Written atomically (io/file_util.h). IoError when the file cannot be written.
Result<OctomapExportStats> ExportOctomap(const TsdfVolume& volume, const std::string& path,
                                         const VoxelStateParams& state_params = {});

}  // namespace voxplan
