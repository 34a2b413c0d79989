#include "io/point_cloud_io.h"

#include <bit>
#include <cstring>

#include "io/file_util.h"

namespace voxplan {

Status WritePointCloudPly(const Mesh& points, const std::string& path) {
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little-endian");
  const size_t n = points.num_vertices();
  const bool has_normals = !points.normals.empty() && points.normals.size() == n;
  const bool has_colors = !points.colors.empty() && points.colors.size() == n;
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by voxplan\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (has_normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "end_header\n";
  const size_t header_bytes = out.size();
  const size_t point_bytes = 12 + (has_normals ? 12 : 0) + (has_colors ? 3 : 0);
  out.resize(header_bytes + point_bytes * n);
  char* dst = out.data() + header_bytes;
  for (size_t i = 0; i < n; ++i) {
    std::memcpy(dst, points.positions[i].data(), 12);
    dst += 12;
    if (has_normals) {
      std::memcpy(dst, points.normals[i].data(), 12);
      dst += 12;
    }
    if (has_colors) {
      std::memcpy(dst, points.colors[i].data(), 3);
      dst += 3;
    }
  }
  return WriteFileAtomically(path, out).Naming(path);
}

}  // namespace voxplan
