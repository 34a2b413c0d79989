#pragma once
// Marching cubes over the hashed volume: per block, with neighbour lookups across block borders,
// vertices welded by the voxel edge they lie on, per-vertex colour and normals; parallel over
// blocks and deterministic (same volume -> same mesh bytes, whatever the thread count).
#include "core/mesh.h"
#include "core/volume.h"

namespace voxplan {

struct MeshParams {
  float min_weight = 0.5f;  // voxels with less weight count as unobserved
  bool with_color = true;
};

Mesh ExtractMesh(const TsdfVolume& volume, const MeshParams& params = {});

}  // namespace voxplan
