#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/omt/algorithms/task_views.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

using testing::FillRect;
using testing::FrameRect;
using testing::MakeRaster;

// A 4 × 4 m walled room, known, with a pillar, opening onto unknown space for x >= 4 m.
OccupancyRaster PartialRoom(float wall_weight) {
  OccupancyRaster r = MakeRaster(8.0, 4.0, 0.05, Cell::kFree);
  FrameRect(&r, 0.0, 0.0, 8.0, 4.0);
  FillRect(&r, 1.6, 1.6, 2.0, 2.0, Cell::kOccupied);
  FillRect(&r, 4.0, 0.1, 7.9, 3.9, Cell::kUnknown);
  r.tsdf_weight.assign(r.cells.size(), 0.0f);
  for (std::size_t i = 0; i < r.cells.size(); ++i)
    if (r.cells[i] == Cell::kOccupied) r.tsdf_weight[i] = wall_weight;
  return r;
}

TaskViewParams Params() {
  TaskViewParams p;
  p.max_views = 12;
  return p;
}

TEST(OmtTaskViews, UncertaintyFollowsSection32) {
  const UncertaintyParams p;
  EXPECT_EQ(CellUncertainty(Cell::kFree, 5.0f, p), 0.0);
  EXPECT_EQ(CellUncertainty(Cell::kUnknown, 0.0f, p), p.unknown_uncertainty);
  EXPECT_GT(CellUncertainty(Cell::kOccupied, 1.0f, p), CellUncertainty(Cell::kOccupied, 10.0f, p));
}

TEST(OmtTaskViews, CandidatesAreFrontierAndUncertainSurfaceSortedByUncertainty) {
  const OccupancyRaster r = PartialRoom(/*wall_weight=*/1.0f);
  const std::vector<Candidate> c = CollectCandidates(r, UncertaintyParams{});
  ASSERT_FALSE(c.empty());
  bool saw_surface = false;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i > 0) {
      EXPECT_GE(c[i - 1].uncertainty, c[i].uncertainty);
    }
    EXPECT_NE(r.At(c[i].cell), Cell::kFree);
    saw_surface |= r.At(c[i].cell) == Cell::kOccupied;
  }
  EXPECT_TRUE(saw_surface);
  EXPECT_EQ(r.At(c.front().cell), Cell::kUnknown);  // unknown ranks first (uncertainty 1 > 0.5)
}

TEST(OmtTaskViews, ViewsKeepClearanceAndLookAtTheirTargets) {
  const OccupancyRaster r = PartialRoom(1.0f);
  const ClearanceRaster clearance = ComputeClearance(r);
  const TaskViewParams p = Params();
  const std::vector<TaskView> views = ExtractTaskViews(r, clearance, p);
  ASSERT_GE(views.size(), 3u);
  EXPECT_LE(static_cast<int>(views.size()), p.max_views);
  std::set<int> targets;
  for (const TaskView& v : views) {
    EXPECT_EQ(r.At(v.cell), Cell::kFree);
    EXPECT_GT(clearance.At(v.cell), p.clearance_factor * p.robot_radius_m);
    EXPECT_GT(v.validness, 0.0f);
    EXPECT_LE(v.validness, 1.0f);
    const Eigen::Vector2d to_target = r.geometry.Center(v.target_cell) - v.position_m;
    EXPECT_NEAR(WrapAngle(std::atan2(to_target.y(), to_target.x()) - v.yaw_rad), 0.0, 1e-9);
    EXPECT_LE(to_target.norm(), p.sensor.d_inf_m);
    EXPECT_TRUE(targets.insert(v.target_cell).second) << "one view per queue head";
  }
  // Returned by decreasing importance; the most important looks into the unknown part.
  for (std::size_t i = 1; i < views.size(); ++i) {
    EXPECT_GE(views[i - 1].importance, views[i].importance);
  }
  EXPECT_EQ(r.At(views.front().target_cell), Cell::kUnknown);
  EXPECT_GT(views.front().importance, views.back().importance);
  // In extraction order instead, the queue (by uncertainty) puts the frontier heads first.
  TaskViewParams unsorted = p;
  unsorted.sort_by_importance = false;
  const std::vector<TaskView> by_priority = ExtractTaskViews(r, clearance, unsorted);
  ASSERT_EQ(by_priority.size(), views.size());
  EXPECT_EQ(r.At(by_priority.front().target_cell), Cell::kUnknown);
}

TEST(OmtTaskViews, BestViewsOfSurfacesStandInTheValidRange) {
  const OccupancyRaster r = PartialRoom(1.0f);
  const TaskViewParams p = Params();
  int checked = 0;
  for (const TaskView& v : ExtractTaskViews(r, ComputeClearance(r), p)) {
    if (r.At(v.target_cell) != Cell::kOccupied || v.validness < 0.999f) continue;
    const double d = (r.geometry.Center(v.target_cell) - v.position_m).norm();
    EXPECT_GE(d, p.sensor.d_min_m);
    EXPECT_LE(d, p.sensor.d_max_m);
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(OmtTaskViews, ImportanceRanksUnknownAboveUnscannedAboveScannedSurfaces) {
  const TaskViewParams p = Params();
  const OccupancyRaster fresh = PartialRoom(/*wall_weight=*/0.0f);
  const OccupancyRaster scanned = PartialRoom(/*wall_weight=*/50.0f);
  // From (2.5, 2.5): facing +x into the unknown part, facing -y at the bottom wall.
  const Eigen::Vector2d p0(2.5, 2.5);
  const double into_unknown = ViewImportance(fresh, p0, 0.0, p);
  const double fresh_wall = ViewImportance(fresh, p0, -kPi / 2, p);
  const double scanned_wall = ViewImportance(scanned, p0, -kPi / 2, p);
  EXPECT_GT(into_unknown, fresh_wall);
  EXPECT_GT(fresh_wall, scanned_wall);
  EXPECT_GT(into_unknown, 1.5);  // worth a task: above the termination threshold
  EXPECT_LT(scanned_wall, 1.5);  // a well-scanned wall is not
}

TEST(OmtTaskViews, TerminatesOnlyWhenNoImportantViewRemains) {
  const TaskViewParams p = Params();
  const OccupancyRaster partial = PartialRoom(1.0f);
  EXPECT_FALSE(ShouldTerminate(ExtractTaskViews(partial, ComputeClearance(partial), p)));
  // Fully explored room whose walls are scanned enough (weight 3, uncertainty 0.25) to be
  // queued but not to be worth a view any more.
  OccupancyRaster done = MakeRaster(4.0, 4.0, 0.05, Cell::kFree);
  FrameRect(&done, 0.0, 0.0, 4.0, 4.0);
  done.tsdf_weight.assign(done.cells.size(), 0.0f);
  for (std::size_t i = 0; i < done.cells.size(); ++i)
    if (done.cells[i] == Cell::kOccupied) done.tsdf_weight[i] = 3.0f;
  const std::vector<TaskView> views = ExtractTaskViews(done, ComputeClearance(done), p);
  EXPECT_FALSE(views.empty());
  EXPECT_TRUE(ShouldTerminate(views));
}

TEST(OmtTaskViews, SettledCellsAreNeitherQueuedNorCounted) {
  // The unknown half settled (looked at in vain): no frontier candidate, no view worth it; the
  // walls (weight 3) are not worth one either.
  OccupancyRaster r = PartialRoom(3.0f);
  const ClearanceRaster clearance = ComputeClearance(r);
  EXPECT_FALSE(ShouldTerminate(ExtractTaskViews(r, clearance, Params())));
  r.settled.assign(r.cells.size(), 0);
  for (std::size_t i = 0; i < r.cells.size(); ++i) r.settled[i] = r.cells[i] == Cell::kUnknown;
  for (const Candidate& c : CollectCandidates(r, UncertaintyParams{}))
    EXPECT_NE(r.At(c.cell), Cell::kUnknown);
  const Eigen::Vector2d p(3.0, 2.0);
  EXPECT_EQ(ViewImportance(r, p, 0.0, Params()), 0.0);  // facing the settled half
  EXPECT_TRUE(ShouldTerminate(ExtractTaskViews(r, clearance, Params())));
}

TEST(OmtTaskViews, AccessibilityMaskRestrictsViewCells) {
  const OccupancyRaster r = PartialRoom(1.0f);
  const ClearanceRaster clearance = ComputeClearance(r);
  std::vector<std::uint8_t> accessible(r.cells.size(), 0);
  for (int i = 0; i < r.geometry.NumCells(); ++i)
    accessible[static_cast<std::size_t>(i)] = r.geometry.Center(i).y() < 2.0 ? 1 : 0;
  const std::vector<TaskView> views = ExtractTaskViews(r, clearance, Params(), &accessible);
  ASSERT_FALSE(views.empty());
  for (const TaskView& v : views) EXPECT_LT(v.position_m.y(), 2.0);
}

TEST(OmtTaskViews, FrontierPointsAblationStandsNextToTheFrontier) {
  const OccupancyRaster r = PartialRoom(1.0f);
  TaskViewParams p = Params();
  p.frontier_points_only = true;
  const std::vector<TaskView> views = ExtractTaskViews(r, ComputeClearance(r), p);
  ASSERT_FALSE(views.empty());
  for (const TaskView& v : views) {
    const double d = (r.geometry.Center(v.target_cell) - v.position_m).norm();
    // Nearest cell with 1.5 robot radii of clearance: about that far from the frontier, up to
    // the cell lattice (kLatticeSlack cells).
    constexpr double kLatticeSlack = 3.0;
    EXPECT_LE(d, p.clearance_factor * p.robot_radius_m + kLatticeSlack * r.geometry.resolution_m);
  }
}

TEST(OmtTaskViews, ExtractionIsDeterministic) {
  const OccupancyRaster r = PartialRoom(1.0f);
  const ClearanceRaster c = ComputeClearance(r);
  const auto a = ExtractTaskViews(r, c, Params());
  const auto b = ExtractTaskViews(r, c, Params());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].cell, b[i].cell);
    EXPECT_EQ(a[i].target_cell, b[i].target_cell);
    EXPECT_EQ(a[i].importance, b[i].importance);
  }
}

TEST(OmtTaskViews, ClearanceTransformIsExactDistanceToObstacles) {
  OccupancyRaster r = MakeRaster(2.0, 2.0, 0.1, Cell::kFree);
  r.cells[static_cast<std::size_t>(r.geometry.Index(5, 5))] = Cell::kOccupied;
  const ClearanceRaster c = ComputeClearance(r);
  EXPECT_NEAR(c.At(r.geometry.Index(5, 5)), 0.0, 1e-6);
  EXPECT_NEAR(c.At(r.geometry.Index(8, 9)), 0.5, 1e-6);  // 3-4-5 triangle
  EXPECT_NEAR(c.At(r.geometry.Index(0, 5)), 0.5, 1e-6);
}

}  // namespace
}  // namespace voxplan::omt
