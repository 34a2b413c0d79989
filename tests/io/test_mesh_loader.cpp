// The validating mesh loader behind ReadMesh: voxplan's own PLY reader (every encoding, refusals
// of malformed files before anything is allocated), and the confined assimp for the rest
// (format by extension only, no file outside the mesh's folder, no FIFO).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>

#include "io/mesh_io.h"
#include "tests/io/mesh_fixtures.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Ply;

// ReadMesh on `path` must fail within seconds with a message naming the file and `reason`.
void ExpectRefused(const fs::path& path, const std::string& reason) {
  const auto start = std::chrono::steady_clock::now();
  const Result<Mesh> mesh = ReadMesh(path.string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(mesh.ok()) << path << " was accepted";
  const std::string& m = mesh.status().message();
  EXPECT_NE(m.find(path.string()), std::string::npos) << m;
  EXPECT_NE(m.find(reason), std::string::npos) << "expected '" << reason << "' in: " << m;
  EXPECT_LT(seconds, 5.0) << m;
}

void ExpectSameMesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.colors, b.colors);
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (size_t v = 0; v < a.num_vertices(); ++v) {
    EXPECT_TRUE(a.positions[v].isApprox(b.positions[v], 1e-6f)) << "vertex " << v;
    if (!a.normals.empty()) {
      EXPECT_TRUE(a.normals[v].isApprox(b.normals[v], 1e-6f));
    }
  }
}

TEST(PlyReader, AsciiAndBothBinaryByteOrdersReadTheKnownMesh) {
  test::TempDir dir("ply_encodings");
  const Mesh expected = test::KnownMesh();
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const fs::path path = dir / (std::string(format) + ".ply");
    test::WriteFile(path, test::EncodeKnownMesh(format));
    const Result<Mesh> mesh = ReadMesh(path.string());
    ASSERT_TRUE(mesh.ok()) << format << ": " << mesh.status().message();
    SCOPED_TRACE(format);
    ExpectSameMesh(*mesh, expected);
  }
}

TEST(PlyReader, FanTriangulatesPolygonsAndSkipsOtherElements) {
  test::TempDir dir("ply_polygons");
  Ply ply("ascii");
  ply.header += "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n";
  ply.header += "property list uchar int extra\n";
  ply.header += "element edge 1\nproperty int vertex1\nproperty int vertex2\n";
  ply.header += "element face 1\nproperty uchar flags\nproperty list int int vertex_index\n";
  ply.body = "0 0 0 2 7 8\n1 0 0 0\n1 1 0 1 5\n0 1 0 0\n0 1\n9 4 0 1 2 3\n";
  const fs::path path = dir / "quad.ply";
  test::WriteFile(path, ply.Bytes());
  const Result<Mesh> mesh = ReadMesh(path.string());
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->num_vertices(), 4u);
  EXPECT_EQ(mesh->triangles, (std::vector<std::array<uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}));
  EXPECT_EQ(mesh->positions[2], Eigen::Vector3f(1, 1, 0));
}

struct BadPly {
  const char* name;
  std::string bytes;
  const char* reason;
};

std::vector<BadPly> MalformedPlys() {
  const std::string le = "binary_little_endian";
  auto xyz = [](uint32_t n) {
    return "element vertex " + std::to_string(n) +
           "\nproperty float x\nproperty float y\nproperty float z\n";
  };
  const std::string faces1 = "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string tri = test::Floats({0, 0, 0, 1, 0, 0, 0, 1, 0});
  std::vector<BadPly> cases;
  auto add = [&](const char* name, const std::string& format, const std::string& header,
                 const std::string& body, const char* reason) {
    Ply ply(format);
    ply.header += header;
    ply.body = body;
    cases.push_back({name, ply.Bytes(), reason});
  };
  add("truncated_vertices", le, xyz(3) + faces1, tri.substr(0, 20), "only 20 bytes follow");
  add("truncated_faces", le, xyz(3) + "element face 2\nproperty list uchar int vertex_indices\n",
      tri + test::Face({0, 1, 2, 0}) + test::Face({0, 1, 2}).substr(0, 10), "ends in the middle");
  add("index_out_of_range", le, xyz(3) + faces1, tri + test::Face({0, 1, 7}),
      "vertex index 7 is out of range");
  add("negative_index", le, xyz(3) + faces1, tri + test::Face({0, -1, 2}), "out of range");
  add("two_index_face", le, xyz(3) + faces1, tri + test::Face({0, 1}) + test::Ints({0}),
      "has 2 vertex indices");
  add("huge_list", le, xyz(3) + "element face 1\nproperty list int int vertex_indices\n",
      tri + test::Ints({2000000000, 0, 1, 2}), "has 2000000000 vertex indices");
  add("count_beyond_file", le, xyz(4000000000u) + faces1, tri, "declares 4000000000 records");
  add("face_count_beyond_file", le,
      xyz(3) + "element face 900000000000\nproperty list uchar int vertex_indices\n",
      tri + test::Face({0, 1, 2}), "declares 900000000000 records");
  add("ascii_count_beyond_file", "ascii", xyz(100000000) + faces1, "0 0 0\n1 0 0\n",
      "declares 100000000 records");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  add("nan_coordinate", le, xyz(3) + faces1,
      test::Floats({0, 0, 0, nan, 0, 0, 0, 1, 0}) + test::Face({0, 1, 2}), "not finite");
  add("huge_coordinate", le, xyz(3) + faces1,
      test::Floats({0, 0, 0, 1e19f, 0, 0, 0, 1, 0}) + test::Face({0, 1, 2}), "beyond the bound");
  add("ascii_nan", "ascii", xyz(3) + faces1, "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n",
      "line 11: vertex 1: coordinates");
  add("ascii_word", "ascii", xyz(3) + faces1, "0 0 0\n1 0 0\n0 1 zero\n3 0 1 2\n",
      "line 12: vertex 2: 'zero' is not a value");
  add("unknown_type", le, "element vertex 3\nproperty flaot x\n", "", "line 4: unknown property");
  add("no_faces", le, xyz(3), tri, "no face element");
  cases.push_back({"no_end_header", "ply\nformat ascii 1.0\nelement vertex 1\n", "end_header"});
  cases.push_back({"endless_header", "ply\nformat ascii 1.0\n" + std::string(100000, 'x'),
                   "no end_header line within the first 65536 bytes"});
  cases.push_back({"not_ply", "solid cube\nfacet normal 0 0 1\n", "not a PLY file"});
  return cases;
}

TEST(PlyReader, RefusesEveryMalformedFileNamingTheFileAndTheReason) {
  test::TempDir dir("ply_malformed");
  for (const BadPly& c : MalformedPlys()) {
    SCOPED_TRACE(c.name);
    const fs::path path = dir / (std::string(c.name) + ".ply");
    test::WriteFile(path, c.bytes);
    ExpectRefused(path, c.reason);
  }
}

TEST(PlyReader, ReadsTheSharedDataMeshesAsAssimpDid) {
  // Counts and first entries as assimp 5.2 (JoinIdenticalVertices) gave them: unused vertices
  // dropped, equal ones merged, file order kept.
  struct Expect {
    const char* path;
    size_t vertices, triangles;
  };
  for (const Expect& e :
       {Expect{"scenes/replica_office0/office0_mesh.ply", 25149, 50000},
        Expect{"scenes/aws_small_house/derived/small_house_visual.ply", 78775, 145844},
        Expect{"scenes/aws_small_house/derived/small_house_collision.ply", 2566, 4131}}) {
    const Result<Mesh> mesh = ReadMesh((test::SharedDataDir() / e.path).string());
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_EQ(mesh->num_vertices(), e.vertices) << e.path;
    EXPECT_EQ(mesh->num_triangles(), e.triangles) << e.path;
  }
}

TEST(AssimpLoader, PlyBytesNamedGlbAreRefused) {
  test::TempDir dir("glb_named_ply");
  const fs::path path = dir / "mesh.glb";
  test::WriteFile(path, test::EncodeKnownMesh("binary_little_endian"));
  ExpectRefused(path, "not a binary glTF file");
}

TEST(AssimpLoader, RefusesMalformedGlbAndStl) {
  test::TempDir dir("glb_stl_bad");
  const fs::path glb = dir / "short.glb";
  std::string header("glTF\x02\0\0\0", 8);
  const uint32_t length = 4000;  // more than the file has
  header.append(reinterpret_cast<const char*>(&length), 4);
  test::WriteFile(glb, header + std::string(20, ' '));
  ExpectRefused(glb, "the header gives a length of 4000 bytes");

  const fs::path stl = dir / "truncated.stl";
  std::string bytes = "solid binary header" + std::string(61, ' ');
  const uint32_t n = 10;
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  bytes += std::string(120, '\0');  // 2.4 of the 10 triangles
  test::WriteFile(stl, bytes);
  ExpectRefused(stl, "a binary STL of 10 triangles has 584 bytes");
}

// A valid GLB (written by WriteMesh) whose JSON is edited by `edit`, chunks re-assembled.
std::string EditedGlb(const fs::path& dir, const std::function<void(nlohmann::json&)>& edit) {
  const fs::path path = dir / "valid.glb";
  EXPECT_TRUE(WriteMesh(test::KnownMesh(), path.string()).ok());
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  uint32_t json_length = 0;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  nlohmann::json doc = nlohmann::json::parse(bytes.substr(20, json_length));
  edit(doc);
  std::string json = doc.dump();
  json.resize((json.size() + 3) / 4 * 4, ' ');
  const std::string rest = bytes.substr(20 + json_length);
  const std::string chunk = test::Raw(uint32_t(json.size())) + "JSON" + json + rest;
  return "glTF" + test::Raw(uint32_t(2)) + test::Raw(uint32_t(12 + chunk.size())) + chunk;
}

TEST(AssimpLoader, RefusesGlbWhoseAccessorsOrNodesAreOutOfBounds) {
  test::TempDir dir("glb_edit");
  const fs::path valid = dir / "edited.glb";
  test::WriteFile(valid, EditedGlb(dir.path(), [](nlohmann::json&) {}));
  ASSERT_TRUE(ReadMesh(valid.string()).ok()) << "the unedited re-assembly must load";
  const std::pair<std::function<void(nlohmann::json&)>, const char*> edits[] = {
      {[](nlohmann::json& j) { j["accessors"][0]["count"] = 1000000000; }, "run past the end"},
      {[](nlohmann::json& j) { j["bufferViews"][0]["byteLength"] = 1 << 30; },
       "lies outside its buffer"},
      {[](nlohmann::json& j) { j["nodes"][0]["children"] = {0}; }, "the nodes form a cycle"},
      {[](nlohmann::json& j) { j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99; },
       "names none of the"},
  };
  for (const auto& [edit, reason] : edits) {
    SCOPED_TRACE(reason);
    const fs::path path = dir / "bad.glb";
    test::WriteFile(path, EditedGlb(dir.path(), edit));
    ExpectRefused(path, reason);
  }
}

// An OBJ whose material file lies outside its folder, reached by "../" and by a symlink: the
// material must not be read (the triangle keeps assimp's default grey, not red).
TEST(AssimpLoader, ObjMaterialsOutsideTheMeshFolderAreNotRead) {
  test::TempDir dir("obj_outside");
  fs::create_directory(dir / "mesh");
  test::WriteFile(dir / "outside.mtl", "newmtl red\nKd 1 0 0\n");
  fs::create_symlink(dir / "outside.mtl", dir / "mesh" / "link.mtl");
  for (const char* mtllib : {"../outside.mtl", "link.mtl"}) {
    SCOPED_TRACE(mtllib);
    const fs::path obj = dir / "mesh" / "tri.obj";
    test::WriteFile(obj, std::string("mtllib ") + mtllib +
                             "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    const Result<Mesh> mesh = ReadMesh(obj.string());
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    for (const auto& c : mesh->colors) EXPECT_NE(c, (std::array<uint8_t, 3>{255, 0, 0}));
  }
  // The same material inside the folder is read: the check above is not vacuous.
  fs::copy_file(dir / "outside.mtl", dir / "mesh" / "inside.mtl");
  test::WriteFile(dir / "mesh" / "tri.obj",
                  "mtllib inside.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  const Result<Mesh> mesh = ReadMesh((dir / "mesh" / "tri.obj").string());
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->colors.size(), 3u);
  EXPECT_EQ(mesh->colors[0], (std::array<uint8_t, 3>{255, 0, 0}));
}

TEST(AssimpLoader, ObjMaterialFifoDoesNotBlock) {
  test::TempDir dir("obj_fifo");
  const fs::path fifo = dir / "fifo.mtl";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const fs::path obj = dir / "tri.obj";
  test::WriteFile(obj, "mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  auto read = std::async(std::launch::async, [&] { return ReadMesh(obj.string()); });
  const bool done = read.wait_for(std::chrono::seconds(10)) == std::future_status::ready;
  if (!done) {  // unblock the reader so the test can end: open the FIFO's other side
    const int fd = open(fifo.c_str(), O_WRONLY);
    if (fd >= 0) close(fd);
  }
  ASSERT_TRUE(done) << "ReadMesh blocked on the FIFO";
  const Result<Mesh> mesh = read.get();
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->num_triangles(), 1u);
}

TEST(AssimpLoader, RefusesAFifoAsTheMeshItself) {
  test::TempDir dir("mesh_fifo");
  const fs::path fifo = dir / "mesh.ply";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ExpectRefused(fifo, "not a regular file");
}

}  // namespace
}  // namespace voxplan
