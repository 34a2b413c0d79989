// ReadMesh: every mesh file voxplan reads comes through here or through LoadWorld, both over
// mesh_import.h (PLY by voxplan's own reader, the rest by a confined assimp).
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "io/assimp_material.h"
#include "io/file_util.h"
#include "io/mesh_import.h"
#include "io/mesh_io.h"
#include "io/ply_reader.h"

namespace voxplan {

namespace {

uint8_t ToByte(float c) {
  if (!std::isfinite(c)) return 0;
  return uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
}

Eigen::Vector3f Orient(const Eigen::Vector3f& v, UpAxis up, float k) {
  if (up == UpAxis::kY) return {k * v.x(), -k * v.z(), k * v.y()};
  return k * v;
}

// Unit length, or +Z where the file's normal is zero or not finite.
Eigen::Vector3f UnitNormal(const Eigen::Vector3f& n) {
  const float len = n.norm();
  return len > 0.0f && std::isfinite(len) ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
}

Result<Mesh> ReadPlyMesh(const std::string& path, const MeshReadOptions& options) {
  Result<Mesh> mesh = internal::ReadPly(path);
  if (!mesh.ok()) return mesh.status();
  for (auto& p : mesh->positions) p = Orient(p, options.up, options.scale);
  for (auto& n : mesh->normals) n = UnitNormal(Orient(n, options.up, 1.0f));
  return mesh;
}

bool IsTriangleMesh(const aiMesh& mesh) {
  return (mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) && mesh.mNumFaces > 0;
}

Eigen::Vector3f ToEigen(const aiVector3D& v) { return {v.x, v.y, v.z}; }

// All triangle meshes of the scene merged (node transforms already applied by assimp).
Result<Mesh> ReadAssimpMesh(const std::string& path, const MeshReadOptions& options) {
  Result<internal::AssimpScene> imported =
      internal::ImportWithAssimp(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                           aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!imported.ok()) return imported.status();
  const aiScene& scene = *imported->scene;
  const bool format_has_materials = LowerExtension(path) != ".stl";
  // Colours and normals are kept only if every triangle mesh can supply them, so the merged
  // arrays stay one per vertex.
  bool any_color = false, all_normals = true;
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    if (!IsTriangleMesh(mesh)) continue;
    aiColor4D c;
    if (mesh.HasVertexColors(0) ||
        internal::MaterialDiffuse(scene, mesh.mMaterialIndex, format_has_materials, &c))
      any_color = true;
    if (!mesh.HasNormals()) all_normals = false;
  }
  Mesh out;
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    if (!IsTriangleMesh(mesh)) continue;
    const size_t base = out.positions.size();
    if (base + mesh.mNumVertices > size_t(UINT32_MAX))
      return Unsupported("mesh " + path + " has more vertices than 32-bit indices can address");
    for (unsigned int v = 0; v < mesh.mNumVertices; ++v)
      out.positions.push_back(Orient(ToEigen(mesh.mVertices[v]), options.up, options.scale));
    if (all_normals)
      for (unsigned int v = 0; v < mesh.mNumVertices; ++v)
        out.normals.push_back(UnitNormal(Orient(ToEigen(mesh.mNormals[v]), options.up, 1.0f)));
    if (any_color) {
      aiColor4D diffuse(0.6f, 0.6f, 0.6f, 1.0f);  // assimp's own default grey
      const bool has_vertex_colors = mesh.HasVertexColors(0);
      if (!has_vertex_colors)
        internal::MaterialDiffuse(scene, mesh.mMaterialIndex, format_has_materials, &diffuse);
      for (unsigned int v = 0; v < mesh.mNumVertices; ++v) {
        const aiColor4D& c = has_vertex_colors ? mesh.mColors[0][v] : diffuse;
        out.colors.push_back({ToByte(c.r), ToByte(c.g), ToByte(c.b)});
      }
    }
    for (unsigned int f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.triangles.push_back({uint32_t(base + face.mIndices[0]), uint32_t(base + face.mIndices[1]),
                               uint32_t(base + face.mIndices[2])});
    }
  }
  return out;
}

}  // namespace

Result<Mesh> ReadMesh(const std::string& path, const MeshReadOptions& options) {
  if (!(std::isfinite(options.scale) && options.scale > 0.0f))
    return InvalidArgument("reading " + path + ": scale must be positive, got " +
                           std::to_string(options.scale));
  VOXPLAN_RETURN_IF_ERROR(internal::CheckMeshFile(path));
  // COLLADA is read too (the AWS furniture models), though voxplan writes none.
  if (!IsSupportedMeshExtension(path) && LowerExtension(path) != ".dae")
    return InvalidArgument(path + ": unsupported mesh extension '" + LowerExtension(path) +
                           "' (use .ply, .obj, .glb, .stl or .dae)");
  Result<Mesh> mesh =
      LowerExtension(path) == ".ply" ? ReadPlyMesh(path, options) : ReadAssimpMesh(path, options);
  if (!mesh.ok()) return mesh.status();
  VOXPLAN_RETURN_IF_ERROR(internal::CheckMeshGeometry(path, *mesh));
  return mesh;
}

namespace internal {

bool MaterialDiffuse(const aiScene& scene, unsigned int index, bool format_has_materials,
                     aiColor4D* color) {
  if (!format_has_materials) return false;
  if (index >= scene.mNumMaterials || !scene.mMaterials[index]) return false;
  const aiMaterial& material = *scene.mMaterials[index];
  aiString name;
  if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS &&
      std::strcmp(name.C_Str(), AI_DEFAULT_MATERIAL_NAME) == 0)
    return false;
  return material.Get(AI_MATKEY_COLOR_DIFFUSE, *color) == AI_SUCCESS;
}

}  // namespace internal

}  // namespace voxplan
