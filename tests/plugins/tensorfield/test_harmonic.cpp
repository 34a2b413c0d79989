// The harmonic-function baseline (plugins/tensorfield/harmonic.h) on a corridor with a frontier
// at one end: the potential's bounds, no local minimum in free space, and a descent that runs
// downhill to the frontier and stops where it is refused.
#include <gtest/gtest.h>

#include "plugins/tensorfield/frames.h"
#include "plugins/tensorfield/harmonic.h"
#include "plugins/tensorfield/potential_info.h"

namespace voxplan::tensorfield {
namespace {

// 3 m x 0.5 m at 5 cm: walls along y = 0 and the top row, a closed west end, the east column
// frontier; free inside.
struct Corridor {
  omt::RasterGeometry g;
  std::vector<std::uint8_t> codes;
  Corridor() {
    g.width = 60;
    g.height = 10;
    g.resolution_m = 0.05;
    codes.assign(static_cast<std::size_t>(g.NumCells()), kFloorFree);
    for (int x = 0; x < g.width; ++x) {
      codes[static_cast<std::size_t>(g.Index(x, 0))] = kFloorObstacle;
      codes[static_cast<std::size_t>(g.Index(x, g.height - 1))] = kFloorObstacle;
    }
    for (int y = 1; y + 1 < g.height; ++y) {
      codes[static_cast<std::size_t>(g.Index(0, y))] = kFloorObstacle;
      codes[static_cast<std::size_t>(g.Index(g.width - 1, y))] = kFloorFrontier;
    }
  }
};

TEST(Harmonic, PotentialIsBoundedWithoutLocalMinimaAndDescendsToTheFrontier) {
  const Corridor c;
  const std::vector<double> phi = SolveHarmonic(c.g, c.codes);
  for (int i = 0; i < c.g.NumCells(); ++i) {
    const std::uint8_t code = c.codes[static_cast<std::size_t>(i)];
    const double v = phi[static_cast<std::size_t>(i)];
    if (code == kFloorFrontier) {
      EXPECT_EQ(v, 0.0);
    }
    if (code == kFloorObstacle) {
      EXPECT_EQ(v, 1.0);
    }
    if (code != kFloorFree) continue;
    EXPECT_GT(v, 0.0);
    EXPECT_LT(v, 1.0);
    // Every free cell has a lower 4-neighbour: a descent never gets stuck in free space.
    const int x = c.g.X(i), y = c.g.Y(i);
    double lowest = 1.0;
    for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
      lowest = std::min(lowest, phi[static_cast<std::size_t>(c.g.Index(x + dx, y + dy))]);
    EXPECT_LT(lowest, v) << x << "," << y;
  }
  // From the closed end along the corridor's axis: eastwards, downhill, to the frontier.
  const Eigen::Vector2d start(0.2, 0.25);
  const std::vector<Eigen::Vector2d> path =
      DescendPotential(c.g, phi, c.codes, start, 5.0, [](const Eigen::Vector2d&) { return true; });
  ASSERT_GT(path.size(), 10u);
  EXPECT_NEAR(path.back().x(), 2.95, 0.06);  // in the frontier column
  EXPECT_NEAR(path.back().y(), 0.25, 0.05);  // on the axis (the corridor is symmetric)
  for (std::size_t i = 1; i < path.size(); ++i) EXPECT_GT(path[i].x(), path[i - 1].x());
  // Refused beyond x = 1 m: stops there.
  const std::vector<Eigen::Vector2d> stopped = DescendPotential(
      c.g, phi, c.codes, start, 5.0, [](const Eigen::Vector2d& p) { return p.x() < 1.0; });
  EXPECT_LT(stopped.back().x(), 1.0);
  EXPECT_GT(stopped.back().x(), 0.9);
}

TEST(Harmonic, NoFrontierNoWayDown) {
  Corridor c;
  for (std::uint8_t& code : c.codes)
    if (code == kFloorFrontier) code = kFloorObstacle;
  const std::vector<double> phi = SolveHarmonic(c.g, c.codes);
  const std::vector<Eigen::Vector2d> path = DescendPotential(
      c.g, phi, c.codes, {1.0, 0.25}, 2.0, [](const Eigen::Vector2d&) { return true; });
  EXPECT_EQ(path.size(), 1u);  // φ is 1 everywhere: flat
}

// The potential information field (potential_info.h): unknown space attracts, walls repel.
TEST(PotentialInfo, AttractsTowardsTheUnknownEndAndRepelsFromTheWalls) {
  Corridor c;
  // The east end unknown instead of frontier (the potential counts both as information).
  for (std::uint8_t& code : c.codes)
    if (code == kFloorFrontier) code = kFloorUnknown;
  std::vector<float> clearance(c.codes.size());
  for (int i = 0; i < c.g.NumCells(); ++i) {
    const double y = c.g.Center(i).y();
    clearance[static_cast<std::size_t>(i)] =
        static_cast<float>(std::min(y - 0.025, c.g.height * c.g.resolution_m - 0.025 - y));
  }
  PotentialInfoParams pp;
  pp.sigma_m = 1.0;
  pp.repulse_within_m = 0.1;
  const std::vector<double> phi = SolvePotentialInfo(c.g, c.codes, clearance, pp);
  ASSERT_EQ(phi.size(), c.codes.size());
  // Lower (more attractive) towards the unknown east end along the axis.
  const auto at = [&](double x, double y) {
    return phi[static_cast<std::size_t>(c.g.IndexOf({x, y}))];
  };
  EXPECT_LT(at(2.5, 0.25), at(1.5, 0.25));
  EXPECT_LT(at(1.5, 0.25), at(0.5, 0.25));
  // Repelled from the wall: at the same x, the axis is lower than next to the wall.
  EXPECT_LT(at(1.5, 0.25), at(1.5, 0.075));
  // The descent runs east and keeps off the walls.
  const std::vector<Eigen::Vector2d> path = DescendPotential(
      c.g, phi, c.codes, {0.3, 0.25}, 2.0, [](const Eigen::Vector2d&) { return true; });
  ASSERT_GT(path.size(), 10u);
  EXPECT_GT(path.back().x(), 1.5);
  for (const Eigen::Vector2d& p : path) EXPECT_NEAR(p.y(), 0.25, 0.06);
  // Nothing unknown: no attraction, only the walls' repulsion (zero on the axis band).
  for (std::uint8_t& code : c.codes)
    if (code == kFloorUnknown) code = kFloorObstacle;
  const std::vector<double> flat = SolvePotentialInfo(c.g, c.codes, clearance, pp);
  EXPECT_EQ(flat[static_cast<std::size_t>(c.g.IndexOf({1.5, 0.25}))], 0.0);
}

}  // namespace
}  // namespace voxplan::tensorfield
