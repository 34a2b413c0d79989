// The mesh loader (io/mesh_io.h ReadMesh) as every command that reads a mesh calls it: the first
// byte picks the file's extension (.ply .obj .glb .stl; the loader goes by it), the rest is the
// file. An accepted mesh has triangles whose indices are in range and per-vertex arrays of the
// vertex count.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "io/mesh_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace voxplan;
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".ply", ".obj", ".glb", ".stl"};
  const std::string name = std::string("mesh") + kExtensions[data[0] % 4];
  const std::string path = fuzz::InputFile(data + 1, size - 1, name);
  const Result<Mesh> mesh = ReadMesh(path);
  if (!mesh.ok()) return 0;
  const size_t n = mesh->num_vertices();
  if (mesh->triangles.empty()) std::abort();  // documented: no triangles is refused
  for (const auto& t : mesh->triangles)
    for (uint32_t v : t)
      if (v >= n) std::abort();
  if (!mesh->normals.empty() && mesh->normals.size() != n) std::abort();
  if (!mesh->colors.empty() && mesh->colors.size() != n) std::abort();
  return 0;
}
