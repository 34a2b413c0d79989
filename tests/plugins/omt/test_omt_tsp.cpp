#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "plugins/omt/algorithms/tsp.h"

namespace voxplan::omt {
namespace {

constexpr double kChristofidesLocalBound = 1.5;  // brief: within 1.5× of Held–Karp
constexpr double kHoogeveenBound = 5.0 / 3.0;    // fixed-endpoint Christofides, exact matching
constexpr double kTol = 1e-9;

DistanceMatrix RandomEuclidean(std::mt19937* rng, int n, double size_m) {
  std::uniform_real_distribution<double> coord(0.0, size_m);
  std::vector<Eigen::Vector2d> p(n);
  for (auto& v : p) v = {coord(*rng), coord(*rng)};
  DistanceMatrix d(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) d(a, b) = (p[a] - p[b]).norm();
  return d;
}

int Farthest(const DistanceMatrix& d, int from) {
  int end = from == 0 ? 1 : 0;
  for (int v = 0; v < d.rows; ++v)
    if (v != from && d(from, v) > d(from, end)) end = v;
  return end;
}

void ExpectOpenPath(const std::vector<int>& order, int n, int start, int end) {
  ASSERT_EQ(static_cast<int>(order.size()), n);
  EXPECT_EQ(order.front(), start);
  EXPECT_EQ(order.back(), end);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < n; ++i) EXPECT_EQ(sorted[i], i);
}

TEST(OmtTsp, HeldKarpMatchesExhaustiveSearch) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 3 + trial % 5;  // up to 7 nodes: 5! interior orders
    const DistanceMatrix d = RandomEuclidean(&rng, n, 10.0);
    const int end = Farthest(d, 0);
    const std::vector<int> hk = OpenPathHeldKarp(d, 0, end);
    ExpectOpenPath(hk, n, 0, end);
    std::vector<int> inner;
    for (int v = 1; v < n; ++v)
      if (v != end) inner.push_back(v);
    double best = std::numeric_limits<double>::infinity();
    do {
      std::vector<int> order{0};
      order.insert(order.end(), inner.begin(), inner.end());
      order.push_back(end);
      best = std::min(best, PathLength(d, order));
    } while (std::next_permutation(inner.begin(), inner.end()));
    EXPECT_NEAR(PathLength(d, hk), best, kTol);
  }
}

TEST(OmtTsp, ChristofidesIsWithinBoundsOfHeldKarp) {
  std::mt19937 rng(2019);
  double worst_plain = 1.0;
  double worst_local = 1.0;
  for (int trial = 0; trial < 80; ++trial) {
    const int n = 4 + trial % 10;  // 4..13 nodes
    const DistanceMatrix d = RandomEuclidean(&rng, n, 10.0);
    const int end = Farthest(d, 0);
    const double opt = PathLength(d, OpenPathHeldKarp(d, 0, end));
    TspParams plain;
    plain.local_search = false;
    const std::vector<int> c0 = OpenPathChristofides(d, 0, end, plain);
    const std::vector<int> c1 = OpenPathChristofides(d, 0, end);
    ExpectOpenPath(c0, n, 0, end);
    ExpectOpenPath(c1, n, 0, end);
    const double l0 = PathLength(d, c0);
    const double l1 = PathLength(d, c1);
    EXPECT_GE(l1, opt - kTol);
    EXPECT_LE(l0, kHoogeveenBound * opt + kTol) << "trial " << trial;
    EXPECT_LE(l1, kChristofidesLocalBound * opt + kTol) << "trial " << trial;
    EXPECT_LE(l1, l0 + kTol);  // local search only shortens
    worst_plain = std::max(worst_plain, l0 / opt);
    worst_local = std::max(worst_local, l1 / opt);
  }
  RecordProperty("worst_plain_ratio", std::to_string(worst_plain));
  RecordProperty("worst_local_ratio", std::to_string(worst_local));
}

TEST(OmtTsp, GreedyVisitsNearestFirst) {
  // Points on a line at 0, 1, 3, 6, start at 1: nearest-first goes 1 → 0 → 3 → 6.
  const std::vector<double> x{0.0, 1.0, 3.0, 6.0};
  DistanceMatrix d(4, 4);
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) d(a, b) = std::abs(x[a] - x[b]);
  EXPECT_EQ(OpenPathGreedy(d, 1), (std::vector<int>{1, 0, 2, 3}));
  // The open TSP from 1 to the farthest node (3) does the same here; from 0 it is the line.
  EXPECT_EQ(OpenPathChristofides(d, 0, 3), (std::vector<int>{0, 1, 2, 3}));
}

TEST(OmtTsp, LargeInstancesUseGreedyMatchingAndStayValid) {
  std::mt19937 rng(5);
  const DistanceMatrix d = RandomEuclidean(&rng, 40, 20.0);
  const int end = Farthest(d, 0);
  const std::vector<int> order = OpenPathChristofides(d, 0, end);
  ExpectOpenPath(order, 40, 0, end);
  EXPECT_LE(PathLength(d, order), PathLength(d, OpenPathGreedy(d, 0)) * 1.5);
  EXPECT_EQ(order, OpenPathChristofides(d, 0, end));  // deterministic
}

}  // namespace
}  // namespace voxplan::omt
