// Short, coarse experiments for the explore tests: the greedy planner the CMake target names and
// a run a few seconds of wall time long.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>

#include "explore/explore_run.h"

namespace voxplan::test {

inline std::unique_ptr<LoadedPlanner> GreedyPlanner() {
  Result<std::unique_ptr<LoadedPlanner>> planner =
      LoadPlanner(VOXPLAN_EXPLORE_TEST_PLANNER,
                  {.config_json = "{}", .seed = 5, .search_path = {}, .limits = {}});
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

// 10 cm voxels, 160 x 120 images, seed 5, 50 evaluation samples per m².
inline ExploreRunParams CoarseRun(const std::string& scene, int robots, double max_time_s,
                                  const std::filesystem::path& out) {
  ExploreRunParams p;
  p.scene = scene;
  p.robots = robots;
  p.explore.voxel_size_m = 0.1f;
  p.explore.image_width = 160;
  p.explore.image_height = 120;
  p.explore.max_time_s = max_time_s;
  p.explore.seed = 5;
  p.eval_samples_per_m2 = 50.0;
  p.out_dir = out.string();
  return p;
}

}  // namespace voxplan::test
