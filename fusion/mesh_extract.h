#pragma once
// Marching cubes over the hashed volume: per block, with neighbour lookups across block borders,
// vertices welded by the voxel edge or corner they lie on, per-vertex colour and normals;
// parallel over blocks and deterministic (same volume -> same mesh bytes, whatever the thread
// count). The mesh has no zero-area triangle, no two vertices at one position and no vertex
// that no triangle uses (fusion/README.md).
#include <array>
#include <map>
#include <memory>
#include <vector>

#include "core/mesh.h"
#include "core/volume.h"

namespace voxplan {

struct MeshParams {
  float min_weight = 0.5f;  // voxels with less weight count as unobserved
  bool with_color = true;
};

Mesh ExtractMesh(const TsdfVolume& volume, const MeshParams& params = {});

namespace internal {
struct BlockMesh;  // fusion/mesh_block.h
}

// Meshing a map split over ranks (distributed/): each rank meshes the blocks it owns, with
// copies of the neighbours their cubes read (MeshStencilNeighbours) that other ranks own, and
// one rank welds every rank's pieces in block order. ExtractMesh(volume) is
// AssembleMeshPieces of MeshBlockPieces over volume.SortedBlockIndices(), so the split mesh has
// the same bytes.
std::vector<internal::BlockMesh> MeshBlockPieces(const TsdfVolume& volume,
                                                 const std::vector<BlockIndex>& blocks,
                                                 const MeshParams& params);
Mesh AssembleMeshPieces(const std::vector<const internal::BlockMesh*>& pieces_in_block_order,
                        const MeshParams& params);
// The blocks whose voxels the cubes of `b` read besides its own: its +x/+y/+z neighbours.
std::array<BlockIndex, 7> MeshStencilNeighbours(BlockIndex b);

// Meshing that keeps each block's piece and redoes only the pieces a frame can have changed:
// a block's cubes read it and its +x/+y/+z neighbours, so a changed block dirties itself and
// its seven -x/-y/-z neighbours. Assemble() welds the pieces exactly as ExtractMesh does, so
// after any sequence of updates it returns the same bytes as ExtractMesh of the volume.
class IncrementalMesher {
 public:
  explicit IncrementalMesher(const MeshParams& params = {});
  ~IncrementalMesher();
  IncrementalMesher(IncrementalMesher&&) noexcept;
  IncrementalMesher& operator=(IncrementalMesher&&) noexcept;

  // `changed`: every block whose voxels changed (or that was allocated or erased) since the
  // last call, in any order. Returns how many blocks were meshed again.
  size_t Update(const TsdfVolume& volume, const std::vector<BlockIndex>& changed);
  // Meshes every block again (after loading a map, or changing parameters).
  void Rebuild(const TsdfVolume& volume);
  Mesh Assemble() const;
  size_t num_pieces() const { return pieces_.size(); }  // blocks with at least one triangle

 private:
  MeshParams params_;
  std::map<BlockIndex, std::unique_ptr<internal::BlockMesh>> pieces_;  // sorted, as ExtractMesh
};

}  // namespace voxplan
