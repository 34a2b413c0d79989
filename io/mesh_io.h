#pragma once
// Mesh files through assimp, format by extension: .ply (binary, with vertex colours), .obj,
// .glb, .stl. Writes go to a temporary file beside the target and are renamed into place.
#include <string>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan {

enum class UpAxis { kZ, kY };

struct MeshReadOptions {
  float scale = 1.0f;      // multiplies coordinates after the file's own unit scale
  UpAxis up = UpAxis::kZ;  // kY rotates a Y-up file into voxplan's Z-up world
};

// All meshes of the file merged into one, node transforms applied; per-vertex colour from the
// file's vertex colours, else its material diffuse colour. Refuses files with no triangles.
Result<Mesh> ReadMesh(const std::string& path, const MeshReadOptions& options = {});
Status WriteMesh(const Mesh& mesh, const std::string& path);
bool IsSupportedMeshExtension(const std::string& path);  // .ply .obj .glb .stl

}  // namespace voxplan
