#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <thread>

#include "plugins/omt/algorithms/planner.h"
#include "plugins/omt/algorithms/raster_ops.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

using testing::MakeApartment;

std::vector<RobotState> Robots() {
  std::vector<RobotState> robots(3);
  robots[0].position_m = {1.0, 1.0};
  robots[1].position_m = {2.5, 2.5};
  robots[2].position_m = {1.0, 4.5};
  return robots;
}

bool PathClear(const ClearanceRaster& c, const std::vector<PathPoint>& pts, double r) {
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!SegmentClear(c, pts[i - 1].p_m, pts[i].p_m, r)) return false;
  return true;
}

class OmtPlanner : public ::testing::Test {
 protected:
  OccupancyRaster raster_ = MakeApartment(10.0, 6.0, 0.05, /*known_x_m=*/7.0);
  ClearanceRaster clearance_ = ComputeClearance(raster_);
};

TEST_F(OmtPlanner, FullPassAssignsEachViewOnceAlongCollisionFreePaths) {
  PlannerOptions options;
  PlanResult result;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &result).ok());
  EXPECT_FALSE(result.terminated);
  ASSERT_FALSE(result.views.empty());
  EXPECT_LE(static_cast<int>(result.views.size()), options.kappa * 3);
  std::set<int> visited;
  int planned = 0;
  for (int r = 0; r < 3; ++r) {
    const RobotPlan& plan = result.robots[r];
    if (plan.tasks.empty()) continue;
    ++planned;
    EXPECT_TRUE(plan.path.front().p_m.isApprox(Robots()[r].position_m));
    EXPECT_EQ(plan.yaw_rad.size(), plan.path.size());
    EXPECT_TRUE(PathClear(clearance_, plan.path, options.robot_radius_m)) << "robot " << r;
    EXPECT_GT(plan.length_m, 0.0);
    for (int k : plan.tasks) {
      EXPECT_EQ(result.assignment.task_robot[k], r);
      EXPECT_TRUE(visited.insert(k).second);
    }
    // The path ends at the farthest assigned task view, reached within the λ tolerance.
    EXPECT_LE((plan.path.back().p_m - result.views[plan.tasks.back()].position_m).norm(), 0.15);
  }
  EXPECT_GE(planned, 1);
  for (std::size_t k = 0; k < result.views.size(); ++k)
    if (result.assignment.task_robot[k] >= 0) {
      EXPECT_TRUE(visited.count(static_cast<int>(k)));
    }
}

TEST_F(OmtPlanner, ViewsNotAboveTheThresholdAreLeftOutWhileABetterOneRemains) {
  PlannerOptions all;
  all.assign_unimportant_views = true;
  PlanResult every;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), all, &every).ok());
  std::vector<double> importance;
  for (const TaskView& v : every.views) importance.push_back(v.importance);
  std::sort(importance.begin(), importance.end());
  ASSERT_GE(importance.size(), 4u);
  // A threshold between two of the views' importances, so that some fall on each side.
  const std::size_t mid = importance.size() / 2;
  ASSERT_LT(importance[mid - 1], importance[mid]);
  const double threshold = 0.5 * (importance[mid - 1] + importance[mid]);
  PlannerOptions options;
  options.importance_threshold = threshold;
  PlanResult result;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &result).ok());
  EXPECT_FALSE(result.terminated);
  EXPECT_EQ(result.views.size(), importance.size() - mid);
  for (const TaskView& v : result.views) EXPECT_GT(v.importance, threshold);
  all.importance_threshold = threshold;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), all, &result).ok());
  EXPECT_EQ(result.views.size(), importance.size());
}

TEST_F(OmtPlanner, SmoothedPathsKeepTheMarginBeyondTheRadius) {
  constexpr double kMarginM = 0.1;
  PlannerOptions options;
  for (double margin : {0.0, kMarginM}) {
    options.path_margin_m = margin;
    PlanResult result;
    ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &result).ok());
    int clear = 0, planned = 0;
    for (const RobotPlan& plan : result.robots) {
      if (plan.path.empty()) continue;
      ++planned;
      clear += PathClear(clearance_, plan.path, options.robot_radius_m + kMarginM);
    }
    ASSERT_GT(planned, 0);
    // Without the margin some path hugs a corner closer than that.
    if (margin > 0.0) {
      EXPECT_EQ(clear, planned);
    } else {
      EXPECT_LT(clear, planned);
    }
  }
}

TEST(OmtAccessibility, ADoorwayBarelyWiderThanTheRobotLeadsOn) {
  // Two rooms joined by a 0.5 m doorway (0.25 m clearance in its middle, a 0.18 m robot passes);
  // the right room is half unknown. Views there must count as accessible: the coarse geodesic
  // grid alone (nodes 0.2 m apart needing 0.36 m of clearance) would shut the door.
  constexpr double kDoorM = 0.5;
  OccupancyRaster r = testing::MakeRaster(8.0, 4.0, 0.05, Cell::kFree);
  testing::FrameRect(&r, 0.0, 0.0, 8.0, 4.0);
  testing::FillRect(&r, 4.0, 0.0, 4.1, 2.0 - 0.5 * kDoorM, Cell::kOccupied);
  testing::FillRect(&r, 4.0, 2.0 + 0.5 * kDoorM, 4.1, 4.0, Cell::kOccupied);
  testing::FillRect(&r, 6.0, 0.1, 7.9, 3.9, Cell::kUnknown);
  const ClearanceRaster clearance = ComputeClearance(r);
  std::vector<RobotState> robots(1);
  robots[0].position_m = {1.0, 2.0};
  PlannerOptions options;
  int anchored = 0;
  const std::vector<std::uint8_t> cells =
      AccessibleCells(r, clearance, robots, options.robot_radius_m, 0.5, &anchored);
  EXPECT_EQ(anchored, 1);
  EXPECT_TRUE(cells[static_cast<std::size_t>(r.geometry.IndexOf({5.0, 2.0}))]);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (cells[i]) {
      EXPECT_GE(clearance.clearance_m[i], options.robot_radius_m);
    }
  }
  const ViewSet set = ExtractAccessibleViews(r, clearance, robots, options);
  EXPECT_EQ(set.anchored_robots, 1);
  int behind_door = 0;
  for (const TaskView& v : set.views) behind_door += v.position_m.x() > 4.1;
  EXPECT_GT(behind_door, 0);
  // A robot off the free cells (inside the wall) is snapped within the radius, or not at all.
  robots[0].position_m = {4.05, 1.0};
  AccessibleCells(r, clearance, robots, options.robot_radius_m, 0.5, &anchored);
  EXPECT_EQ(anchored, 1);
  AccessibleCells(r, clearance, robots, options.robot_radius_m, 0.1, &anchored);
  EXPECT_EQ(anchored, 0);
}

TEST_F(OmtPlanner, DeterministicAndIndependentOfThreadCount) {
  PlannerOptions options;
  PlanResult a, b;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &a).ok());
  options.num_threads = 1;
  ASSERT_TRUE(PlanOmt(raster_, nullptr, Robots(), options, &b).ok());
  ASSERT_EQ(a.views.size(), b.views.size());
  EXPECT_EQ(a.assignment.task_robot, b.assignment.task_robot);
  for (int r = 0; r < 3; ++r) {
    ASSERT_EQ(a.robots[r].path.size(), b.robots[r].path.size());
    for (std::size_t i = 0; i < a.robots[r].path.size(); ++i)
      EXPECT_EQ(a.robots[r].path[i].p_m, b.robots[r].path[i].p_m);
  }
}

TEST_F(OmtPlanner, AblationsRun) {
  for (int ablation = 0; ablation < 4; ++ablation) {
    PlannerOptions options;
    options.use_task_views = ablation != 0;
    options.use_tsp = ablation != 1;
    options.refine = ablation != 2;
    options.optimize_paths = ablation != 3;
    PlanResult result;
    ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &result).ok()) << ablation;
    ASSERT_FALSE(result.views.empty());
    if (!options.refine) {  // NoRefine assigns every task
      for (int r : result.assignment.task_robot) EXPECT_GE(r, 0);
    }
    for (const RobotPlan& plan : result.robots)
      EXPECT_TRUE(PathClear(clearance_, plan.path, options.robot_radius_m)) << ablation;
  }
}

TEST_F(OmtPlanner, PathOptimisationShortensPaths) {
  PlannerOptions options;
  options.refine = false;  // every robot gets tasks
  PlanResult smooth, raw;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &smooth).ok());
  options.optimize_paths = false;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &raw).ok());
  double l_smooth = 0.0, l_raw = 0.0;
  for (int r = 0; r < 3; ++r) {
    l_smooth += smooth.robots[r].length_m;
    l_raw += raw.robots[r].length_m;
  }
  EXPECT_LT(l_smooth, l_raw);
}

TEST_F(OmtPlanner, FewViewsForTheTeamLeaveTheExtraRobotsStill) {
  // Six robots in the known part, fewer than 3 important views each: ⌈K / 3⌉ robots work.
  std::vector<RobotState> robots = Robots();
  for (RobotState r : Robots()) {
    r.position_m.x() += 0.5;
    robots.push_back(r);
  }
  auto busy = [](const PlanResult& result) {
    return std::count_if(result.robots.begin(), result.robots.end(),
                         [](const RobotPlan& plan) { return !plan.tasks.empty(); });
  };
  PlannerOptions options;
  options.reach_horizon_s = 0.0;  // only the team limit holds robots back
  PlanResult result;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, robots, options, &result).ok());
  const int views = static_cast<int>(result.views.size());
  ASSERT_GT(views, 0);
  ASSERT_LT(views, 3 * 6);
  const int workers = (views + 2) / 3;
  EXPECT_EQ(result.robots_held_back, 6 - workers);
  EXPECT_LE(busy(result), workers);
  // Without the limit every robot has capacity, and more of them drive.
  options.team_views_per_robot = 0.0;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, robots, options, &result).ok());
  EXPECT_EQ(result.robots_held_back, 0);
  EXPECT_GT(busy(result), workers);
}

TEST_F(OmtPlanner, ExternalGeodesicsAreUsedFromTheCallingThread) {
  // Provider: the internal geodesics' stand-in, Euclidean distances and straight segments, in
  // a scene where those are wrong only by going through walls; what matters is that they are
  // used, once per leg, and only from the calling thread.
  const std::thread::id caller = std::this_thread::get_id();
  int matrix_calls = 0;
  int path_calls = 0;
  bool other_thread = false;
  GeodesicProvider provider;
  provider.distance_matrix = [&](const std::vector<Eigen::Vector2d>& pts, DistanceMatrix* out) {
    other_thread |= std::this_thread::get_id() != caller;
    ++matrix_calls;
    const int n = static_cast<int>(pts.size());
    *out = DistanceMatrix(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) (*out)(a, b) = (pts[a] - pts[b]).norm();
    return true;
  };
  provider.shortest_path = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                               std::vector<Eigen::Vector2d>* out) {
    other_thread |= std::this_thread::get_id() != caller;
    ++path_calls;
    *out = {a, b};
    return true;
  };
  PlannerOptions options;
  options.optimize_paths = false;  // straight legs through walls would not smooth
  PlanResult result;
  ASSERT_TRUE(PlanOmt(raster_, &clearance_, Robots(), options, &result, &provider).ok());
  EXPECT_EQ(matrix_calls, 1);
  int legs = 0;
  for (const RobotPlan& plan : result.robots) legs += static_cast<int>(plan.tasks.size());
  EXPECT_GT(legs, 0);
  EXPECT_EQ(path_calls, legs);
  EXPECT_FALSE(other_thread);
  // A failing provider is reported, not hidden.
  provider.distance_matrix = [](const std::vector<Eigen::Vector2d>&, DistanceMatrix*) {
    return false;
  };
  EXPECT_EQ(PlanOmt(raster_, &clearance_, Robots(), options, &result, &provider).code,
            Status::Code::kInvalidInput);
}

TEST(OmtPlannerInput, RejectsMismatchedRasterAndEmptyTeam) {
  OccupancyRaster r = testing::MakeRaster(2.0, 2.0, 0.05, Cell::kFree);
  PlanResult result;
  EXPECT_EQ(PlanOmt(r, nullptr, {}, PlannerOptions{}, &result).code, Status::Code::kInvalidInput);
  r.cells.pop_back();
  EXPECT_EQ(PlanOmt(r, nullptr, Robots(), PlannerOptions{}, &result).code,
            Status::Code::kInvalidInput);
}

TEST(OmtPlannerInput, ExploredSceneTerminates) {
  OccupancyRaster r = testing::MakeApartment(10.0, 6.0, 0.05, /*known_x_m=*/10.0);
  for (float& w : r.tsdf_weight) w = 50.0f;  // everything scanned well
  PlanResult result;
  ASSERT_TRUE(PlanOmt(r, nullptr, Robots(), PlannerOptions{}, &result).ok());
  EXPECT_TRUE(result.terminated);
}

}  // namespace
}  // namespace voxplan::omt
