#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "io/file_util.h"
#include "io/mesh_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr float kPositionTol = 1e-5f;
constexpr float kNormalTol = 1e-5f;

struct Bounds {
  Eigen::Vector3f lo, hi;
};
Bounds BoundsOf(const Mesh& mesh) {
  Bounds b{mesh.positions.at(0), mesh.positions.at(0)};
  for (const auto& p : mesh.positions) {
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

std::string Data(const std::string& rel) { return (test::SharedDataDir() / rel).string(); }

// Files in `dir`, so tests can check that failed writes leave no temporaries behind.
std::vector<std::string> Listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A closed, colourful test mesh: an octahedron whose vertices are all distinct, so importers
// that merge identical vertices give back exactly what was written.
Mesh Octahedron(bool with_normals, bool with_colors) {
  Mesh mesh;
  const Eigen::Vector3f c(0.25f, -1.5f, 3.0f);
  const Eigen::Vector3f axes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                   {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (int i = 0; i < 6; ++i) {
    mesh.positions.push_back(c + 0.7f * (i + 1) / 6.0f * axes[i]);
    if (with_normals) mesh.normals.push_back(axes[i]);
    if (with_colors)
      mesh.colors.push_back({uint8_t(40 * i), uint8_t(255 - 17 * i), uint8_t(3 + i)});
  }
  // Counter-clockwise seen from outside.
  mesh.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                    {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return mesh;
}

TEST(ReadMesh, ReplicaOfficePlyWithVertexColours) {
  auto mesh = ReadMesh(Data("scenes/replica_office0/office0_mesh.ply"));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->num_triangles(), 50000u);
  EXPECT_EQ(mesh->colors.size(), mesh->num_vertices());
  for (const auto& t : mesh->triangles)
    for (uint32_t i : t) ASSERT_LT(i, mesh->num_vertices());
  const Bounds b = BoundsOf(*mesh);
  // A room a few metres across.
  EXPECT_GT((b.hi - b.lo).minCoeff(), 1.0f);
  EXPECT_LT((b.hi - b.lo).maxCoeff(), 10.0f);
}

TEST(ReadMesh, CornellBoxObjTakesMaterialColoursAndYUp) {
  const std::string path = Data("scenes/cornell_box/CornellBox-Original.obj");
  auto y_up = ReadMesh(path, {1.0f, UpAxis::kY});
  ASSERT_TRUE(y_up.ok()) << y_up.status().message();
  EXPECT_EQ(y_up->num_triangles(), 36u);
  ASSERT_EQ(y_up->colors.size(), y_up->num_vertices());
  bool has_red = false, has_green = false;  // the coloured side walls
  for (const auto& c : y_up->colors) {
    has_red |= c[0] > 150 && c[1] < 40 && c[2] < 40;
    has_green |= c[1] > 100 && c[0] < 40 && c[2] < 40;
  }
  EXPECT_TRUE(has_red);
  EXPECT_TRUE(has_green);
  // The box stands on the floor: after the Y-up rotation its height runs along +z.
  const Bounds b = BoundsOf(*y_up);
  EXPECT_NEAR(b.lo.z(), 0.0f, 1e-4f);
  EXPECT_NEAR(b.hi.z(), 1.99f, 1e-3f);

  auto z_up = ReadMesh(path, {2.0f, UpAxis::kZ});
  ASSERT_TRUE(z_up.ok());
  ASSERT_EQ(z_up->num_vertices(), y_up->num_vertices());
  for (size_t v = 0; v < y_up->num_vertices(); ++v) {
    const Eigen::Vector3f p = z_up->positions[v] / 2.0f;  // (x, y, z) in the file
    EXPECT_NEAR(y_up->positions[v].x(), p.x(), kPositionTol);
    EXPECT_NEAR(y_up->positions[v].y(), -p.z(), kPositionTol);
    EXPECT_NEAR(y_up->positions[v].z(), p.y(), kPositionTol);
  }
}

TEST(ReadMesh, SimpleRoomGlbAppliesNodeTransforms) {
  auto mesh = ReadMesh(Data("scenes/simple_room/simple_room.glb"));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_GT(mesh->num_triangles(), 10u);
  EXPECT_EQ(mesh->normals.size(), mesh->num_vertices());
  EXPECT_EQ(mesh->colors.size(), mesh->num_vertices());
  for (const auto& n : mesh->normals) EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
  // The stage is Z-up (its stage config says so): a room about 10 m square and 2 m high.
  const Bounds b = BoundsOf(*mesh);
  EXPECT_GT(b.hi.x() - b.lo.x(), 8.0f);
  EXPECT_GT(b.hi.y() - b.lo.y(), 8.0f);
  EXPECT_LT(b.hi.z() - b.lo.z(), 3.0f);
}

TEST(ReadMesh, RefusesMissingGarbageAndTriangleFreeFiles) {
  test::TempDir dir("mesh_io");
  const std::string missing = (dir / "missing.ply").string();
  auto r = ReadMesh(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find(missing), std::string::npos) << r.status().message();

  const std::string garbage = (dir / "garbage.ply").string();
  std::ofstream(garbage) << "this is not a mesh\n";
  r = ReadMesh(garbage);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find(garbage), std::string::npos) << r.status().message();

  const std::string points = (dir / "points.ply").string();
  std::ofstream(points) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  r = ReadMesh(points);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find(points), std::string::npos) << r.status().message();

  r = ReadMesh(Data("scenes/cornell_box/CornellBox-Original.obj"), {0.0f, UpAxis::kZ});
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
}

// Exporters may reorder vertices: match each vertex of `a` to the one of `b` at the same place,
// then compare attributes and triangles (same winding) through that matching.
void ExpectSameMesh(const Mesh& a, const Mesh& b, bool normals, bool colors, int color_tol = 0) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_triangles(), b.num_triangles());
  std::vector<uint32_t> a_to_b(a.num_vertices());
  for (size_t v = 0; v < a.num_vertices(); ++v) {
    size_t best = 0;
    for (size_t w = 1; w < b.num_vertices(); ++w)
      if ((b.positions[w] - a.positions[v]).squaredNorm() <
          (b.positions[best] - a.positions[v]).squaredNorm())
        best = w;
    ASSERT_LT((a.positions[v] - b.positions[best]).cwiseAbs().maxCoeff(), kPositionTol) << v;
    a_to_b[v] = uint32_t(best);
  }
  if (normals) {
    ASSERT_EQ(b.normals.size(), b.num_vertices());
    for (size_t v = 0; v < a.num_vertices(); ++v)
      EXPECT_LT((a.normals[v] - b.normals[a_to_b[v]]).cwiseAbs().maxCoeff(), kNormalTol) << v;
  }
  if (colors) {
    ASSERT_EQ(b.colors.size(), b.num_vertices());
    for (size_t v = 0; v < a.num_vertices(); ++v)
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(int(a.colors[v][k]), int(b.colors[a_to_b[v]][k]), color_tol) << v;
  }
  // Canonical triangles: rotated so the smallest index leads (keeps winding), then sorted.
  auto canonical = [](std::vector<std::array<uint32_t, 3>> tris) {
    for (auto& t : tris) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    std::sort(tris.begin(), tris.end());
    return tris;
  };
  std::vector<std::array<uint32_t, 3>> mapped;
  for (const auto& t : a.triangles) mapped.push_back({a_to_b[t[0]], a_to_b[t[1]], a_to_b[t[2]]});
  EXPECT_EQ(canonical(mapped), canonical(b.triangles));
}

TEST(WriteMesh, PlyRoundTripIsExact) {
  test::TempDir dir("mesh_io");
  for (bool normals : {false, true}) {
    for (bool colors : {false, true}) {
      const Mesh mesh = Octahedron(normals, colors);
      const std::string path = (dir / "octahedron.PLY").string();  // extension case ignored
      ASSERT_TRUE(WriteMesh(mesh, path).ok());
      auto back = ReadMesh(path);
      ASSERT_TRUE(back.ok()) << back.status().message();
      ExpectSameMesh(mesh, *back, normals, colors);
      if (!colors) {
        EXPECT_TRUE(back->colors.empty());
      }
      if (!normals) {
        EXPECT_TRUE(back->normals.empty());
      }
      EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"octahedron.PLY"});
    }
  }
}

TEST(WriteMesh, ObjAndGlbRoundTrip) {
  test::TempDir dir("mesh_io");
  const Mesh mesh = Octahedron(true, true);
  for (const char* name : {"octahedron.obj", "octahedron.glb"}) {
    const std::string path = (dir / name).string();
    const Status written = WriteMesh(mesh, path);
    ASSERT_TRUE(written.ok()) << written.message();
    auto back = ReadMesh(path);
    ASSERT_TRUE(back.ok()) << back.status().message();
    // Colours go through 0..1 floats; allow one step of rounding.
    ExpectSameMesh(mesh, *back, /*normals=*/true, /*colors=*/true, /*color_tol=*/1);
  }
  // "obj" would have written a .mtl beside the file; nothing else may appear.
  EXPECT_EQ(Listing(dir.path()), (std::vector<std::string>{"octahedron.glb", "octahedron.obj"}));
}

TEST(WriteMesh, StlKeepsTrianglesAndBounds) {
  test::TempDir dir("mesh_io");
  const Mesh mesh = Octahedron(false, false);
  const std::string path = (dir / "octahedron.stl").string();
  ASSERT_TRUE(WriteMesh(mesh, path).ok());
  auto back = ReadMesh(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->num_triangles(), mesh.num_triangles());
  const Bounds a = BoundsOf(mesh), b = BoundsOf(*back);
  EXPECT_LT((a.lo - b.lo).cwiseAbs().maxCoeff(), kPositionTol);
  EXPECT_LT((a.hi - b.hi).cwiseAbs().maxCoeff(), kPositionTol);
}

TEST(WriteMesh, RefusesUnknownExtensionAndBadMeshes) {
  test::TempDir dir("mesh_io");
  const std::string path = (dir / "mesh.xyz").string();
  const Status s = WriteMesh(Octahedron(false, false), path);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(".xyz"), std::string::npos) << s.message();
  EXPECT_FALSE(IsSupportedMeshExtension(path));
  EXPECT_TRUE(IsSupportedMeshExtension("a/b.GLB"));

  Mesh bad = Octahedron(false, true);
  bad.triangles.push_back({0, 1, 6});
  EXPECT_EQ(WriteMesh(bad, (dir / "bad.ply").string()).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(WriteMesh(Mesh{}, (dir / "empty.ply").string()).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(Listing(dir.path()).empty());
}

TEST(WriteMesh, FailedWriteLeavesNothingAndKeepsExistingFile) {
  test::TempDir dir("mesh_io");
  const std::string nowhere = (dir / "no_such_folder" / "mesh.ply").string();
  const Status s = WriteMesh(Octahedron(true, true), nowhere);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(nowhere), std::string::npos) << s.message();
  EXPECT_TRUE(Listing(dir.path()).empty());

  // An existing file survives a failed write untouched.
  const std::string existing = (dir / "mesh.ply").string();
  ASSERT_TRUE(WriteMesh(Octahedron(false, false), existing).ok());
  auto before = ReadFileToString(existing);
  ASSERT_TRUE(before.ok());
  Mesh bad = Octahedron(true, true);
  bad.colors.pop_back();
  EXPECT_FALSE(WriteMesh(bad, existing).ok());
  auto after = ReadFileToString(existing);
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(*before, *after);
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"mesh.ply"});
}

TEST(WriteAtomically, FailingWriterLeavesTargetUntouched) {
  test::TempDir dir("file_util");
  const std::string path = (dir / "target.bin").string();
  ASSERT_TRUE(WriteAtomically(path, [](const std::string& tmp) {
                return WriteStringToFile(tmp, "old contents");
              }).ok());
  std::string seen_tmp;
  const Status s = WriteAtomically(path, [&](const std::string& tmp) {
    seen_tmp = tmp;
    EXPECT_TRUE(WriteStringToFile(tmp, "half of the new").ok());
    return IoError("disk full (simulated)");
  });
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_EQ(fs::path(seen_tmp).parent_path(), dir.path());
  EXPECT_EQ(fs::path(seen_tmp).extension(), ".bin");
  auto contents = ReadFileToString(path);
  ASSERT_TRUE(contents.ok());
  EXPECT_EQ(*contents, "old contents");
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"target.bin"});

  // A writer that "succeeds" without producing a file is an error too.
  EXPECT_FALSE(WriteAtomically(path, [](const std::string&) { return Status::Ok(); }).ok());
  EXPECT_EQ(*ReadFileToString(path), "old contents");
}

TEST(ReadFileToString, NamesTheFile) {
  test::TempDir dir("file_util");
  const std::string missing = (dir / "missing.txt").string();
  auto r = ReadFileToString(missing);
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find(missing), std::string::npos);
  EXPECT_FALSE(ReadFileToString(dir.path().string()).ok());
  const std::string empty = (dir / "empty.txt").string();
  std::ofstream{empty};
  auto e = ReadFileToString(empty);
  ASSERT_TRUE(e.ok());
  EXPECT_TRUE(e->empty());
}

}  // namespace
}  // namespace voxplan
