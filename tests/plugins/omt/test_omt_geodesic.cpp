#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plugins/omt/algorithms/geodesic.h"
#include "plugins/omt/algorithms/raster_ops.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

constexpr double kRobotRadius = 0.18;

TEST(OmtGeodesic, OpenFloorDistanceIsOctileAndPathsKeepClearance) {
  OccupancyRaster r = testing::MakeRaster(6.0, 4.0, 0.05, Cell::kFree);
  testing::FrameRect(&r, 0.0, 0.0, 6.0, 4.0);
  const ClearanceRaster c = ComputeClearance(r);
  const GeodesicGrid grid = BuildGeodesicGrid(c, 0.2, kRobotRadius);
  const Anchor a = AnchorPoint(grid, c, {1.0, 1.0}, kRobotRadius);
  const Anchor b = AnchorPoint(grid, c, {5.0, 3.0}, kRobotRadius);
  ASSERT_GE(a.node, 0);
  ASSERT_GE(b.node, 0);
  ShortestPaths sp;
  Dijkstra(grid, a.node, &sp);
  // 8-connected grid: octile distance between the two nodes.
  const Eigen::Vector2d d = (grid.Position(b.node) - grid.Position(a.node)).cwiseAbs();
  const double octile = d.maxCoeff() - d.minCoeff() + std::sqrt(2.0) * d.minCoeff();
  EXPECT_NEAR(sp.dist_m[static_cast<std::size_t>(b.node)], octile, 1e-4);
  const std::vector<Eigen::Vector2d> path = ExtractPath(grid, sp, a, b);
  ASSERT_GE(path.size(), 2u);
  EXPECT_TRUE(path.front().isApprox(a.point_m));
  EXPECT_TRUE(path.back().isApprox(b.point_m));
  for (std::size_t i = 1; i < path.size(); ++i)
    EXPECT_TRUE(SegmentClear(c, path[i - 1], path[i], kRobotRadius));
}

TEST(OmtGeodesic, WallsForceDetoursAndClosedDoorsDisconnect) {
  OccupancyRaster r = testing::MakeRaster(6.0, 4.0, 0.05, Cell::kFree);
  testing::FrameRect(&r, 0.0, 0.0, 6.0, 4.0);
  testing::FillRect(&r, 3.0, 0.0, 3.1, 3.0, Cell::kOccupied);  // wall, 1 m gap at the top
  ClearanceRaster c = ComputeClearance(r);
  GeodesicGrid grid = BuildGeodesicGrid(c, 0.2, kRobotRadius);
  const Anchor a = AnchorPoint(grid, c, {1.5, 0.6}, kRobotRadius);
  const Anchor b = AnchorPoint(grid, c, {4.5, 0.6}, kRobotRadius);
  ShortestPaths sp;
  Dijkstra(grid, a.node, &sp);
  EXPECT_GT(sp.dist_m[static_cast<std::size_t>(b.node)], 5.0);  // up and over, not 3 m
  testing::FillRect(&r, 3.0, 3.0, 3.1, 4.0, Cell::kOccupied);   // close the gap
  c = ComputeClearance(r);
  grid = BuildGeodesicGrid(c, 0.2, kRobotRadius);
  Dijkstra(grid, a.node, &sp);
  EXPECT_FALSE(std::isfinite(sp.dist_m[static_cast<std::size_t>(b.node)]));
  EXPECT_FALSE(ReachableNodes(grid, {a.node})[static_cast<std::size_t>(b.node)]);
}

TEST(OmtGeodesic, EarlyExitKeepsTargetDistancesAndPathsExact) {
  const OccupancyRaster r = testing::MakeApartment(10.0, 6.0, 0.05, 10.0);
  const ClearanceRaster c = ComputeClearance(r);
  const GeodesicGrid grid = BuildGeodesicGrid(c, 0.2, kRobotRadius);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> node(0, grid.NumNodes() - 1);
  std::vector<int> targets;
  while (targets.size() < 6) {
    const int n = node(rng);
    if (grid.traversable[static_cast<std::size_t>(n)]) targets.push_back(n);
  }
  std::vector<std::uint8_t> wanted(static_cast<std::size_t>(grid.NumNodes()), 0);
  for (int t : targets) wanted[static_cast<std::size_t>(t)] = 1;
  int num_wanted = 0;
  for (std::uint8_t w : wanted) num_wanted += w;
  ShortestPaths full, early;
  Dijkstra(grid, targets[0], &full);
  Dijkstra(grid, targets[0], &early, &wanted, num_wanted);
  for (int t : targets) {
    EXPECT_EQ(full.dist_m[static_cast<std::size_t>(t)], early.dist_m[static_cast<std::size_t>(t)]);
    Anchor from, to;
    from.node = targets[0];
    from.point_m = grid.Position(targets[0]);
    to.node = t;
    to.point_m = grid.Position(t);
    EXPECT_EQ(ExtractPath(grid, full, from, to), ExtractPath(grid, early, from, to));
  }
}

}  // namespace
}  // namespace voxplan::omt
