// OctoMap export: the .bt file read back by OctoMap holds every observed voxel with its state
// and nothing else; same map, same bytes; unwritable paths fail cleanly.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "io/file_util.h"
#include "planning/integrate_planning.h"
#include "planning/octomap_export.h"
#include "planning/planning_map.h"
#include "tests/fusion/box_room.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

constexpr float kVoxel = 0.05f;

// The box room of the planning-map tests, seen from its centre looking along +x, +y and -z.
TsdfVolume RoomVolume() {
  const test::BoxRoom room{Eigen::Vector3f(-1.49f, -1.29f, -0.99f),
                           Eigen::Vector3f(1.49f, 1.29f, 0.99f)};
  TsdfVolume volume({kVoxel, 3 * kVoxel});
  PlanningMap map(volume);
  const PinholeCamera cam = test::RoomCamera(64);
  IntegrateParams params;
  params.max_depth_m = 4.f;
  const std::vector<Pose3f> views = test::AxisViews(Eigen::Vector3f(0.02f, 0.03f, 0.01f));
  for (int k : {0, 2, 5}) {
    const DepthImage depth = test::RenderRoomDepth(room, cam, views[size_t(k)]);
    EXPECT_TRUE(
        IntegratePlanningFrame(depth, {}, nullptr, cam, views[size_t(k)], params, volume, map)
            .ok());
  }
  return volume;
}

TEST(OctomapExport, RoundTripKeepsEveryVoxelState) {
  const TsdfVolume volume = RoomVolume();
  const PlanningMap map(volume);  // StateAt only: no sidecars needed
  test::TempDir dir("octomap");
  const std::string path = (dir / "room.bt").string();
  auto stats = ExportOctomap(volume, path);
  ASSERT_TRUE(stats.ok()) << stats.status().message();
  EXPECT_GT(stats->occupied_voxels, 1000u);
  EXPECT_GT(stats->free_voxels, 10000u);
  EXPECT_EQ(stats->outside_range, 0u);

  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  EXPECT_NEAR(tree.getResolution(), kVoxel, 1e-7);
  size_t occupied = 0, free = 0, unknown = 0;
  for (const BlockIndex& b : volume.SortedBlockIndices())
    for (int i = 0; i < kBlockVoxels; ++i) {
      const GlobalVoxelIndex g = GlobalOf(b, VoxelOfLinear(i));
      const Eigen::Vector3f c = VoxelCenter(g, kVoxel);
      const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
      switch (map.StateAt(g)) {
        case VoxelState::kOccupied:
          ASSERT_NE(node, nullptr);
          EXPECT_TRUE(tree.isNodeOccupied(node));
          ++occupied;
          break;
        case VoxelState::kFree:
          ASSERT_NE(node, nullptr);
          EXPECT_FALSE(tree.isNodeOccupied(node));
          ++free;
          break;
        case VoxelState::kUnobserved:
          EXPECT_EQ(node, nullptr);
          ++unknown;
          break;
      }
    }
  EXPECT_EQ(occupied, stats->occupied_voxels);
  EXPECT_EQ(free, stats->free_voxels);
  EXPECT_GT(unknown, 1000u);
  // Leaves the tree counts cover exactly the observed voxels (pruned nodes stand for 8^k).
  size_t leaf_voxels = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const double cells = it.getSize() / tree.getResolution();
    leaf_voxels += size_t(std::llround(cells * cells * cells));
  }
  EXPECT_EQ(leaf_voxels, occupied + free);
}

TEST(OctomapExport, SameMapSameBytes) {
  const TsdfVolume volume = RoomVolume();
  test::TempDir dir("octomap");
  ASSERT_TRUE(ExportOctomap(volume, (dir / "a.bt").string()).ok());
  ASSERT_TRUE(ExportOctomap(volume, (dir / "b.bt").string()).ok());
  auto a = ReadFileToString((dir / "a.bt").string());
  auto b = ReadFileToString((dir / "b.bt").string());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_GT(a->size(), 100u);
  EXPECT_EQ(*a, *b);
}

TEST(OctomapExport, UnwritablePathFailsAndLeavesNothing) {
  const TsdfVolume volume = RoomVolume();
  test::TempDir dir("octomap");
  const std::string path = (dir / "missing" / "room.bt").string();
  auto stats = ExportOctomap(volume, path);
  ASSERT_FALSE(stats.ok());
  EXPECT_NE(stats.status().message().find("missing"), std::string::npos)
      << stats.status().message();
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace voxplan
