// Topology control X8 (d): a wedge-trisector pair is cancelled by local Laplacian smoothing when
// eq. 6 holds (skeleton distance below the sum of the local feature sizes), and kept when the
// points lie close to obstacles (small lfs) or the skeleton does not join them.
#include <gtest/gtest.h>

#include <complex>

#include "plugins/tensorfield/algorithms/topology_control.h"
#include "tests/plugins/tensorfield/tensor_scenes.h"

namespace voxplan::tensorfield {
namespace {

// τ11 + i τ12 = (z - z_w) conj(z - z_t): winding +1 (a wedge) around z_w, -1 (a trisector)
// around z_t, 0 around both; 4 m x 4 m at 5 cm.
TensorRaster PairField(const Eigen::Vector2d& w, const Eigen::Vector2d& t) {
  return test::AnalyticField(80, 80, [&](const Eigen::Vector2d& p) {
    const std::complex<double> z(p.x(), p.y());
    const std::complex<double> c = (z - std::complex<double>(w.x(), w.y())) *
                                   std::conj(z - std::complex<double>(t.x(), t.y()));
    return Eigen::Vector2d(c.real(), c.imag());
  });
}

omt::ClearanceRaster UniformClearance(const omt::RasterGeometry& g, float c) {
  omt::ClearanceRaster r;
  r.geometry = g;
  r.clearance_m.assign(static_cast<std::size_t>(g.NumCells()), c);
  return r;
}

// The skeleton as ExtractSkeleton numbers it: the points as nodes 0..P-1, here one edge between.
Skeleton Joined(const std::vector<DegeneratePoint>& points, double length_m) {
  Skeleton s;
  for (std::size_t i = 0; i < points.size(); ++i) {
    SkeletonNode node;
    node.kind = points[i].type == DegenerateType::kWedge ? SkeletonNodeKind::kWedge
                                                         : SkeletonNodeKind::kTrisector;
    node.position_m = points[i].position_m;
    node.degenerate_index = static_cast<int>(i);
    s.nodes.push_back(node);
  }
  SkeletonEdge e;
  e.from = 0;
  e.to = 1;
  e.polyline = {points[0].position_m, points[1].position_m};
  e.length_m = length_m;
  s.edges.push_back(e);
  return s;
}

TEST(TopologyControl, CancelsACloseWedgeTrisectorPairByLocalSmoothing) {
  const Eigen::Vector2d w(2.2, 2.0), t(1.8, 2.0);
  TensorRaster field = PairField(w, t);
  const std::vector<DegeneratePoint> before = FindDegeneratePoints(field);
  ASSERT_EQ(before.size(), 2u);
  for (const DegeneratePoint& p : before) {
    const Eigen::Vector2d expected = p.type == DegenerateType::kWedge ? w : t;
    EXPECT_LT((p.position_m - expected).norm(), 0.05);  // within one cell
  }
  const TensorRaster original = field;
  // lfs 0.5 m each: 0.4 m over the skeleton < 1 m.
  const PairCancelResult r = CancelDegeneratePairs(&field, before, Joined(before, 0.4),
                                                   UniformClearance(field.geometry, 0.5f));
  EXPECT_EQ(r.candidates, 1);
  EXPECT_EQ(r.cancelled, 1);
  EXPECT_TRUE(FindDegeneratePoints(field).empty());
  // Only the disc around the pair changed (radius 0.2 m plus at most three margins).
  for (int i = 0; i < field.geometry.NumCells(); ++i) {
    if ((field.geometry.Center(i) - 0.5 * (w + t)).norm() <= 0.2 + 3 * 0.15 + 1e-9) continue;
    EXPECT_EQ(field.tau11[static_cast<std::size_t>(i)],
              original.tau11[static_cast<std::size_t>(i)]);
    EXPECT_EQ(field.tau12[static_cast<std::size_t>(i)],
              original.tau12[static_cast<std::size_t>(i)]);
  }
}

TEST(TopologyControl, KeepsPairsThatAreTopologicallySignificant) {
  const Eigen::Vector2d w(2.2, 2.0), t(1.8, 2.0);
  const TensorRaster original = PairField(w, t);
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(original);
  ASSERT_EQ(points.size(), 2u);
  // Near obstacles (lfs 0.1 m each): 0.4 m is not below 0.2 m.
  TensorRaster field = original;
  PairCancelResult r = CancelDegeneratePairs(&field, points, Joined(points, 0.4),
                                             UniformClearance(field.geometry, 0.1f));
  EXPECT_EQ(r.candidates, 0);
  EXPECT_EQ(field.tau11, original.tau11);
  // Far apart over the skeleton (a detour of 3 m) although close in the plane.
  r = CancelDegeneratePairs(&field, points, Joined(points, 3.0),
                            UniformClearance(field.geometry, 0.5f));
  EXPECT_EQ(r.candidates, 0);
  EXPECT_EQ(FindDegeneratePoints(field).size(), 2u);
}

}  // namespace
}  // namespace voxplan::tensorfield
