// `voxplan explore` run as a user would: a short run writes every output and repeats itself
// byte for byte; an unknown planner lists the available ones; a camera out of range and robots
// that cannot be placed are refused before the run.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

// A short, coarse run: 60 simulated seconds on a small apartment.
std::vector<std::string> ShortRun(const fs::path& out) {
  return {"explore",
          "--scene",
          "apartment:size=S,seed=1",
          "--robots",
          "2",
          "--planner",
          "greedy",
          "--max-time",
          "60",
          "--voxel-size",
          "0.1",
          "--width",
          "160",
          "--height",
          "120",
          "--seed",
          "5",
          "--progress-interval",
          "10",
          "--eval-samples",
          "50",
          "--out",
          out.string()};
}

TEST(ExploreCli, ShortRunWritesEveryOutputAndRepeatsItself) {
  test::TempDir dir("explore_cli");
  std::vector<nlohmann::json> metrics;
  for (const char* sub : {"a", "b"}) {
    const RunResult r = RunCli(ShortRun(dir / sub));
    ASSERT_EQ(r.exit_code, 0) << Describe(r);
    ASSERT_TRUE(r.last_json.is_object()) << Describe(r);
    EXPECT_NE(r.err.find("explore: t="), std::string::npos) << "no progress line\n" << r.err;
    for (const char* f : {"mesh.ply", "metrics.json", "timeseries.csv", "run_log.csv",
                          "topdown.png", "plan_log.txt", "plan_calls.csv"})
      EXPECT_TRUE(fs::is_regular_file(dir / sub / f)) << f;
    metrics.push_back(nlohmann::json::parse(ReadAll(dir / sub / "metrics.json")));
  }
  nlohmann::json& m = metrics[0];
  for (const char* key :
       {"completeness", "accuracy_rms_m", "distance_per_robot_m", "distance_total_m",
        "distance_per_area", "load_balance_cov", "time_s", "idle_time_s", "plan_ms_median",
        "plan_calls", "terminated", "camera_position_clamped_workspace",
        "camera_position_clamped_speed", "unobserved_m3_start", "unobserved_m3_final",
        "unobserved_area_fraction", "mean_uncertainty_final"})
    EXPECT_TRUE(m.contains(key)) << key;
  const std::string terminated = m["terminated"].get<std::string>();
  EXPECT_TRUE(terminated == "done" || terminated == "time_limit") << terminated;
  EXPECT_LE(m["time_s"].get<double>(), 60.0 + 1.0);  // the last robot step may overrun
  EXPECT_EQ(m["distance_per_robot_m"].size(), 2u);
  EXPECT_GT(m["completeness"].get<double>(), 0.0);

  // Same arguments, same bytes: everything but the plan calls' wall time.
  for (nlohmann::json& j : metrics) {
    j.erase("plan_ms_median");
    j.erase("plan_ms_p90");
  }
  EXPECT_EQ(metrics[0], metrics[1]);
  for (const char* f : {"run_log.csv", "timeseries.csv", "mesh.ply", "topdown.png"})
    EXPECT_EQ(ReadAll(dir / "a" / f), ReadAll(dir / "b" / f)) << f;
}

TEST(ExploreCli, EvalScoresTheRunAgainstItsOwnWorldAndRefusesAnother) {
  test::TempDir dir("explore_cli_world");
  std::vector<std::string> args = ShortRun(dir / "run");
  const RunResult run = RunCli(args);
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const std::string log = (dir / "run" / "run_log.csv").string();
  const std::string mesh = (dir / "run" / "mesh.ply").string();
  const std::string own = (dir / "run" / "world.ply").string();
  const RunResult scored = RunCli({"eval", "run", log, "--scene", own});
  EXPECT_EQ(scored.exit_code, 0) << Describe(scored);
  const RunResult objects =
      RunCli({"eval", "objects", mesh, "--scene", own, "--samples-per-m2", "200"});
  EXPECT_EQ(objects.exit_code, 0) << Describe(objects);
  EXPECT_NE(objects.err.find("steps (100%)"), std::string::npos) << "no progress\n" << objects.err;
  // Another seed's apartment: refused with the reason, unless asked to score it anyway.
  const RunResult other_world =
      RunCli({"sim", "scene", "--generate", "apartment", "--size", "S", "--seed", "2", "--no-glb",
              "--out", (dir / "other").string()});
  ASSERT_EQ(other_world.exit_code, 0) << Describe(other_world);
  const std::string other = (dir / "other" / "world.ply").string();
  for (const std::vector<std::string>& cmd :
       {std::vector<std::string>{"eval", "run", log, "--scene", other},
        std::vector<std::string>{"eval", "objects", mesh, "--scene", other}}) {
    const RunResult refused = RunCli(cmd);
    EXPECT_EQ(refused.exit_code, 1) << Describe(refused);
    EXPECT_NE(refused.err.find("not the world this run explored"), std::string::npos)
        << refused.err;
  }
  const RunResult forced = RunCli({"eval", "run", log, "--scene", other, "--any-world"});
  EXPECT_EQ(forced.exit_code, 0) << Describe(forced);
  EXPECT_NE(forced.err.find("warning: the scene is not the world"), std::string::npos)
      << forced.err;
}

TEST(ExploreCli, UnknownPlannerListsTheAvailableOnes) {
  test::TempDir dir("explore_cli_planner");
  const RunResult r = RunCli({"explore", "--scene", "apartment:size=S,seed=1", "--planner",
                              "no_such_planner", "--out", (dir / "out").string()});
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("unknown planner 'no_such_planner'; available:"), std::string::npos)
      << Describe(r);
  EXPECT_NE(r.err.find("greedy"), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(ExploreCli, RefusesACameraItCannotSimulate) {
  test::TempDir dir("explore_cli_camera");
  for (const auto& [option, value, expect] : std::vector<std::array<std::string, 3>>{
           {"--fov-deg", "0", "--fov-deg must lie strictly between 1 and 179 degrees, got 0"},
           {"--fov-deg", "180", "--fov-deg must lie strictly between 1 and 179"},
           {"--fov-deg", "nan", "--fov-deg must lie"},
           {"--max-range-m", "0.05", "--max-range-m must be a finite number of metres above 0.1"},
           {"--max-range-m", "inf", "--max-range-m must be"},
           {"--capture-hz", "-1",
            "--capture-hz must be 0 (capture by displacement) or a rate up to 60"},
           {"--capture-hz", "61", "--capture-hz must be"},
           {"--capture-hz", "nan", "--capture-hz must be"},
           {"--recon-voxel-size", "-0.02", "--recon-voxel-size must be 0 (none) or between"},
           {"--recon-voxel-size", "nan", "--recon-voxel-size must be"}}) {
    const RunResult r = RunCli({"explore", "--scene", "apartment:size=S,seed=1", "--planner",
                                "greedy", option, value, "--out", (dir / "out").string()});
    EXPECT_EQ(r.exit_code, 2) << Describe(r);
    EXPECT_NE(r.err.find(expect), std::string::npos) << Describe(r);
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(ExploreCli, RefusesRobotsThatCannotBePlaced) {
  test::TempDir dir("explore_cli_start");
  // (-50, -50) lies outside the apartment; so does a malformed list and a count mismatch.
  for (const auto& [start, expect] : std::vector<std::pair<std::string, std::string>>{
           {"-50,-50", "robot 0 cannot start at (-50.00, -50.00)"},
           {"1,2;x", "--start wants"},
           {"1,2;3,4", "2 positions for 1 robots"}}) {
    const RunResult r =
        RunCli({"explore", "--scene", "apartment:size=S,seed=1", "--planner", "greedy", "--robots",
                "1", "--start", start, "--out", (dir / "out").string()});
    EXPECT_EQ(r.exit_code, 2) << Describe(r);
    EXPECT_NE(r.err.find(expect), std::string::npos) << Describe(r);
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace voxplan
