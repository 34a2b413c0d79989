// The tensorfield planner (Xu 2017) closed in the exploration loop on one generated room
// (apartment size R, Xu's scenes): it drives on field-guided continuous paths, called one
// sub-step at a time, and ends `done` well before the time limit with the floor covered.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "explore/explore.h"
#include "plugins/host/plugin_host.h"
#include "sim/apartment.h"
#include "sim/floor_plan.h"

namespace voxplan {
namespace {

TEST(TensorfieldLoop, ASingleRoomEndsDoneWithTheFloorCovered) {
  constexpr double kMinCoverage = 0.95;  // reached: see the run below
  ApartmentParams ap;
  ap.size = ApartmentSize::kR;
  ap.seed = 2;
  Result<World> world = GenerateApartment(ap);
  ASSERT_TRUE(world.ok()) << world.status().message();
  Result<FloorPlan> plan = RasterizeFloorPlan(*world);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  ExploreParams params;
  params.image_width = 160;
  params.image_height = 120;
  params.noise = false;
  params.max_time_s = 300.0;
  params.seed = 1;
  Result<std::vector<Eigen::Vector2f>> starts =
      ChooseStarts(*plan, world->rooms, 1, params.robot.radius_m);
  ASSERT_TRUE(starts.ok()) << starts.status().message();
  Result<std::unique_ptr<LoadedPlanner>> planner =
      LoadPlanner(VOXPLAN_TENSORFIELD_PLANNER,
                  {.config_json = "{}", .seed = 1, .search_path = {}, .limits = {}});
  ASSERT_TRUE(planner.ok()) << planner.status().message();
  Result<ExploreResult> run = RunExplore(*world, *plan, *starts, **planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  EXPECT_EQ(run->terminated, "done") << "stopped at t=" << run->time_s;
  EXPECT_LT(run->time_s, params.max_time_s);
  ASSERT_FALSE(run->series.empty());
  EXPECT_GE(run->series.back().coverage, kMinCoverage);
  // Driven on the planner's continuous paths, re-planned every sub-step: wakeup calls dominate.
  int wakeups = 0;
  for (const PlanCallRecord& c : run->plan_calls) wakeups += c.event == PlanEvent::kWakeup;
  EXPECT_GT(wakeups, int(run->plan_calls.size()) / 2);
  EXPECT_EQ(run->failed_plans, 0u);
}

}  // namespace
}  // namespace voxplan
