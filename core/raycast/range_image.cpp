// The range image of a cast: per image cell the depth range where rays can meet a block, and
// the nearest depth of a negative voxel's cube, so that rays skip empty space at once. Blocks
// are splatted in chunks in parallel (range_image.h has the splatting), merged by min and max.
#include "core/raycast/range_image.h"

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace voxplan::raycast_detail {

void CullChunk(const Splatter& splatter, const BlockIndex* blocks, const TsdfBlock* const* data,
               size_t first, size_t last, Chunk& chunk) {
  splatter.CullBlocks(blocks, data, first, last, chunk);
}
void SplatChunk(const Splatter& splatter, const BrickMaskTable& table, Chunk& chunk) {
  splatter.SplatBricks(table, chunk);
}

RangeImage BuildRangeImage(const TsdfVolume& volume, const PinholeCamera& camera,
                           const Pose3f& T_C_W, const RaycastParams& params, bool avx2) {
  RangeImage range;
  range.cols = (camera.width + kRangeCell - 1) / kRangeCell;
  range.rows = (camera.height + kRangeCell - 1) / kRangeCell;
  range.surface_cols = (camera.width + kSurfaceCell - 1) / kSurfaceCell;
  range.surface_rows = (camera.height + kSurfaceCell - 1) / kSurfaceCell;
  const size_t num_cells = size_t(range.cols) * size_t(range.rows);
  const size_t num_surface_cells = size_t(range.surface_cols) * size_t(range.surface_rows);

  std::vector<BlockIndex> blocks;
  std::vector<const TsdfBlock*> block_data;
  blocks.reserve(volume.num_blocks());
  block_data.reserve(volume.num_blocks());
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock& data) {
    blocks.push_back(b);
    block_data.push_back(&data);
  });
  // A chunk per thread at most: each holds whole images, set and merged serially.
  constexpr size_t kBlocksPerChunk = 1024;
  const size_t num_chunks =
      std::clamp<size_t>(blocks.size() / kBlocksPerChunk, 1, size_t(std::max(MaxThreads(), 1)));
  std::vector<Chunk> chunks(num_chunks);
  const float voxel_m = volume.voxel_size_m();
  const Eigen::Matrix3f R_C_W = T_C_W.linear();
  const Eigen::Vector3f voxel_x = R_C_W.col(0) * voxel_m, voxel_y = R_C_W.col(1) * voxel_m,
                        voxel_z = R_C_W.col(2) * voxel_m;
  const Eigen::Vector3f voxel_extent = voxel_x.cwiseAbs() + voxel_y.cwiseAbs() + voxel_z.cwiseAbs();
  const float block_m = volume.block_size_m();
  const Splatter splatter{
      camera,
      T_C_W,
      T_C_W.inverse().translation(),
      block_m,
      MarchStart(volume, params),
      params.max_depth_m,
      range.cols,
      range.surface_cols,
      num_cells,
      num_surface_cells,
      voxel_x,
      voxel_y,
      voxel_z,
      (0.5f * float(kBlockSide)) * voxel_extent,
      (0.5f * float(kBrickSide)) * voxel_extent,
      0.5f * (R_C_W.col(0) * block_m + R_C_W.col(1) * block_m + R_C_W.col(2) * block_m),
      (0.5f * float(kBrickSide)) * (voxel_x + voxel_y + voxel_z)};
  ParallelFor(num_chunks, 1, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      const size_t first = blocks.size() * c / num_chunks;
      const size_t last = blocks.size() * (c + 1) / num_chunks;
      if (avx2) {
        CullChunkAvx2(splatter, blocks.data(), block_data.data(), first, last, chunks[c]);
        continue;
      }
      CullChunk(splatter, blocks.data(), block_data.data(), first, last, chunks[c]);
    }
  });
  BrickMaskTable table;
  table.Build(chunks);
  ParallelFor(num_chunks, 1, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      if (avx2) {
        SplatChunkAvx2(splatter, table, chunks[c]);
        continue;
      }
      SplatChunk(splatter, table, chunks[c]);
    }
  });

  range.z_min = std::move(chunks[0].z_min);
  range.z_max = std::move(chunks[0].z_max);
  range.surface_z_min = std::move(chunks[0].surface_z_min);
  for (size_t c = 1; c < num_chunks; ++c) {
    const Chunk& chunk = chunks[c];
    for (size_t i = 0; i < num_cells; ++i) {
      range.z_min[i] = std::min(range.z_min[i], chunk.z_min[i]);
      range.z_max[i] = std::max(range.z_max[i], chunk.z_max[i]);
    }
    for (size_t i = 0; i < num_surface_cells; ++i)
      range.surface_z_min[i] = std::min(range.surface_z_min[i], chunk.surface_z_min[i]);
  }
  return range;
}

}  // namespace voxplan::raycast_detail
