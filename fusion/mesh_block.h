#pragma once
// Marching cubes over one block (internal to mesh_extract.cpp): the block's piece of the mesh,
// with every vertex keyed by the voxel edge or corner it lies on, so that pieces weld into one
// mesh by key. A piece holds no zero-area triangle, no two vertices at one position and no
// vertex that no triangle uses.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/volume.h"
#include "fusion/mesh_extract.h"

namespace voxplan::internal {

struct BlockMesh {
  std::vector<uint64_t> keys;   // one per local vertex: its edge or corner (VertexKey)
  std::vector<uint8_t> shared;  // 1 when a neighbouring block's cubes can use the same key
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<std::array<uint32_t, 3>> triangles;  // local vertex ids
};

// A vertex's key: its edge by lower voxel (global) and axis 0..2, or with axis 3 the voxel
// corner it sits on. The same key from every block, 20 bits per coordinate (+-524k voxels).
uint64_t VertexKey(GlobalVoxelIndex g, int axis);

// Scratch space one worker reuses from block to block.
struct BlockScratch;
struct BlockScratchDeleter {
  void operator()(BlockScratch* s) const;
};
std::unique_ptr<BlockScratch, BlockScratchDeleter> MakeBlockScratch();

// Meshes the cubes whose lower corner lies in block `b` into `out` (left empty where no
// surface passes).
void MeshBlock(const TsdfVolume& volume, BlockIndex b, const MeshParams& params,
               BlockScratch& scratch, BlockMesh& out);

}  // namespace voxplan::internal
