#include "io/mesh_io.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include "io/assimp_material.h"
#include "io/file_util.h"
#include "io/mesh_encode.h"

namespace voxplan {

namespace {

// Binary little-endian PLY written directly: assimp's PLY exporter stores colours as floats
// (r, g, b, a), which most tools read as non-standard properties; uchar red/green/blue is what
// MeshLab, Open3D and assimp itself expect.
std::string EncodePly(const Mesh& mesh) {
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little-endian");
  const bool has_normals = mesh.normals.size() == mesh.positions.size() && !mesh.normals.empty();
  const bool has_colors = mesh.colors.size() == mesh.positions.size() && !mesh.colors.empty();
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by voxplan\n";
  out += "element vertex " + std::to_string(mesh.num_vertices()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (has_normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "element face " + std::to_string(mesh.num_triangles()) + "\n";
  out += "property list uchar uint vertex_indices\nend_header\n";
  const size_t vertex_bytes = 12 + (has_normals ? 12 : 0) + (has_colors ? 3 : 0);
  const size_t header_bytes = out.size();
  out.resize(header_bytes + vertex_bytes * mesh.num_vertices() + 13 * mesh.num_triangles());
  char* dst = out.data() + header_bytes;
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    std::memcpy(dst, mesh.positions[v].data(), 12);
    dst += 12;
    if (has_normals) {
      std::memcpy(dst, mesh.normals[v].data(), 12);
      dst += 12;
    }
    if (has_colors) {
      std::memcpy(dst, mesh.colors[v].data(), 3);
      dst += 3;
    }
  }
  for (const auto& t : mesh.triangles) {
    *dst++ = 3;
    std::memcpy(dst, t.data(), 12);
    dst += 12;
  }
  return out;
}

// A one-mesh, one-node scene for assimp's exporters. The material is named like assimp's own
// default so that reading the file back does not turn it into a uniform colour.
std::unique_ptr<aiScene> MakeScene(const Mesh& mesh) {
  auto scene = std::make_unique<aiScene>();
  scene->mFlags = AI_SCENE_FLAGS_NON_VERBOSE_FORMAT;  // vertices are shared between faces
  scene->mRootNode = new aiNode("root");
  scene->mRootNode->mNumMeshes = 1;
  scene->mRootNode->mMeshes = new unsigned int[1]{0};
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial*[1];
  scene->mMaterials[0] = new aiMaterial();
  aiString name(AI_DEFAULT_MATERIAL_NAME);
  scene->mMaterials[0]->AddProperty(&name, AI_MATKEY_NAME);
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh*[1];
  aiMesh* m = scene->mMeshes[0] = new aiMesh();
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mMaterialIndex = 0;
  m->mNumVertices = unsigned(mesh.num_vertices());
  m->mVertices = new aiVector3D[m->mNumVertices];
  for (unsigned v = 0; v < m->mNumVertices; ++v) {
    const auto& p = mesh.positions[v];
    m->mVertices[v] = aiVector3D(p.x(), p.y(), p.z());
  }
  if (!mesh.normals.empty() && mesh.normals.size() == mesh.positions.size()) {
    m->mNormals = new aiVector3D[m->mNumVertices];
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const auto& n = mesh.normals[v];
      m->mNormals[v] = aiVector3D(n.x(), n.y(), n.z());
    }
  }
  if (!mesh.colors.empty() && mesh.colors.size() == mesh.positions.size()) {
    m->mColors[0] = new aiColor4D[m->mNumVertices];
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const auto& c = mesh.colors[v];
      m->mColors[0][v] = aiColor4D(c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1.0f);
    }
  }
  m->mNumFaces = unsigned(mesh.num_triangles());
  m->mFaces = new aiFace[m->mNumFaces];
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    m->mFaces[f].mNumIndices = 3;
    m->mFaces[f].mIndices = new unsigned int[3];
    for (int k = 0; k < 3; ++k) m->mFaces[f].mIndices[k] = mesh.triangles[f][k];
  }
  return scene;
}

Status CheckMesh(const Mesh& mesh) {
  if (mesh.empty()) return InvalidArgument("the mesh has no triangles");
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    return InvalidArgument("the mesh has " + std::to_string(mesh.normals.size()) + " normals for " +
                           std::to_string(mesh.positions.size()) + " vertices");
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size())
    return InvalidArgument("the mesh has " + std::to_string(mesh.colors.size()) + " colours for " +
                           std::to_string(mesh.positions.size()) + " vertices");
  if (mesh.num_vertices() > size_t(UINT32_MAX) || mesh.num_triangles() > size_t(UINT32_MAX))
    return Unsupported("the mesh is too large for 32-bit indices");
  for (const auto& t : mesh.triangles)
    for (uint32_t i : t)
      if (i >= mesh.num_vertices())
        return InvalidArgument("triangle index " + std::to_string(i) + " is out of range (" +
                               std::to_string(mesh.num_vertices()) + " vertices)");
  return Status::Ok();
}

}  // namespace

Status WriteMesh(const Mesh& mesh, const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext != ".ply" && ext != ".obj" && ext != ".glb" && ext != ".stl")
    return InvalidArgument("cannot write mesh " + path + ": unsupported extension '" + ext +
                           "' (use .ply, .obj, .glb or .stl)");
  VOXPLAN_RETURN_IF_ERROR(CheckMesh(mesh).WithContext("cannot write mesh " + path));

  // PLY, OBJ and GLB are encoded here (io/mesh_encode.h): assimp's OBJ and glTF exporters join
  // identical vertices. Its binary STL exporter writes every triangle's own corners as given.
  std::string bytes;
  if (ext == ".ply") {
    bytes = EncodePly(mesh);
  } else if (ext == ".obj") {
    bytes = internal::EncodeObj(mesh);
  } else if (ext == ".glb") {
    Result<std::string> glb = internal::EncodeGlb(mesh);
    if (!glb.ok()) return glb.status().WithContext("cannot write mesh " + path);
    bytes = std::move(*glb);
  } else {
    // Export to memory, then write the bytes ourselves so the atomic rename covers them.
    const std::unique_ptr<aiScene> scene = MakeScene(mesh);
    Assimp::Exporter exporter;
    const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), "stlb");
    if (!blob)
      return IoError("cannot write mesh " + path + ": assimp: " + exporter.GetErrorString());
    if (blob->next)
      return Status(StatusCode::kInternal,
                    "cannot write mesh " + path + ": assimp produced more than one file");
    bytes.assign(static_cast<const char*>(blob->data), blob->size);
  }
  return WriteFileAtomically(path, bytes);
}

bool IsSupportedMeshExtension(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".ply" || ext == ".obj" || ext == ".glb" || ext == ".stl";
}

}  // namespace voxplan
