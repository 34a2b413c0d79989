// What the OBJ and GLB writers put in the file, read from the file itself (a reader that joins
// vertices, as assimp's does, would hide a writer that merged them): every vertex and triangle
// as given, in order, positions bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/file_util.h"
#include "io/mesh_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

// A square of two triangles whose shared corner is stored twice, one copy per triangle, with the
// same normal and colour (as a mesh cut along a seam is): a writer must keep both copies. The
// coordinates need all nine digits of a float.
Mesh SeamedSquare() {
  Mesh mesh;
  mesh.positions = {{0.123456791f, -2.71828175f, 1.0e-7f},
                    {1.00000012f, -2.71828175f, 1.0e-7f},
                    {1.00000012f, 3.14159274f, 1.0e-7f},
                    {0.123456791f, 3.14159274f, 1.0e-7f},
                    {1.00000012f, 3.14159274f, 1.0e-7f}};  // vertex 2 again
  mesh.normals.assign(5, Eigen::Vector3f::UnitZ());
  mesh.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {17, 34, 51}, {0, 0, 255}};
  mesh.triangles = {{0, 1, 2}, {0, 4, 3}};
  return mesh;
}

struct FileMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
};

FileMesh ParseObj(const std::string& text) {
  FileMesh m;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string tag;
    fields >> tag;
    if (tag == "v") {
      Eigen::Vector3f p;
      fields >> p.x() >> p.y() >> p.z();
      m.positions.push_back(p);
    } else if (tag == "f") {
      std::array<uint32_t, 3> t;
      for (uint32_t& i : t) {
        std::string corner;
        fields >> corner;
        i = uint32_t(std::stoul(corner.substr(0, corner.find('/')))) - 1;
      }
      m.triangles.push_back(t);
    }
  }
  return m;
}

uint32_t U32(const std::string& bytes, size_t at) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;
}

// The first primitive's positions and indices, through its accessors and buffer views.
FileMesh ParseGlb(const std::string& bytes) {
  FileMesh m;
  EXPECT_EQ(U32(bytes, 0), 0x46546C67u) << "glTF magic";
  EXPECT_EQ(U32(bytes, 8), bytes.size());
  const uint32_t json_size = U32(bytes, 12);
  const nlohmann::json gltf = nlohmann::json::parse(bytes.substr(20, json_size));
  const size_t bin = 20 + json_size + 8;
  const auto& primitive = gltf["meshes"][0]["primitives"][0];
  auto data = [&](int accessor_id, size_t* count) {
    const auto& accessor = gltf["accessors"][size_t(accessor_id)];
    const auto& view = gltf["bufferViews"][accessor["bufferView"].get<size_t>()];
    *count = accessor["count"].get<size_t>();
    return bytes.data() + bin + view.value("byteOffset", size_t{0});
  };
  size_t n = 0;
  const char* p = data(primitive["attributes"]["POSITION"].get<int>(), &n);
  m.positions.resize(n);
  for (size_t i = 0; i < n; ++i) std::memcpy(m.positions[i].data(), p + 12 * i, 12);
  const char* idx = data(primitive["indices"].get<int>(), &n);
  m.triangles.resize(n / 3);
  std::memcpy(m.triangles.data(), idx, n * 4);
  return m;
}

TEST(WriteMesh, ObjAndGlbHoldEveryVertexAndTriangleAsGiven) {
  test::TempDir dir("mesh_write");
  const Mesh mesh = SeamedSquare();
  for (const char* name : {"square.obj", "square.glb"}) {
    const std::string path = (dir / name).string();
    ASSERT_TRUE(WriteMesh(mesh, path).ok());
    Result<std::string> bytes = ReadFileToString(path);
    ASSERT_TRUE(bytes.ok());
    const FileMesh file = std::string(name).ends_with(".obj") ? ParseObj(*bytes) : ParseGlb(*bytes);
    ASSERT_EQ(file.positions.size(), mesh.num_vertices()) << name << ": vertices were joined";
    for (size_t v = 0; v < mesh.num_vertices(); ++v)
      EXPECT_EQ(file.positions[v], mesh.positions[v]) << name << " vertex " << v;
    EXPECT_EQ(file.triangles, mesh.triangles) << name;
  }
}

}  // namespace
}  // namespace voxplan
