// A scene whose floor is not at z = 0 (SceneLoadOptions::detect_floor, `--floor-z auto`): a small
// apartment written as a scene file once as it is and once raised by 0.875 m runs the same
// exploration when the raised one is loaded with its floor detected, and metrics.json records
// the height the run's world was moved down by.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "explore/explore_run.h"
#include "explore/run_outputs.h"
#include "sim/apartment.h"
#include "sim/world_io.h"
#include "tests/explore/explore_test_runs.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

std::unique_ptr<LoadedPlanner> Greedy() { return test::GreedyPlanner(); }

ExploreRunParams ShortRun(const std::string& scene, const fs::path& out) {
  return test::CoarseRun(scene, 1, 40.0, out);
}

TEST(ExploreFloorOffset, RaisedSceneRunsAsTheSceneAtZeroFloor) {
  test::TempDir dir("explore_floor");
  ApartmentParams ap;
  ap.size = ApartmentSize::kS;
  ap.seed = 1;
  Result<World> generated = GenerateApartment(ap);
  ASSERT_TRUE(generated.ok()) << generated.status().message();
  // Coordinates on a 1/1024 m grid and a raise of 0.875 m: both moves are exact in float, so the
  // raised world moved back down is the flat one bit for bit and the two runs must agree.
  World flat = std::move(generated).value();
  for (Eigen::Vector3f& p : flat.mesh.positions) p = (p * 1024.f).array().round() / 1024.f;
  const float raise = 0.875f;
  World raised = flat;
  for (Eigen::Vector3f& p : raised.mesh.positions) p.z() += raise;
  fs::create_directories(dir / "flat");
  fs::create_directories(dir / "raised");
  ASSERT_TRUE(WriteWorld(flat, (dir / "flat").string()).ok());
  ASSERT_TRUE(WriteWorld(raised, (dir / "raised").string()).ok());
  const std::string flat_file = (dir / "flat" / "world.ply").string();
  const std::string raised_file = (dir / "raised" / "world.ply").string();

  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  ExploreRunParams flat_params = ShortRun(flat_file, dir / "flat_run");
  Result<ExploreRunReport> flat_run = RunExploreExperiment(flat_params, *planner);
  ASSERT_TRUE(flat_run.ok()) << flat_run.status().message();

  // As it is, the raised scene has no floor under the robots' band: nowhere to start.
  ExploreRunParams as_is = ShortRun(raised_file, dir / "as_is_run");
  planner = Greedy();
  ASSERT_NE(planner, nullptr);
  Result<ExploreRunReport> refused = RunExploreExperiment(as_is, *planner);
  EXPECT_FALSE(refused.ok());

  ExploreRunParams raised_params = ShortRun(raised_file, dir / "raised_run");
  raised_params.scene_load.detect_floor = true;
  planner = Greedy();
  ASSERT_NE(planner, nullptr);
  Result<ExploreRunReport> raised_run = RunExploreExperiment(raised_params, *planner);
  ASSERT_TRUE(raised_run.ok()) << raised_run.status().message();

  EXPECT_EQ(raised_run->scene_floor_z_m, raise);
  EXPECT_EQ(flat_run->scene_floor_z_m, 0.0f);
  EXPECT_EQ(raised_run->scene_area_m2, flat_run->scene_area_m2);
  EXPECT_GT(flat_run->scene_area_m2, 10.0);
  EXPECT_GT(flat_run->loop.frames_fused, 10u);
  EXPECT_GT(flat_run->metrics.distance_total_m, 1.0);
  EXPECT_GT(flat_run->quality.completeness, 0.1);
  EXPECT_EQ(raised_run->loop.frames_fused, flat_run->loop.frames_fused);
  EXPECT_EQ(raised_run->loop.plan_calls.size(), flat_run->loop.plan_calls.size());
  EXPECT_EQ(raised_run->mesh.num_triangles(), flat_run->mesh.num_triangles());
  EXPECT_EQ(raised_run->quality.completeness, flat_run->quality.completeness);
  EXPECT_EQ(raised_run->metrics.distance_total_m, flat_run->metrics.distance_total_m);
  // The robots' floor maps: the same cells.
  ASSERT_NE(raised_run->loop.floor, nullptr);
  ASSERT_NE(flat_run->loop.floor, nullptr);
  EXPECT_EQ(raised_run->loop.floor->cells(), flat_run->loop.floor->cells());

  // metrics.json: the same run, bar the scene's name, the recorded floor and wall times.
  auto metrics = [](const fs::path& out) {
    std::ifstream in(out / "metrics.json");
    return nlohmann::json::parse(in);
  };
  nlohmann::json a = metrics(dir / "flat_run"), b = metrics(dir / "raised_run");
  EXPECT_FALSE(a.contains("scene_floor_z_m"));
  ASSERT_TRUE(b.contains("scene_floor_z_m"));
  EXPECT_EQ(b["scene_floor_z_m"].get<double>(), double(raise));
  for (nlohmann::json* m : {&a, &b})
    for (const char* key : {"scene", "scene_floor_z_m", "plan_ms_median", "plan_ms_p90"})
      m->erase(key);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace voxplan
