// OBJ written directly: assimp's exporter joins vertices whose positions and colours are equal
// (and first makes the mesh verbose and joins it again), which turned two of voxplan's
// vertices into one and their triangles into degenerate ones.
#include <charconv>
#include <cstdint>

#include "io/mesh_encode.h"

namespace voxplan::internal {

namespace {

// Appends " value" in the shortest decimal form that parses back to the same float.
void AppendFloat(std::string& out, float value) {
  char buffer[32];
  buffer[0] = ' ';
  const auto result = std::to_chars(buffer + 1, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

void AppendIndex(std::string& out, uint32_t index, bool with_normal) {
  char buffer[32];
  buffer[0] = ' ';
  const auto result = std::to_chars(buffer + 1, buffer + sizeof(buffer), uint64_t(index) + 1);
  out.append(buffer, result.ptr);
  if (!with_normal) return;
  out += "//";
  out.append(buffer + 1, result.ptr);
}

}  // namespace

std::string EncodeObj(const Mesh& mesh) {
  const bool has_normals = !mesh.normals.empty();
  const bool has_colors = !mesh.colors.empty();
  std::string out = "# written by voxplan\n";
  out.reserve(out.size() + mesh.num_vertices() * (has_normals ? 80 : 40) +
              mesh.num_triangles() * (has_normals ? 40 : 24));
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    out += 'v';
    for (int k = 0; k < 3; ++k) AppendFloat(out, mesh.positions[v][k]);
    if (has_colors)
      for (int k = 0; k < 3; ++k) AppendFloat(out, float(mesh.colors[v][k]) / 255.0f);
    out += '\n';
  }
  if (has_normals) {
    for (const auto& n : mesh.normals) {
      out += "vn";
      for (int k = 0; k < 3; ++k) AppendFloat(out, n[k]);
      out += '\n';
    }
  }
  for (const auto& t : mesh.triangles) {
    out += 'f';
    for (uint32_t i : t) AppendIndex(out, i, has_normals);
    out += '\n';
  }
  return out;
}

}  // namespace voxplan::internal
