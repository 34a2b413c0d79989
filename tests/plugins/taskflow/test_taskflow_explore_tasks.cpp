#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <queue>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/taskflow/algorithms/explore_tasks.h"

namespace voxplan::taskflow {
namespace {

constexpr double kSpacing = 0.5;       // brief: FPS at 0.5 m
constexpr double kCellTol = 1e-6;      // metres, for distances between cell centres
constexpr double kAngleTol = 1e-6;     // radians
constexpr double kFov = omt::kPi / 2;  // explorer: 90°
constexpr double kRange = 5.0;         // explorer: 5 m
constexpr std::uint8_t kU = 0, kF = 1, kO = 3;

// A room of the floor raster plus what the host would hand the plugin.
struct Scene {
  omt::RasterGeometry geometry;
  std::vector<std::uint8_t> cells;
  std::vector<float> clearance;
  std::vector<Eigen::Vector2d> robots;
  std::vector<std::vector<float>> geodesic;

  std::uint8_t& At(int x, int y) { return cells[static_cast<std::size_t>(geometry.Index(x, y))]; }

  // Frontier labels (free and 8-adjacent to unknown), clearance and 8-connected geodesic
  // fields over free cells, as the host computes them.
  void Finish() {
    const omt::RasterGeometry& g = geometry;
    std::vector<std::uint8_t> labelled = cells;
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x) {
        if (At(x, y) != kF) continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (g.InBounds(x + dx, y + dy) && At(x + dx, y + dy) == kU)
              labelled[static_cast<std::size_t>(g.Index(x, y))] = 2;
      }
    cells = labelled;
    omt::OccupancyRaster occ;
    occ.geometry = g;
    for (std::uint8_t c : cells)
      occ.cells.push_back(c == kO   ? omt::Cell::kOccupied
                          : c == kU ? omt::Cell::kUnknown
                                    : omt::Cell::kFree);
    clearance = omt::ComputeClearance(occ, /*unknown_is_obstacle=*/false).clearance_m;
    geodesic.clear();
    for (const Eigen::Vector2d& p : robots) geodesic.push_back(Dijkstra(g.IndexOf(p)));
  }

  std::vector<float> Dijkstra(int source) const {
    const omt::RasterGeometry& g = geometry;
    std::vector<double> d(cells.size(), std::numeric_limits<double>::infinity());
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    d[static_cast<std::size_t>(source)] = 0.0;
    open.push({0.0, source});
    while (!open.empty()) {
      const auto [dist, i] = open.top();
      open.pop();
      if (dist > d[static_cast<std::size_t>(i)]) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = g.X(i) + dx, y = g.Y(i) + dy;
          if ((dx == 0 && dy == 0) || !g.InBounds(x, y)) continue;
          const int j = g.Index(x, y);
          const std::uint8_t c = cells[static_cast<std::size_t>(j)];
          if (c != kF && c != 2) continue;
          const double nd = dist + g.resolution_m * std::hypot(dx, dy);
          if (nd < d[static_cast<std::size_t>(j)]) {
            d[static_cast<std::size_t>(j)] = nd;
            open.push({nd, j});
          }
        }
    }
    return std::vector<float>(d.begin(), d.end());
  }

  ExploreInput Input() const {
    ExploreInput in;
    in.floor.geometry = geometry;
    in.floor.cells = cells;
    in.floor.clearance_m = clearance;
    in.robots_xy_m = robots;
    for (const auto& f : geodesic) in.geodesic_m.emplace_back(f);
    in.camera.horizontal_fov_rad = kFov;
    in.camera.max_range_m = kRange;
    return in;
  }
};

// 8 m × 6 m at 10 cm, walls on the border; x < known_m is free, beyond it unknown, so the
// frontier is the column of free cells next to x = known_m.
Scene Room(double known_m, std::vector<Eigen::Vector2d> robots) {
  Scene s;
  s.geometry.width = 80;
  s.geometry.height = 60;
  s.geometry.resolution_m = 0.1;
  s.cells.assign(static_cast<std::size_t>(s.geometry.NumCells()), kU);
  const int known = static_cast<int>(std::lround(known_m / s.geometry.resolution_m));
  for (int y = 0; y < s.geometry.height; ++y)
    for (int x = 0; x < s.geometry.width; ++x) {
      const bool wall = x == 0 || y == 0 || x == s.geometry.width - 1 || y == s.geometry.height - 1;
      s.At(x, y) = wall ? kO : x < known ? kF : kU;
    }
  s.robots = std::move(robots);
  return s;
}

std::vector<int> FrontierCells(const Scene& s) {
  std::vector<int> f;
  for (int i = 0; i < s.geometry.NumCells(); ++i)
    if (s.cells[static_cast<std::size_t>(i)] == 2) f.push_back(i);
  return f;
}

TEST(TaskflowExploreTasks, FarthestPointSamplesAreSpacedAndCoverTheFrontier) {
  Scene s = Room(5.0, {{2.0, 3.0}});
  // An L-shaped frontier: also unknown above y = 4.5 m.
  for (int y = 45; y < 59; ++y)
    for (int x = 1; x < 50; ++x) s.At(x, y) = kU;
  s.Finish();
  const ExploreInput in = s.Input();
  const std::vector<int> samples = SampleFrontiers(in.floor, kSpacing);
  const std::vector<int> frontier = FrontierCells(s);
  ASSERT_GT(frontier.size(), 50u);
  ASSERT_GT(samples.size(), 10u);
  for (std::size_t a = 0; a < samples.size(); ++a) {
    EXPECT_EQ(s.cells[static_cast<std::size_t>(samples[a])], 2);
    for (std::size_t b = a + 1; b < samples.size(); ++b)
      EXPECT_GE((s.geometry.Center(samples[a]) - s.geometry.Center(samples[b])).norm(),
                kSpacing - kCellTol);
  }
  for (int f : frontier) {
    double nearest = std::numeric_limits<double>::infinity();
    for (int smp : samples)
      nearest = std::min(nearest, (s.geometry.Center(f) - s.geometry.Center(smp)).norm());
    EXPECT_LT(nearest, kSpacing + kCellTol);
  }
  EXPECT_EQ(SampleFrontiers(in.floor, kSpacing), samples);  // deterministic
}

TEST(TaskflowExploreTasks, LineOfSightStopsAtObstaclesAndUnknownOnly) {
  Scene s = Room(8.0, {{1.0, 1.0}});
  for (int y = 1; y < 40; ++y) s.At(40, y) = kO;  // an inner wall from the bottom
  s.At(20, 50) = kU;
  s.Finish();
  const ExploreInput in = s.Input();
  const auto& g = s.geometry;
  EXPECT_FALSE(LineOfSight(in.floor, g.Index(30, 20), g.Index(50, 20)));  // through the wall
  EXPECT_TRUE(LineOfSight(in.floor, g.Index(30, 45), g.Index(50, 45)));   // above it
  EXPECT_FALSE(LineOfSight(in.floor, g.Index(10, 50), g.Index(30, 50)));  // through unknown
  // The end cells themselves are not tested: a wall cell can be looked at.
  EXPECT_TRUE(LineOfSight(in.floor, g.Index(30, 20), g.Index(40, 20)));
}

TEST(TaskflowExploreTasks, CandidatesSeeTheirFrontiersFromOneToFourMetres) {
  Scene s = Room(5.0, {{1.5, 3.0}});
  for (int y = 1; y < 35; ++y) s.At(30, y) = kO;  // hides part of the frontier from the left
  s.Finish();
  const ExploreInput in = s.Input();
  ExploreParams params;
  const std::vector<int> samples = SampleFrontiers(in.floor, params.frontier_spacing_m);
  const std::vector<float> d_f = NonFreeDistance(in.floor);
  const std::vector<ViewCandidate> candidates = ViewCandidates(in, samples, d_f, params);
  ASSERT_GT(candidates.size(), 20u);
  for (const ViewCandidate& c : candidates) {
    const std::uint8_t cell = s.cells[static_cast<std::size_t>(c.cell)];
    EXPECT_TRUE(cell == kF || cell == 2) << c.cell;
    EXPECT_GE(s.clearance[static_cast<std::size_t>(c.cell)], params.min_clearance_m);
    EXPECT_TRUE(std::isfinite(c.d_robot_m));
    ASSERT_FALSE(c.frontiers.empty());
    for (int f : c.frontiers) {
      const double r = (s.geometry.Center(c.cell) - s.geometry.Center(samples[f])).norm();
      EXPECT_GE(r, params.min_view_distance_m - kCellTol);
      EXPECT_LE(r, params.max_view_distance_m + kCellTol);
      EXPECT_TRUE(LineOfSight(in.floor, c.cell, samples[f]));
    }
  }
  // Behind the inner wall (x < 3 m, y < 3.4 m) nothing sees the low frontier samples.
  for (const ViewCandidate& c : candidates) {
    const Eigen::Vector2d p = s.geometry.Center(c.cell);
    if (p.x() > 2.9 || p.y() > 1.0) continue;
    for (int f : c.frontiers) EXPECT_GT(s.geometry.Center(samples[f]).y(), 3.4);
  }
}

TEST(TaskflowExploreTasks, ScorePrefersNearRobotAndFarFromWallsPaperSignFlips) {
  Scene s = Room(5.0, {{2.0, 3.0}});
  s.Finish();
  const ExploreInput in = s.Input();
  ExploreParams params;
  const std::vector<int> samples = SampleFrontiers(in.floor, params.frontier_spacing_m);
  const std::vector<float> d_f = NonFreeDistance(in.floor);
  const std::vector<ViewCandidate> ours = ViewCandidates(in, samples, d_f, params);
  params.paper_sign = true;
  const std::vector<ViewCandidate> paper = ViewCandidates(in, samples, d_f, params);
  ASSERT_EQ(ours.size(), paper.size());
  // Near the robot in the open vs. a corner far from it (cells on the 0.2 m lattice).
  const auto find = [&](double x, double y) {
    const int cell = s.geometry.IndexOf({x, y});
    for (std::size_t i = 0; i < ours.size(); ++i)
      if (ours[i].cell == cell) return static_cast<int>(i);
    return -1;
  };
  const int open = find(2.45, 3.05), corner = find(4.05, 0.45);
  ASSERT_GE(open, 0);
  ASSERT_GE(corner, 0);
  EXPECT_GT(ours[open].d_free_m, ours[corner].d_free_m);
  EXPECT_LT(ours[open].d_robot_m, ours[corner].d_robot_m);
  EXPECT_GT(ours[open].score, ours[corner].score);
  EXPECT_LT(paper[open].score, paper[corner].score);
  for (std::size_t i = 0; i < ours.size(); ++i)
    EXPECT_NEAR(paper[i].score, -ours[i].score, kCellTol);
}

TEST(TaskflowExploreTasks, GreedyCoverCoversARoomWithFewViewsInFovAndRange) {
  Scene s = Room(5.0, {{2.0, 3.0}});
  s.Finish();
  ExploreParams params;
  params.max_views = 10;
  const ExploreResult result = GenerateExplorationTasks(s.Input(), params);
  ASSERT_TRUE(result.status.ok()) << result.status.message;
  ASSERT_FALSE(result.frontier_samples.empty());
  EXPECT_EQ(result.uncovered, 0);
  EXPECT_LE(result.views.size(), 3u);  // 5.8 m of frontier, a 90° camera 1-4 m from it
  std::vector<int> times(result.frontier_samples.size(), 0);
  for (const ExploreView& v : result.views) {
    ASSERT_FALSE(v.covered.empty());
    for (int f : v.covered) {
      ++times[static_cast<std::size_t>(f)];
      const Eigen::Vector2d d = s.geometry.Center(result.frontier_samples[f]) - v.xy_m;
      EXPECT_LE(d.norm(), kRange + kCellTol);
      EXPECT_LE(std::abs(omt::WrapAngle(std::atan2(d.y(), d.x()) - v.theta_rad)),
                kFov / 2 + kAngleTol);
      EXPECT_TRUE(LineOfSight(s.Input().floor, v.cell, result.frontier_samples[f]));
    }
  }
  for (int t : times) EXPECT_EQ(t, 1);  // each sample is listed by the view that covered it
  // Views face the frontier (+x).
  for (const ExploreView& v : result.views) EXPECT_LT(std::abs(v.theta_rad), omt::kPi / 2);
}

TEST(TaskflowExploreTasks, GreedyCoverRespectsTheViewCount) {
  Scene s = Room(5.0, {{2.0, 3.0}});
  s.Finish();
  ExploreParams params;
  params.max_views = 1;
  EXPECT_EQ(GenerateExplorationTasks(s.Input(), params).views.size(), 1u);
  // Default: views_per_robot × R = 2 for one robot, even with a frontier that needs more.
  Scene big = Room(5.0, {{2.0, 3.0}});
  for (int y = 1; y < 59; ++y)
    for (int x = 1; x < 79; ++x)
      if ((x + y) % 9 == 0 && x > 10 && x < 48) big.At(x, y) = kU;  // scattered holes
  big.Finish();
  const ExploreResult r = GenerateExplorationTasks(big.Input(), ExploreParams{});
  EXPECT_EQ(r.views.size(), 2u);
  EXPECT_GT(r.uncovered, 0);
}

TEST(TaskflowExploreTasks, RejectsMismatchedInputAndNoFrontierGivesNoViews) {
  Scene s = Room(8.0, {{2.0, 3.0}});
  s.Finish();
  ExploreInput in = s.Input();
  const ExploreResult none = GenerateExplorationTasks(in, ExploreParams{});
  EXPECT_TRUE(none.status.ok());
  EXPECT_TRUE(none.views.empty());
  in.geodesic_m.pop_back();
  EXPECT_FALSE(GenerateExplorationTasks(in, ExploreParams{}).status.ok());
}

}  // namespace
}  // namespace voxplan::taskflow
