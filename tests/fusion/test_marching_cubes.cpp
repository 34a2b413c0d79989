// Marching cubes on exact signed distance fields: closed, on the surface, right area, normals out.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "fusion/integrate.h"
#include "fusion/marching_cubes_table.h"
#include "fusion/mesh_extract.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

template <typename Sdf>
TsdfVolume FillExact(const Sdf& sdf, float voxel, float trunc, const Eigen::Vector3f& lo,
                     const Eigen::Vector3f& hi) {
  return test::FillExactSdf(sdf, {voxel, trunc}, lo, hi);
}

TEST(MarchingCubes, TableCoversEveryCaseConsistently) {
  const auto& table = internal::MarchingCubesTable();
  EXPECT_EQ(table[0].num_triangles, 0);
  EXPECT_EQ(table[255].num_triangles, 0);
  for (int i = 1; i < 255; ++i) {
    EXPECT_GT(table[i].num_triangles, 0) << "case " << i;
    EXPECT_LE(table[i].num_triangles, 12) << "case " << i;
  }
  EXPECT_EQ(table[1].num_triangles, 1);   // one corner inside: one triangle
  EXPECT_EQ(table[3].num_triangles, 2);   // one edge inside: a quad
  EXPECT_EQ(table[15].num_triangles, 2);  // half the cube: a quad
}

TEST(MarchingCubes, SphereIsClosedOnTheSurfaceWithTheRightArea) {
  const Eigen::Vector3f c(0.013f, -0.021f, 0.007f);
  const float r = 0.3f, voxel = 0.01f;
  auto sdf = [&](const Eigen::Vector3f& p) { return (p - c).norm() - r; };
  const TsdfVolume volume = FillExact(sdf, voxel, 4 * voxel, c - Eigen::Vector3f::Constant(0.5f),
                                      c + Eigen::Vector3f::Constant(0.5f));
  const Mesh mesh = ExtractMesh(volume);
  ASSERT_GT(mesh.num_triangles(), 1000u);
  EXPECT_EQ(test::EdgesNotClosed(mesh), 0u) << "edges not shared by exactly two opposite triangles";

  double area = 0.0;
  for (const auto& t : mesh.triangles)
    area += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]])
                      .cross(mesh.positions[t[2]] - mesh.positions[t[0]])
                      .norm();
  const double true_area = 4.0 * M_PI * r * r;
  EXPECT_NEAR(area / true_area, 1.0, 0.01);  // within 1 %

  constexpr float kMaxDistanceVox = 0.05f;  // linear interpolation of an exact SDF
  float worst = 0.f, worst_normal = 1.f;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    worst = std::max(worst, std::abs(sdf(mesh.positions[i])));
    worst_normal =
        std::min(worst_normal, mesh.normals[i].dot((mesh.positions[i] - c).normalized()));
  }
  EXPECT_LT(worst, kMaxDistanceVox * voxel);
  EXPECT_GT(worst_normal, 0.98f) << "normals point outwards";
  ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
  EXPECT_EQ(mesh.colors[0], (std::array<uint8_t, 3>{10, 20, 30}));
}

TEST(MarchingCubes, UnobservedVoxelsProduceNothing) {
  auto sdf = [](const Eigen::Vector3f& p) { return p.z() - 0.0123f; };
  TsdfVolume volume = FillExact(sdf, 0.02f, 0.08f, Eigen::Vector3f(-0.3f, -0.3f, -0.2f),
                                Eigen::Vector3f(0.3f, 0.3f, 0.2f));
  const size_t full = ExtractMesh(volume).num_triangles();
  ASSERT_GT(full, 0u);
  volume.ForEachBlock([&](BlockIndex, const TsdfBlock&) {});
  for (const BlockIndex& b : volume.SortedBlockIndices()) {
    TsdfBlock* block = volume.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i)
      if (b.x >= 0) block->weight[i] = 0;
  }
  MeshParams params;
  const size_t half = ExtractMesh(volume, params).num_triangles();
  EXPECT_GT(half, 0u);
  EXPECT_LT(half, full * 6 / 10);
  params.min_weight = 2.0f;  // every voxel has weight 1: all skipped
  EXPECT_EQ(ExtractMesh(volume, params).num_triangles(), 0u);
}

// Observed free space only: every block is meshed and yields no triangle. Found by fuzz_map (a
// loaded map of such blocks); under UBSan (build-asan) assembling it bound a reference to the
// empty triangle array.
TEST(MarchingCubes, ObservedFreeSpaceGivesAnEmptyMesh) {
  TsdfVolume volume({0.05f, 0.2f});
  for (int x = 0; x < 3; ++x) {
    TsdfBlock& block = volume.FindOrAllocate({x, 0, 0});
    for (int i = 0; i < kBlockVoxels; ++i) {
      block.tsdf[i] = EncodeTsdf(1.f);
      block.weight[i] = EncodeWeight(4.f);
    }
  }
  const Mesh mesh = ExtractMesh(volume);
  EXPECT_TRUE(mesh.triangles.empty());
  EXPECT_TRUE(mesh.positions.empty());
}

}  // namespace
}  // namespace voxplan

namespace voxplan {
namespace {

bool SameMesh(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.normals == b.normals && a.colors == b.colors &&
         a.triangles == b.triangles;
}

// Frames of a sphere seen from a camera that circles it: each frame changes some blocks, and
// the incremental mesh must equal a from-scratch extraction after every one of them.
TEST(IncrementalMesher, EqualsFullExtractionAfterEveryFrame) {
  const test::Sphere sphere{{0.f, 0.f, 0.f}, 0.4f};
  const PinholeCamera camera = test::TestCamera(120, 90);
  TsdfVolume volume({0.02f, 0.06f});
  IntegrateParams params;
  IncrementalMesher mesher;
  size_t remeshed_total = 0, blocks_total = 0;
  for (int k = 0; k < 8; ++k) {
    const float a = 0.6f * float(k);
    const Eigen::Vector3f eye(1.3f * std::cos(a), 1.3f * std::sin(a), 0.3f);
    const Pose3f T_W_C = test::LookAt(eye, sphere.c);
    const DepthImage depth = test::RenderDepth(sphere, camera, T_W_C);
    const std::vector<BlockIndex> touched =
        BlocksInTruncationBand(depth, camera, T_W_C, params, volume.params());
    ASSERT_TRUE(IntegrateFrame(depth, ColorImage{}, camera, T_W_C, params, volume).ok());
    remeshed_total += mesher.Update(volume, touched);
    blocks_total += volume.num_blocks();
    const Mesh full = ExtractMesh(volume);
    ASSERT_GT(full.num_triangles(), 0u);
    ASSERT_TRUE(SameMesh(mesher.Assemble(), full)) << "after frame " << k;
  }
  // The point of it: fewer blocks meshed than a full extraction per frame would.
  EXPECT_LT(remeshed_total, blocks_total);

  IncrementalMesher rebuilt;
  rebuilt.Rebuild(volume);
  EXPECT_TRUE(SameMesh(rebuilt.Assemble(), ExtractMesh(volume)));
  EXPECT_EQ(rebuilt.num_pieces(), mesher.num_pieces());
}

TEST(IncrementalMesher, ErasedBlocksLoseTheirPieces) {
  const test::Sphere sphere{{0.f, 0.f, 0.f}, 0.3f};
  TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); }, 0.02f, 0.06f,
                Eigen::Vector3f::Constant(-0.5f), Eigen::Vector3f::Constant(0.5f));
  IncrementalMesher mesher;
  mesher.Rebuild(volume);
  const size_t before = mesher.Assemble().num_triangles();
  std::vector<BlockIndex> erased;
  for (const BlockIndex& b : volume.SortedBlockIndices())
    if (b.x >= 1) erased.push_back(b);
  ASSERT_FALSE(erased.empty());
  for (const BlockIndex& b : erased) volume.EraseBlock(b);
  mesher.Update(volume, erased);
  const Mesh after = mesher.Assemble();
  EXPECT_LT(after.num_triangles(), before);
  EXPECT_TRUE(SameMesh(after, ExtractMesh(volume)));
}

}  // namespace
}  // namespace voxplan
