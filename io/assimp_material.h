#pragma once
// For code that reads scenes through assimp itself (io's ReadMesh, sim's scene loader): the one
// rule for a mesh's material colour. Includes assimp, so only .cpp files of targets that link
// assimp include it.
#include <assimp/scene.h>

namespace voxplan::internal {

// The material's diffuse colour, unless the importer invented the material ("DefaultMaterial",
// or an unnamed white one for PLY and STL, which have no materials of their own).
bool MaterialDiffuse(const aiScene& scene, unsigned int index, bool format_has_materials,
                     aiColor4D* color);

}  // namespace voxplan::internal
