#include "planning/octomap_export.h"

// Silences OctoMap's debug output in the templates compiled here.
#define OCTOMAP_NODEBUGOUT
#include <octomap/OcTree.h>

#include <fstream>

#include "io/file_util.h"

namespace voxplan {

Result<OctomapExportStats> ExportOctomap(const TsdfVolume& volume, const std::string& path,
                                         const VoxelStateParams& state_params) {
  OctomapExportStats stats;
  const float s = volume.voxel_size_m();
  const float trunc_vox = volume.trunc_m() / s;
  octomap::OcTree tree{double(s)};
  // Leaves at the clamping limits, so the stored max-likelihood state is the voxel's state.
  const float occupied_log = tree.getClampingThresMaxLog();
  const float free_log = tree.getClampingThresMinLog();
  // Sorted blocks: the same volume always builds the same tree, hence the same bytes.
  for (const BlockIndex& b : volume.SortedBlockIndices()) {
    const TsdfBlock& block = *volume.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      const VoxelState state =
          ClassifyVoxel(block.tsdf[i], block.weight[i], trunc_vox, state_params);
      if (state == VoxelState::kUnobserved) continue;
      const Eigen::Vector3f c = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), s);
      octomap::OcTreeKey key;
      if (!tree.coordToKeyChecked(octomap::point3d(c.x(), c.y(), c.z()), key)) {
        ++stats.outside_range;
        continue;
      }
      const bool occupied = state == VoxelState::kOccupied;
      tree.setNodeValue(key, occupied ? occupied_log : free_log, /*lazy_eval=*/true);
      ++(occupied ? stats.occupied_voxels : stats.free_voxels);
    }
  }
  tree.updateInnerOccupancy();
  tree.toMaxLikelihood();
  tree.prune();
  stats.tree_nodes = tree.size();
  const Status written = WriteAtomically(path, [&](const std::string& tmp) -> Status {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return IoError("cannot open a temporary file beside " + path + " for writing");
    // The header AbstractOccupancyOcTree::writeBinaryConst writes, then the data: that
    // function also prints progress on stderr, which library code must not.
    out << "# Octomap OcTree binary file\n"
        << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
        << "id " << tree.getTreeType() << "\nsize " << tree.size() << "\nres "
        << tree.getResolution() << "\ndata\n";
    tree.writeBinaryData(out);
    if (!out.flush()) return IoError("cannot write the OctoMap tree to " + path);
    return Status::Ok();
  });
  if (!written.ok()) return written;
  return stats;
}

}  // namespace voxplan
