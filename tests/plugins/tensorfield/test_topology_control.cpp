// Topology control X8. (d): a wedge-trisector pair is cancelled by local Laplacian smoothing when
// eq. 6 holds (skeleton distance below the sum of the local feature sizes), and kept when the
// points lie close to obstacles (small lfs) or the skeleton does not join them. The moves: one
// point moved where it is asked to, alone, the field outside its disc untouched; (a) a corner
// wedge hidden in its corner, (b) an exhausted end wedge retracted along its separatrix, (c) a
// trisector moved off an obstacle until it and its separatrices are clear.
#include <gtest/gtest.h>

#include <algorithm>
#include <complex>

#include "plugins/omt/algorithms/raster_ops.h"
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

// τ11 + i τ12 = z - z_w (a wedge) or conj(z - z_t) (a trisector); 4 m x 4 m at 5 cm.
TensorRaster LoneField(DegenerateType type, const Eigen::Vector2d& at) {
  return test::AnalyticField(80, 80, [&](const Eigen::Vector2d& p) {
    std::complex<double> d(p.x() - at.x(), p.y() - at.y());
    if (type == DegenerateType::kTrisector) d = std::conj(d);
    return Eigen::Vector2d(d.real(), d.imag());
  });
}

// Every cell at least `distance` from the segment a-b holds its value.
void ExpectUnchangedOutside(const TensorRaster& field, const TensorRaster& original,
                            const Eigen::Vector2d& a, const Eigen::Vector2d& b, double distance) {
  for (int i = 0; i < field.geometry.NumCells(); ++i) {
    const Eigen::Vector2d p = field.geometry.Center(i);
    const double s = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    if ((p - a - s * (b - a)).norm() < distance) continue;
    ASSERT_EQ(field.tau11[static_cast<std::size_t>(i)],
              original.tau11[static_cast<std::size_t>(i)]);
    ASSERT_EQ(field.tau12[static_cast<std::size_t>(i)],
              original.tau12[static_cast<std::size_t>(i)]);
  }
}

TEST(TopologyControl, MovesALoneWedgeOrTrisectorToItsTarget) {
  for (const DegenerateType type : {DegenerateType::kWedge, DegenerateType::kTrisector}) {
    const Eigen::Vector2d from(1.62, 2.03), to(2.14, 1.81);
    TensorRaster field = LoneField(type, from);
    const std::vector<DegeneratePoint> before = FindDegeneratePoints(field);
    ASSERT_EQ(before.size(), 1u);
    ASSERT_EQ(before[0].type, type);
    const TensorRaster original = field;
    DegeneratePoint moved;
    ASSERT_TRUE(MoveDegeneratePoint(&field, before[0], to, {}, &moved));
    const std::vector<DegeneratePoint> after = FindDegeneratePoints(field);
    ASSERT_EQ(after.size(), 1u);  // no point left behind, none made
    EXPECT_EQ(after[0].type, type);
    EXPECT_LT((after[0].position_m - to).norm(), test::kRes);  // within one cell
    EXPECT_EQ(after[0].cell_x, moved.cell_x);
    EXPECT_EQ(after[0].cell_y, moved.cell_y);
    EXPECT_EQ(after[0].separatrix_angles_rad.size(), before[0].separatrix_angles_rad.size());
    ExpectUnchangedOutside(field, original, before[0].position_m, to, PointMoveParams{}.outer_m);
  }
}

TEST(TopologyControl, RefusesToMoveAPointThatIsNotAloneInItsDisc) {
  // The pair 0.4 m apart: moving the wedge 0.3 m away from the trisector takes a disc holding
  // both. The field stays as it was.
  const Eigen::Vector2d w(2.2, 2.0), t(1.8, 2.0);
  TensorRaster field = PairField(w, t);
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(field);
  ASSERT_EQ(points.size(), 2u);
  const DegeneratePoint& wedge = points[0].type == DegenerateType::kWedge ? points[0] : points[1];
  const TensorRaster original = field;
  EXPECT_FALSE(MoveDegeneratePoint(&field, wedge, w + Eigen::Vector2d(0.3, 0.0)));
  EXPECT_EQ(field.tau11, original.tau11);
  EXPECT_EQ(field.tau12, original.tau12);
}

TEST(TopologyControl, RetractsAnExhaustedEndWedgeAlongItsSeparatrix) {
  // z - z_w has one separatrix, along +x. Its skeleton: the wedge and one edge of 2 m to a leaf.
  const Eigen::Vector2d w(1.0, 2.0);
  const TensorRaster original = LoneField(DegenerateType::kWedge, w);
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(original);
  ASSERT_EQ(points.size(), 1u);
  ASSERT_EQ(points[0].separatrix_angles_rad.size(), 1u);
  Skeleton skeleton;
  skeleton.nodes.resize(2);
  skeleton.nodes[0].kind = SkeletonNodeKind::kWedge;
  skeleton.nodes[0].position_m = points[0].position_m;
  skeleton.nodes[0].degenerate_index = 0;
  skeleton.nodes[1].position_m = w + Eigen::Vector2d(2.0, 0.0);
  SkeletonEdge edge;
  edge.from = 0;
  edge.to = 1;
  edge.polyline = {points[0].position_m, w + Eigen::Vector2d(1.0, 0.0),
                   w + Eigen::Vector2d(2.0, 0.0)};
  edge.length_m = 2.0;
  skeleton.edges.push_back(edge);
  const omt::ClearanceRaster clearance = UniformClearance(original.geometry, 2.0f);

  // Not exhausted: nothing moves (and one separatrix is no corner).
  TensorRaster field = original;
  PointMovesResult r =
      MoveDegeneratePoints(&field, points, skeleton, clearance,
                           [](const DegeneratePoint&, const SkeletonEdge&) { return false; });
  EXPECT_EQ(r.retracted_wedges + r.corner_wedges + r.moved_trisectors + r.failed, 0);
  EXPECT_EQ(field.tau11, original.tau11);

  // Exhausted: retract_m (1 m) along the edge.
  int asked = 0;
  r = MoveDegeneratePoints(&field, points, skeleton, clearance,
                           [&](const DegeneratePoint& p, const SkeletonEdge& e) {
                             ++asked;
                             EXPECT_EQ(e.to, 1);
                             EXPECT_LT((p.position_m - w).norm(), test::kRes);
                             return true;
                           });
  EXPECT_EQ(asked, 1);
  EXPECT_EQ(r.retracted_wedges, 1);
  const std::vector<DegeneratePoint> after = FindDegeneratePoints(field);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].type, DegenerateType::kWedge);
  EXPECT_LT((after[0].position_m - (points[0].position_m + Eigen::Vector2d(1.0, 0.0))).norm(),
            test::kRes);
}

TEST(TopologyControl, MovesATrisectorOffAnObstacleUntilItAndItsSeparatricesAreClear) {
  // A wall at x < 0.5; the trisector 0.15 m from it, closer than the robot's 0.2 m radius, two of
  // its separatrices (at ±120°) heading into the wall.
  omt::OccupancyRaster room = test::MakeRaster(4.0, 4.0, omt::Cell::kFree);
  test::FillRect(&room, 0.0, 0.0, 0.5, 4.0, omt::Cell::kOccupied);
  const omt::ClearanceRaster clearance = omt::ComputeClearance(room);
  const Eigen::Vector2d t(0.66, 2.01);
  TensorRaster field = LoneField(DegenerateType::kTrisector, t);
  const std::vector<DegeneratePoint> points = FindDegeneratePoints(field);
  ASSERT_EQ(points.size(), 1u);
  ASSERT_EQ(points[0].type, DegenerateType::kTrisector);
  PointMovesParams params;
  params.trace.block_clearance_m = params.robot_radius_m;
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  const Skeleton skeleton = ExtractSkeleton(field, points, params.trace, obstacles);
  const PointMovesResult r = MoveDegeneratePoints(&field, points, skeleton, clearance, {}, params);
  EXPECT_EQ(r.moved_trisectors, 1);
  EXPECT_EQ(r.failed, 0);
  const std::vector<DegeneratePoint> after = FindDegeneratePoints(field);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].type, DegenerateType::kTrisector);
  EXPECT_GT(after[0].position_m.x(), t.x() + 0.1);  // away from the wall, up the clearance
  EXPECT_LE((after[0].position_m - t).norm(), params.trisector_max_move_m + test::kRes);
  EXPECT_GE(clearance.AtPoint(after[0].position_m), params.robot_radius_m);
  SkeletonParams check = params.trace;
  check.max_length_m = params.trisector_check_m;
  const Skeleton own = ExtractSkeleton(field, after, check, obstacles);
  ASSERT_EQ(own.edges.size(), 3u);
  for (const SkeletonEdge& e : own.edges)
    EXPECT_NE(own.nodes[static_cast<std::size_t>(e.to)].end, AdvectionStop::kBlocked);
}

TEST(TopologyControl, HidesACornerWedgeInItsCorner) {
  // V = Δ + 0.8 e^{i 165°} conj(Δ), Δ = z - z_w: a wedge with three separatrices, two of them
  // (at about 315° and 351°) 36° apart, the shape a sharp corner gives. A wall at x >= wall_x.
  const Eigen::Vector2d w(2.01, 2.02);
  const std::complex<double> beta = std::polar(0.8, 165.0 * M_PI / 180.0);
  const auto wedge_field = [&](double b_scale) {
    return test::AnalyticField(80, 80, [&](const Eigen::Vector2d& p) {
      const std::complex<double> d(p.x() - w.x(), p.y() - w.y());
      const std::complex<double> v = d + b_scale * beta * std::conj(d);
      return Eigen::Vector2d(v.real(), v.imag());
    });
  };
  const auto wall_at = [](double wall_x) {
    omt::OccupancyRaster room = test::MakeRaster(4.0, 4.0, omt::Cell::kFree);
    test::FillRect(&room, wall_x, 0.0, 4.0, 4.0, omt::Cell::kOccupied);
    return omt::ComputeClearance(room);
  };
  const PointMovesParams params;
  {
    TensorRaster field = wedge_field(1.0);
    const std::vector<DegeneratePoint> points = FindDegeneratePoints(field);
    ASSERT_EQ(points.size(), 1u);
    ASSERT_EQ(points[0].type, DegenerateType::kWedge);
    ASSERT_EQ(points[0].separatrix_angles_rad.size(), 3u);
    // The wall 0.6 m away on the narrow pair's side: the wedge goes there, out of reach.
    const omt::ClearanceRaster clearance = wall_at(2.6);
    const PointMovesResult r =
        MoveDegeneratePoints(&field, points, Skeleton{}, clearance, {}, params);
    EXPECT_EQ(r.corner_wedges, 1);
    const std::vector<DegeneratePoint> after = FindDegeneratePoints(field);
    ASSERT_EQ(after.size(), 1u);
    EXPECT_EQ(after[0].type, DegenerateType::kWedge);
    EXPECT_LT(clearance.AtPoint(after[0].position_m), params.robot_radius_m);
    EXPECT_GT(after[0].position_m.x(), w.x() + 0.2);  // towards the wall
    EXPECT_LT(after[0].position_m.y(), w.y());        // along the bisector (about 333°)
  }
  {
    // The wall farther than corner_max_move_m plus the radius: left where it is.
    TensorRaster field = wedge_field(1.0);
    const TensorRaster original = field;
    const std::vector<DegeneratePoint> points = FindDegeneratePoints(field);
    const PointMovesResult r =
        MoveDegeneratePoints(&field, points, Skeleton{}, wall_at(3.5), {}, params);
    EXPECT_EQ(r.corner_wedges + r.failed, 0);
    EXPECT_EQ(field.tau11, original.tau11);
  }
  {
    // One separatrix (V = Δ): no corner, however near the wall.
    TensorRaster field = wedge_field(0.0);
    const std::vector<DegeneratePoint> points = FindDegeneratePoints(field);
    ASSERT_EQ(points.size(), 1u);
    ASSERT_EQ(points[0].separatrix_angles_rad.size(), 1u);
    const PointMovesResult r =
        MoveDegeneratePoints(&field, points, Skeleton{}, wall_at(2.6), {}, params);
    EXPECT_EQ(r.corner_wedges + r.failed, 0);
  }
}

}  // namespace
}  // namespace voxplan::tensorfield
