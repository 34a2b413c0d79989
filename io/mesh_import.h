#pragma once
// Internal to io and sim: the one way a mesh file is opened. ReadMesh (io) and LoadWorld (sim's
// scene loader) both go through it; nothing else in voxplan reads a mesh file.
//
//  - .ply: voxplan's own reader (ply_reader.h), never assimp.
//  - .obj .glb .stl .dae: assimp, made safe: the importer is chosen by the extension
//    alone and every other importer is removed, so content never picks the format; files it
//    opens besides the mesh (mtllib, textures, glTF buffers) must be regular files inside the
//    mesh's own folder (symlinks resolved), anything else reads as missing; cheap structural
//    pre-checks first (GLB header, chunks and accessor bounds; binary STL size); assimp's
//    ValidateDataStructure step; then the scene's indices and coordinates are checked.
//  - every format: a regular file of at most kMaxMeshFileBytes; after scaling every coordinate
//    is finite with |c| <= kMaxMeshCoordinate (CheckMeshGeometry).
// Refusals read "<path>: <reason>". Includes assimp: only for .cpp files of targets linking it.
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cstdint>
#include <memory>
#include <string>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan::internal {

// Metres after scaling: larger coordinates are corrupt data or a wrong unit, and they break
// Embree and the samplers (1e19 overflows every product of two coordinates).
constexpr double kMaxMeshCoordinate = 1e6;
constexpr uintmax_t kMaxMeshFileBytes = uintmax_t(1) << 30;  // 1 GiB

// A regular file (not a FIFO, device or folder) within kMaxMeshFileBytes.
Status CheckMeshFile(const std::string& path);

// The imported scene; the importer owns it.
struct AssimpScene {
  std::unique_ptr<Assimp::Importer> importer;
  const aiScene* scene = nullptr;
};

// Imports .obj .glb .stl .dae as described above; `steps` are assimp post-processing flags
// (ValidateDataStructure is always added). Points and lines are split off by SortByPType.
Result<AssimpScene> ImportWithAssimp(const std::string& path, unsigned int steps);

// Finite coordinates within kMaxMeshCoordinate, indices in range, at least one triangle.
Status CheckMeshGeometry(const std::string& path, const Mesh& mesh);

}  // namespace voxplan::internal
