#pragma once
// Small mesh files made in the tests: a known tetrahedron in every PLY encoding, and helpers to
// write malformed PLY headers and bodies byte by byte.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include "core/mesh.h"

namespace voxplan::test {

inline void WriteFile(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// A PLY file: header lines after "ply" and "format", then end_header and the body.
struct Ply {
  explicit Ply(const std::string& format) : header("ply\nformat " + format + " 1.0\n") {}
  std::string Bytes() const { return header + "end_header\n" + body; }
  std::string header, body;
};

template <typename T>
std::string Raw(T v, bool big_endian = false) {
  std::string b(sizeof(T), '\0');
  std::memcpy(b.data(), &v, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b.begin(), b.end());
  return b;
}
inline std::string Floats(std::initializer_list<float> v) {
  std::string b;
  for (float f : v) b += Raw(f);
  return b;
}
inline std::string Ints(std::initializer_list<int32_t> v) {
  std::string b;
  for (int32_t i : v) b += Raw(i);
  return b;
}
// A face as `list uchar int`.
inline std::string Face(std::initializer_list<int32_t> v) {
  return Raw(uint8_t(v.size())) + Ints(v);
}

// A tetrahedron with unit normals and colours, every vertex distinct.
inline Mesh KnownMesh() {
  Mesh m;
  m.positions = {{0.5f, -1.25f, 2}, {1.5f, -1.25f, 2}, {0.5f, 0.75f, 2}, {0.5f, -1.25f, 3.5f}};
  m.normals = {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.colors = {{{10, 20, 30}}, {{255, 0, 7}}, {{0, 128, 255}}, {{99, 98, 97}}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}

// KnownMesh in `format`, with different types per encoding and properties the reader must skip.
inline std::string EncodeKnownMesh(const std::string& format) {
  const Mesh m = KnownMesh();
  const bool ascii = format == "ascii", be = format == "binary_big_endian";
  Ply ply(format);
  ply.header += "comment made by the voxplan tests\nelement vertex 4\n";
  ply.header += be ? "property double x\nproperty double y\nproperty double z\n"
                   : "property float x\nproperty float y\nproperty float z\n";
  ply.header +=
      "property ushort quality\nproperty float nx\nproperty float ny\nproperty float nz\n";
  ply.header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  ply.header += std::string("element face 4\nproperty ") +
                (be ? "list ushort uint vertex_indices\n" : "list uchar int vertex_indices\n") +
                "property short material\n";
  std::ostringstream text;
  std::string bin;
  for (size_t v = 0; v < 4; ++v) {
    const auto& p = m.positions[v];
    const auto& n = m.normals[v];
    const auto& c = m.colors[v];
    text << p.x() << ' ' << p.y() << ' ' << p.z() << " 7 " << n.x() << ' ' << n.y() << ' ' << n.z()
         << ' ' << int(c[0]) << ' ' << int(c[1]) << ' ' << int(c[2]) << '\n';
    for (int k = 0; k < 3; ++k) bin += be ? Raw(double(p[k]), true) : Raw(p[k]);
    bin += Raw(uint16_t(7), be);
    for (int k = 0; k < 3; ++k) bin += Raw(n[k], be);
    for (int k = 0; k < 3; ++k) bin += Raw(c[k]);
  }
  for (const auto& t : m.triangles) {
    text << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << " -1\n";
    bin += be ? Raw(uint16_t(3), true) : Raw(uint8_t(3));
    for (uint32_t i : t) bin += be ? Raw(i, true) : Raw(int32_t(i));
    bin += Raw(int16_t(-1), be);
  }
  ply.body = ascii ? text.str() : bin;
  return ply.Bytes();
}

}  // namespace voxplan::test
