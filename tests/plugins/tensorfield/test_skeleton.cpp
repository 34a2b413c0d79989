// The topological skeleton (X L312-314) on synthetic floor plans, docking, and routing (X L197-229)
// on hand-built graphs against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/tensorfield/algorithms/skeleton.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"
#include "tests/plugins/tensorfield/tensor_scenes.h"

namespace voxplan::tensorfield {
namespace {

using omt::Cell;
using omt::kPi;
using test::FillRect;
using test::MakeRaster;
using test::RayAngleBetween;

constexpr double kDeg = kPi / 180.0;
// Separatrices leave their point along the traced direction and run along a corridor's axis; the
// asymmetric farthest-point samples move the field's symmetry line by up to two cells.
constexpr double kAxisTolerance_m = 0.15;
constexpr double kBoundaryTolerance_m = 0.1;  // a leaf at the raster's edge: within two cells

int CountKind(const Skeleton& s, SkeletonNodeKind kind) {
  return static_cast<int>(std::count_if(s.nodes.begin(), s.nodes.end(),
                                        [&](const SkeletonNode& n) { return n.kind == kind; }));
}

double MaxDistanceFromAxis(const SkeletonEdge& e, bool vertical, double axis, double from_arc,
                           double to_arc) {
  double worst = 0.0, s = 0.0;
  for (std::size_t i = 0; i < e.polyline.size(); ++i) {
    if (i > 0) s += (e.polyline[i] - e.polyline[i - 1]).norm();
    if (s < from_arc || s > to_arc) continue;
    const double d = vertical ? e.polyline[i].x() - axis : e.polyline[i].y() - axis;
    worst = std::max(worst, std::abs(d));
  }
  return worst;
}

TEST(Skeleton, TJunctionHasATrisectorWithStemAndBarEdges) {
  omt::OccupancyRaster r = MakeRaster(8.0, 5.0, Cell::kOccupied);
  FillRect(&r, 0.0, 3.0, 8.0, 4.0, Cell::kFree);
  FillRect(&r, 3.5, 0.0, 4.5, 3.0, Cell::kFree);
  const TensorRaster f = KeyFrameField(r, {});
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(f);
  ASSERT_EQ(points.size(), 1u);
  ASSERT_EQ(points[0].type, DegenerateType::kTrisector);
  const Skeleton s = ExtractSkeleton(f, points, {});
  EXPECT_EQ(s.traced, 3);
  ASSERT_EQ(s.edges.size(), 3u);
  EXPECT_EQ(CountKind(s, SkeletonNodeKind::kTrisector), 1);
  EXPECT_EQ(CountKind(s, SkeletonNodeKind::kLeaf), 3);
  int stem = 0, left = 0, right = 0;
  for (const SkeletonEdge& e : s.edges) {
    EXPECT_EQ(e.from, 0);
    const SkeletonNode& end = s.nodes[static_cast<std::size_t>(e.to)];
    ASSERT_EQ(end.kind, SkeletonNodeKind::kLeaf);
    EXPECT_EQ(end.end, AdvectionStop::kLeftDomain);  // the raster's open edges
    EXPECT_NEAR(
        e.length_m,
        [&] {
          double l = 0.0;
          for (std::size_t i = 1; i < e.polyline.size(); ++i)
            l += (e.polyline[i] - e.polyline[i - 1]).norm();
          return l;
        }(),
        1e-9);
    const Eigen::Vector2d q = end.position_m;
    if (q.y() < kBoundaryTolerance_m) {  // down the stem to y = 0
      ++stem;
      EXPECT_NEAR(q.x(), 4.0, kAxisTolerance_m);
      EXPECT_LE(RayAngleBetween(e.from_angle_rad, -0.5 * kPi), 10.0 * kDeg);
      // Away from the junction it runs on the stem's axis.
      EXPECT_LE(MaxDistanceFromAxis(e, true, 4.0, 1.0, 1e9), kAxisTolerance_m);
      EXPECT_GT(e.length_m, 3.0);
    } else if (q.x() < kBoundaryTolerance_m) {
      ++left;
      EXPECT_NEAR(q.y(), 3.5, kAxisTolerance_m);
      EXPECT_LE(MaxDistanceFromAxis(e, false, 3.5, 1.0, 1e9), kAxisTolerance_m);
    } else if (q.x() > 8.0 - kBoundaryTolerance_m) {
      ++right;
      EXPECT_NEAR(q.y(), 3.5, kAxisTolerance_m);
      EXPECT_LE(MaxDistanceFromAxis(e, false, 3.5, 1.0, 1e9), kAxisTolerance_m);
    }
    EXPECT_EQ(e.polyline.front(), points[0].position_m);
    EXPECT_EQ(e.polyline.back(), q);
  }
  EXPECT_EQ(stem, 1);
  EXPECT_EQ(left, 1);
  EXPECT_EQ(right, 1);
}

TEST(Skeleton, DeadEndCorridorHasAWedgeWithOneEdgeAlongTheCorridor) {
  omt::OccupancyRaster r = MakeRaster(5.0, 3.0, Cell::kOccupied);
  FillRect(&r, 0.5, 1.0, 5.0, 2.0, Cell::kFree);
  const TensorRaster f = KeyFrameField(r, {});
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(f);
  ASSERT_EQ(points.size(), 1u);
  ASSERT_EQ(points[0].type, DegenerateType::kWedge);
  const Skeleton s = ExtractSkeleton(f, points, {});
  ASSERT_EQ(s.edges.size(), points[0].separatrix_angles_rad.size());
  ASSERT_EQ(s.edges.size(), 1u);
  const SkeletonEdge& e = s.edges[0];
  EXPECT_EQ(s.nodes[static_cast<std::size_t>(e.from)].kind, SkeletonNodeKind::kWedge);
  const SkeletonNode& end = s.nodes[static_cast<std::size_t>(e.to)];
  EXPECT_EQ(end.kind, SkeletonNodeKind::kLeaf);
  EXPECT_GT(end.position_m.x(), 5.0 - kBoundaryTolerance_m);  // the open end
  EXPECT_LE(MaxDistanceFromAxis(e, false, 1.5, 0.0, 1e9), kAxisTolerance_m);
  EXPECT_NEAR(e.length_m, 5.0 - points[0].position_m.x(), 0.1);
}

TEST(Skeleton, SeparatricesJoiningTheSameNodesAreMerged) {
  // The T junction with its stem closed at y = 0.5: the trisector's stem separatrix runs into the
  // wedge at the stem's dead end, and the wedge's separatrix back into the trisector; one edge.
  omt::OccupancyRaster r = MakeRaster(8.0, 5.0, Cell::kOccupied);
  FillRect(&r, 0.0, 3.0, 8.0, 4.0, Cell::kFree);
  FillRect(&r, 3.5, 0.5, 4.5, 3.0, Cell::kFree);
  const TensorRaster f = KeyFrameField(r, {});
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(f);
  ASSERT_EQ(points.size(), 2u);
  const int wedge = points[0].type == DegenerateType::kWedge ? 0 : 1;
  const int trisector = 1 - wedge;
  ASSERT_EQ(points[static_cast<std::size_t>(trisector)].type, DegenerateType::kTrisector);
  const Skeleton s = ExtractSkeleton(f, points, {});
  EXPECT_EQ(s.traced, 4);
  ASSERT_EQ(s.edges.size(), 3u);
  int joining = 0;
  for (const SkeletonEdge& e : s.edges) {
    const bool joins =
        (e.from == wedge && e.to == trisector) || (e.from == trisector && e.to == wedge);
    if (!joins) continue;
    ++joining;
    EXPECT_EQ(e.merged, 1);
    EXPECT_LE(MaxDistanceFromAxis(e, true, 4.0, 0.0, 1e9), kAxisTolerance_m);
    EXPECT_NEAR(e.length_m, (points[0].position_m - points[1].position_m).norm(), 0.1);
  }
  EXPECT_EQ(joining, 1);
  EXPECT_EQ(CountKind(s, SkeletonNodeKind::kLeaf), 2);
  // Without merging the two would both be there.
  SkeletonParams no_merge;
  no_merge.merge_distance_m = -1.0;
  EXPECT_EQ(ExtractSkeleton(f, points, no_merge).edges.size(), 4u);
  // Deterministic.
  const Skeleton again = ExtractSkeleton(f, points, {});
  ASSERT_EQ(again.edges.size(), s.edges.size());
  for (std::size_t i = 0; i < s.edges.size(); ++i)
    EXPECT_EQ(again.edges[i].polyline, s.edges[i].polyline);
}

TEST(Docking, PassingATrisectorWithinTheRadiusDocks) {
  std::vector<DegeneratePoint> points(2);
  points[0].type = DegenerateType::kWedge;
  points[0].position_m = {1.0, 0.1};
  points[1].type = DegenerateType::kTrisector;
  points[1].position_m = {1.0, 0.3};
  const auto pass = [](double y, double x_end) {
    std::vector<Eigen::Vector2d> path;
    for (double x = 0.0; x <= x_end + 1e-9; x += 0.1) path.emplace_back(x, y);
    return path;
  };
  const std::optional<Docking> docked = DetectDocking(pass(0.0, 2.0), points);
  ASSERT_TRUE(docked.has_value());
  EXPECT_EQ(docked->point, 1);  // the wedge is nearer but never docks
  EXPECT_EQ(docked->closest_sample, 10);
  EXPECT_NEAR(docked->min_distance_m, 0.3, 1e-9);
  EXPECT_FALSE(DetectDocking(pass(-0.3, 2.0), points).has_value());  // 0.6 m: too far
  EXPECT_FALSE(DetectDocking(pass(0.0, 1.0), points).has_value());   // not leaving yet
  std::vector<Eigen::Vector2d> away = pass(0.0, 2.0);
  away.erase(away.begin(), away.begin() + 10);  // starts at the closest point: only leaving
  EXPECT_FALSE(DetectDocking(away, points).has_value());
}

// ---------------------------------------------------------------------------------------------
// Routing.

Skeleton HandGraph(int nodes, const std::vector<std::pair<int, int>>& edges) {
  Skeleton s;
  for (int i = 0; i < nodes; ++i) {
    SkeletonNode n;
    n.kind = SkeletonNodeKind::kTrisector;
    n.position_m = {static_cast<double>(i), static_cast<double>(i % 2)};
    s.nodes.push_back(n);
  }
  for (const auto& [a, b] : edges) {
    SkeletonEdge e;
    e.from = a;
    e.to = b;
    e.polyline = {s.nodes[static_cast<std::size_t>(a)].position_m,
                  s.nodes[static_cast<std::size_t>(b)].position_m};
    e.length_m = (e.polyline[1] - e.polyline[0]).norm();
    s.edges.push_back(e);
  }
  return s;
}

int Find(std::vector<int>* parent, int x) {
  while ((*parent)[static_cast<std::size_t>(x)] != x) x = (*parent)[static_cast<std::size_t>(x)];
  return x;
}

// Cheapest spanning tree over all subsets of node_count - 1 edges (the graph is connected).
double BruteForceMst(const Skeleton& s, const std::vector<double>& cost, std::vector<int>* best) {
  const int m = static_cast<int>(s.edges.size());
  const int n = static_cast<int>(s.nodes.size());
  double best_cost = std::numeric_limits<double>::infinity();
  for (int mask = 0; mask < (1 << m); ++mask) {
    if (__builtin_popcount(static_cast<unsigned>(mask)) != n - 1) continue;
    std::vector<int> parent(static_cast<std::size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    bool tree = true;
    double c = 0.0;
    std::vector<int> chosen;
    for (int e = 0; e < m && tree; ++e) {
      if ((mask & (1 << e)) == 0) continue;
      const int a = Find(&parent, s.edges[static_cast<std::size_t>(e)].from);
      const int b = Find(&parent, s.edges[static_cast<std::size_t>(e)].to);
      if (a == b) tree = false;
      parent[static_cast<std::size_t>(a)] = b;
      c += cost[static_cast<std::size_t>(e)];
      chosen.push_back(e);
    }
    if (tree && c < best_cost) {
      best_cost = c;
      *best = chosen;
    }
  }
  return best_cost;
}

TEST(Routing, PrimEqualsBruteForceMinimumSpanningTree) {
  // Two connected graphs of 7 edges (one with a parallel edge and a self-loop, which no tree
  // uses), random distinct costs from gains, several seeds and roots.
  const std::vector<std::vector<std::pair<int, int>>> graphs = {
      {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 0}, {0, 2}, {1, 3}},
      {{0, 1}, {0, 1}, {1, 2}, {2, 2}, {2, 3}, {3, 0}, {1, 4}},
  };
  std::uint32_t state = 12345;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / static_cast<double>(1u << 24);
  };
  int checked = 0;
  for (const auto& edges : graphs) {
    const Skeleton s = HandGraph(5, edges);
    for (int seed = 0; seed < 20; ++seed) {
      std::vector<double> cost;
      for (std::size_t e = 0; e < edges.size(); ++e) cost.push_back(EdgeCost(0.05 + next()));
      std::vector<int> expected;
      const double best = BruteForceMst(s, cost, &expected);
      for (int root = 0; root < 5; ++root) {
        const SpanningTree tree = MinimumSpanningTree(s, cost, root);
        EXPECT_EQ(tree.root, root);
        ASSERT_EQ(tree.edges.size(), 4u);
        EXPECT_EQ(tree.order.size(), 5u);
        EXPECT_NEAR(tree.cost, best, 1e-12);
        std::vector<int> got = tree.edges;
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected);  // distinct costs: the minimum tree is unique
        EXPECT_EQ(tree.parent_edge[static_cast<std::size_t>(root)], -1);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 200);
}

TEST(Routing, UnusableEdgesAndOtherComponentsAreLeftOut) {
  const Skeleton s = HandGraph(5, {{0, 1}, {1, 2}, {0, 2}, {3, 4}});
  const std::vector<double> cost = {1.0, 1.0, 0.5, 1.0};
  const std::vector<std::uint8_t> usable = {1, 1, 0, 1};
  const SpanningTree tree = MinimumSpanningTree(s, cost, 0, usable);
  EXPECT_EQ(tree.edges, (std::vector<int>{0, 1}));
  EXPECT_EQ(tree.parent_edge[3], -1);
  EXPECT_EQ(tree.parent_edge[4], -1);
  EXPECT_EQ(MinimumSpanningTree(s, cost, 0).edges, (std::vector<int>{2, 0}));
  EXPECT_EQ(MinimumSpanningTree(s, cost, -1).root, -1);
}

TEST(Routing, BranchChoiceFollowsTheGainThroughTheTree) {
  // Root 0 (a trisector) with three branches: 0-1 (no gain); 0-2 (little gain) leading to 2-3
  // (much gain); 0-4 (moderate gain). The chosen branch is 0-2: its subtree holds the gain.
  Skeleton s = HandGraph(5, {{0, 1}, {0, 2}, {2, 3}, {0, 4}});
  const std::vector<double> gain = {0.0, 0.02, 0.9, 0.3};
  const BranchChoice choice = ChooseBranch(s, gain, 0);
  EXPECT_EQ(choice.branch_edges, (std::vector<int>{0, 1, 3}));
  ASSERT_EQ(choice.edge, 1);
  EXPECT_EQ(choice.next_node, 2);
  const double l02 = s.edges[1].length_m, l23 = s.edges[2].length_m, l04 = s.edges[3].length_m;
  EXPECT_NEAR(choice.value, l02 * 0.02 + l23 * 0.9, 1e-12);
  EXPECT_NEAR(choice.branch_values[0], 0.0, 1e-12);
  EXPECT_NEAR(choice.branch_values[2], l04 * 0.3, 1e-12);
  const Eigen::Vector2d d = s.nodes[2].position_m - s.nodes[0].position_m;
  EXPECT_NEAR(choice.departure_angle_rad, std::atan2(d.y(), d.x()), 1e-12);
  // When the far edge cannot be reached, the moderate branch wins.
  const std::vector<std::uint8_t> usable = {1, 1, 0, 1};
  EXPECT_EQ(ChooseBranch(s, gain, 0, usable).edge, 3);
  // Reversing edge 0-2 (traced from 2) changes nothing but the departure direction's source.
  std::swap(s.edges[1].from, s.edges[1].to);
  std::reverse(s.edges[1].polyline.begin(), s.edges[1].polyline.end());
  const BranchChoice reversed = ChooseBranch(s, gain, 0);
  EXPECT_EQ(reversed.edge, 1);
  EXPECT_NEAR(reversed.departure_angle_rad, std::atan2(d.y(), d.x()), 1e-12);
  // No gain anywhere: no branch.
  EXPECT_EQ(ChooseBranch(s, std::vector<double>(4, 0.0), 0).edge, -1);
}

TEST(Routing, MstChoosesWhichBranchAnEdgeBelongsTo) {
  // A cycle 0-1-2-3-0 with the gain on edge 1-2: the MST cuts the cycle at its most expensive
  // (least gain) edge, and the gain edge then hangs from whichever root edge the tree keeps.
  const Skeleton s = HandGraph(4, {{0, 1}, {1, 2}, {2, 3}, {3, 0}});
  const std::vector<double> gain = {0.5, 1.0, 0.4, 0.01};  // 3-0 costs most: cut
  const BranchChoice choice = ChooseBranch(s, gain, 0);
  EXPECT_EQ(choice.branch_edges, (std::vector<int>{0}));
  EXPECT_EQ(choice.edge, 0);
  const std::vector<double> other = {0.01, 1.0, 0.4, 0.5};  // 0-1 costs most: leave by 3-0
  EXPECT_EQ(ChooseBranch(s, other, 0).edge, 3);
}

TEST(Routing, TerminationIffEveryAccessibleEdgeIsBelowTheThreshold) {
  const RoutingParams params;  // 0.01
  const std::vector<double> gain = {0.005, 0.02, 0.001};
  EXPECT_TRUE(CheckTermination(gain, std::vector<std::uint8_t>{1, 0, 1}, params).done);
  const TerminationCheck open = CheckTermination(gain, std::vector<std::uint8_t>{1, 1, 1}, params);
  EXPECT_FALSE(open.done);
  EXPECT_EQ(open.accessible_edges, 3);
  EXPECT_EQ(open.edges_above, 1);
  EXPECT_DOUBLE_EQ(open.max_accessible_gain, 0.02);
  EXPECT_FALSE(CheckTermination(gain, {}, params).done);  // empty: all accessible
  EXPECT_FALSE(CheckTermination(std::vector<double>{0.01}, {}, params).done);  // not below
  EXPECT_TRUE(CheckTermination(std::vector<double>{0.0099}, {}, params).done);
  EXPECT_TRUE(CheckTermination(std::vector<double>{}, {}, params).done);  // vacuous
}

TEST(Routing, GainCostAccessibilityAndRoot) {
  // Mean of a linear gain along a bent polyline: its value at half the arc length.
  const std::vector<Eigen::Vector2d> poly = {{0.0, 0.0}, {1.0, 0.0}, {1.0, 2.0}};
  const auto arc_gain = [](const Eigen::Vector2d& p) { return p.y() > 0 ? 1.0 + p.y() : p.x(); };
  EXPECT_NEAR(MeanAlongPolyline(poly, arc_gain, 0.1), 1.5, 1e-12);
  EXPECT_DOUBLE_EQ(EdgeCost(0.5), 2.0);
  EXPECT_DOUBLE_EQ(EdgeCost(0.0), 1e6);  // clamped
  // Accessibility by clearance: a corridor 1 m wide admits a 0.25 m robot on its axis, not by
  // the wall.
  omt::OccupancyRaster r = MakeRaster(4.0, 3.0, Cell::kOccupied);
  FillRect(&r, 0.0, 1.0, 4.0, 2.0, Cell::kFree);
  const omt::ClearanceRaster clearance = omt::ComputeClearance(r);
  SkeletonEdge axis, wall;
  axis.polyline = {{0.5, 1.5}, {3.5, 1.5}};
  wall.polyline = {{0.5, 1.5}, {2.0, 1.5}, {3.0, 1.1}};
  EXPECT_TRUE(EdgeClear(axis, clearance, 0.25));
  EXPECT_FALSE(EdgeClear(wall, clearance, 0.25));
  Skeleton s = HandGraph(3, {{0, 1}, {1, 2}});
  s.edges[0].polyline = axis.polyline;
  s.edges[1].polyline = wall.polyline;
  const std::vector<std::uint8_t> access =
      EdgeAccessibility(s, [&](const SkeletonEdge& e) { return EdgeClear(e, clearance, 0.25); });
  EXPECT_EQ(access, (std::vector<std::uint8_t>{1, 0}));
  const std::vector<double> gains = EdgeGains(s, [](const SkeletonEdge& e) { return e.length_m; });
  EXPECT_DOUBLE_EQ(gains[0], s.edges[0].length_m);
  // Root: the trisector within docking distance wins over a nearer leaf.
  Skeleton g = HandGraph(2, {{0, 1}});
  g.nodes[0].kind = SkeletonNodeKind::kLeaf;
  g.nodes[0].position_m = {0.0, 0.0};
  g.nodes[1].position_m = {0.4, 0.0};
  EXPECT_EQ(RoutingRoot(g, Eigen::Vector2d(0.05, 0.0)), 1);
  g.nodes[1].position_m = {0.7, 0.0};
  EXPECT_EQ(RoutingRoot(g, Eigen::Vector2d(0.05, 0.0)), 0);
  EXPECT_EQ(RoutingRoot(Skeleton{}, Eigen::Vector2d::Zero()), -1);
}

}  // namespace
}  // namespace voxplan::tensorfield
