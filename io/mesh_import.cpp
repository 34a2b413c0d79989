#include "io/mesh_import.h"

#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <vector>

#include "io/file_util.h"
#include "io/glb_check.h"

namespace voxplan::internal {

namespace fs = std::filesystem;

namespace {

// Opens only regular files inside one folder (after resolving symlinks and ".."), for reading:
// an OBJ's mtllib or a glTF's buffer cannot reach outside the mesh's folder, nor block on a
// FIFO or device. A refused file looks missing to assimp, which then goes on without it.
class ConfinedIOSystem : public Assimp::DefaultIOSystem {
 public:
  explicit ConfinedIOSystem(fs::path folder) : folder_(std::move(folder)) {}

  bool Exists(const char* file) const override { return Allowed(file); }
  Assimp::IOStream* Open(const char* file, const char* mode = "rb") override {
    if (std::strpbrk(mode, "wa+") || !Allowed(file)) return nullptr;
    return DefaultIOSystem::Open(file, mode);
  }

 private:
  bool Allowed(const char* file) const {
    std::error_code ec;
    const fs::path p = fs::canonical(file, ec);
    if (ec || !fs::is_regular_file(p, ec)) return false;
    const auto mismatch = std::mismatch(folder_.begin(), folder_.end(), p.begin(), p.end());
    return mismatch.first == folder_.end();
  }

  fs::path folder_;
};

// Leaves `importer` with the one importer of the extension, so content can never choose
// another format (PLY bytes named .glb are then not a GLB, whatever they look like).
Status RestrictToFormat(Assimp::Importer& importer, const std::string& ext) {
  size_t keep = importer.GetImporterCount();
  for (size_t i = 0; i < importer.GetImporterCount(); ++i) {
    const std::string name = importer.GetImporter(i)->GetInfo()->mName;
    // Two importers claim .glb; glTF 1 binaries are refused by CheckGlb anyway.
    const bool match = ext == ".glb" ? name.find("glTF2") != std::string::npos
                                     : i == importer.GetImporterIndex(ext.c_str());
    if (match) keep = i;
  }
  if (keep == importer.GetImporterCount())
    return Unsupported("this assimp has no importer for " + ext);
  std::vector<Assimp::BaseImporter*> others;
  for (size_t i = 0; i < importer.GetImporterCount(); ++i)
    if (i != keep) others.push_back(importer.GetImporter(i));
  for (Assimp::BaseImporter* other : others) {
    importer.UnregisterLoader(other);
    delete other;  // an unregistered loader is the caller's to delete
  }
  return Status::Ok();
}

std::string Num(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

bool IsTextByte(unsigned char c) { return c >= 0x20 || c == '\t' || c == '\n' || c == '\r'; }

// assimp reads a file whose size is 84 + 50 n as binary, else a file starting with "solid" as
// ascii: a truncated binary whose header says "solid" would be parsed as text.
Status CheckStl(const std::string& bytes) {
  if (bytes.size() >= 84) {
    uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (84 + 50 * uint64_t(n) == bytes.size()) return Status::Ok();
  }
  const size_t start = bytes.find_first_not_of(" \t\r\n");
  const bool ascii = start != std::string::npos && bytes.compare(start, 5, "solid") == 0 &&
                     std::all_of(bytes.begin(), bytes.end(),
                                 [](char c) { return IsTextByte(static_cast<unsigned char>(c)); });
  if (ascii) return Status::Ok();
  if (bytes.size() < 84)
    return CorruptData("not an STL file: " + std::to_string(bytes.size()) +
                       " bytes, shorter than a binary STL header, and not ascii STL text");
  uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  return CorruptData("not an STL file: a binary STL of " + std::to_string(n) + " triangles has " +
                     std::to_string(84 + 50 * uint64_t(n)) + " bytes, this file " +
                     std::to_string(bytes.size()) + ", and it is not ascii STL text");
}

Status PreCheck(const std::string& path, const std::string& ext) {
  if (ext != ".glb" && ext != ".stl") return Status::Ok();  // text formats: the size bound
  Result<std::string> bytes = ReadFileToString(path);
  if (!bytes.ok()) return bytes.status();
  return ext == ".glb" ? CheckGlb(*bytes) : CheckStl(*bytes);
}

// What ValidateDataStructure leaves to us: the indices once more (cheap) and non-null arrays.
Status CheckScene(const aiScene& scene) {
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (!mesh || (mesh->mNumVertices > 0 && !mesh->mVertices))
      return CorruptData("mesh " + std::to_string(m) + " has no vertex array");
    for (unsigned int f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      for (unsigned int k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= mesh->mNumVertices)
          return CorruptData("mesh " + std::to_string(m) + " face " + std::to_string(f) +
                             ": vertex index " + std::to_string(face.mIndices[k]) +
                             " is out of range (" + std::to_string(mesh->mNumVertices) +
                             " vertices)");
    }
  }
  return Status::Ok();
}

}  // namespace

Status CheckMeshFile(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return NotFound("no such mesh file: " + path);
  if (!fs::is_regular_file(st))
    return InvalidArgument(path + ": not a regular file (a folder, FIFO or device)");
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) return IoError(path + ": cannot read the file size: " + ec.message());
  if (size > kMaxMeshFileBytes)
    return Unsupported(path + ": " + std::to_string(size) + " bytes, more than the " +
                       std::to_string(kMaxMeshFileBytes >> 20) + " MiB a mesh file may have");
  return Status::Ok();
}

Result<AssimpScene> ImportWithAssimp(const std::string& path, unsigned int steps) {
  VOXPLAN_RETURN_IF_ERROR(CheckMeshFile(path));
  const std::string ext = LowerExtension(path);
  if (ext != ".obj" && ext != ".glb" && ext != ".stl" && ext != ".dae")
    return InvalidArgument(path + ": not a format read through assimp (" + ext + ")");
  VOXPLAN_RETURN_IF_ERROR(PreCheck(path, ext).Naming(path));
  std::error_code ec;
  const fs::path canonical = fs::canonical(path, ec);
  if (ec) return IoError(path + ": " + ec.message());

  AssimpScene out;
  out.importer = std::make_unique<Assimp::Importer>();
  VOXPLAN_RETURN_IF_ERROR(RestrictToFormat(*out.importer, ext).WithContext(path));
  out.importer->SetIOHandler(new ConfinedIOSystem(canonical.parent_path()));  // importer owns it
  out.importer->SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                                   aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  try {
    out.scene = out.importer->ReadFile(canonical.string(), steps | aiProcess_ValidateDataStructure);
  } catch (const std::exception& e) {  // assimp catches its own; this is for the rest
    return CorruptData(path + ": assimp: " + e.what());
  }
  if (!out.scene || !out.scene->mRootNode)
    return CorruptData(path + ": " + out.importer->GetErrorString());
  VOXPLAN_RETURN_IF_ERROR(CheckScene(*out.scene).WithContext(path));
  return out;
}

Status CheckMeshGeometry(const std::string& path, const Mesh& mesh) {
  if (mesh.triangles.empty()) return InvalidArgument("mesh file " + path + " holds no triangles");
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3f& p = mesh.positions[v];
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > kMaxMeshCoordinate)
      return CorruptData(path + ": vertex " + std::to_string(v) + " at (" + Num(p.x()) + ", " +
                         Num(p.y()) + ", " + Num(p.z()) + ") is " +
                         (p.allFinite() ? "beyond the bound of 1e6 m per coordinate (after scaling)"
                                        : "not finite"));
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (uint32_t i : mesh.triangles[t])
      if (i >= mesh.positions.size())
        return CorruptData(path + ": triangle " + std::to_string(t) + ": vertex index " +
                           std::to_string(i) + " is out of range");
  return Status::Ok();
}

}  // namespace voxplan::internal
