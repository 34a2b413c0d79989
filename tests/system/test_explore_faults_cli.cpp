// `voxplan explore` with a planner that crashes or hangs (tests/plugins/planners/faulty.cpp):
// the run ends with exit 3 and a clear error, metrics.json says planner_crashed / planner_hung
// with the call that did it, and every other output is there and readable. A planner file that
// is not a whole shared object is refused before anything runs.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
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

// `timeout` turns a regression (a run that hangs with its planner) into a failure.
const std::string kGuard = "timeout 120";

// A tiny run: one robot, 30 simulated seconds, coarse voxels and small images.
std::vector<std::string> TinyRun(const fs::path& config, const fs::path& out) {
  return {"explore",
          "--scene",
          "apartment:size=S,seed=1",
          "--robots",
          "1",
          "--planner",
          VOXPLAN_FAULTY_PLANNER,
          "--planner-config",
          config.string(),
          "--max-time",
          "30",
          "--voxel-size",
          "0.1",
          "--width",
          "80",
          "--height",
          "60",
          "--eval-samples",
          "20",
          "--no-noise",
          "--out",
          out.string()};
}

fs::path Config(const test::TempDir& dir, const std::string& json) {
  const fs::path path = dir / "config.json";
  std::ofstream(path) << json;
  return path;
}

size_t Lines(const std::string& text) {
  size_t n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) n += line.empty() ? 0 : 1;
  return n;
}

// Every output of the run exists and is readable; returns metrics.json.
nlohmann::json ExpectOutputs(const fs::path& out, size_t plan_calls) {
  for (const char* f : {"mesh.ply", "metrics.json", "timeseries.csv", "run_log.csv", "topdown.png",
                        "plan_log.txt", "plan_calls.csv"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  EXPECT_EQ(ReadAll(out / "mesh.ply").rfind("ply\n", 0), 0u);
  EXPECT_EQ(ReadAll(out / "topdown.png").substr(1, 3), "PNG");
  EXPECT_GT(Lines(ReadAll(out / "run_log.csv")), 1u);
  EXPECT_EQ(Lines(ReadAll(out / "plan_calls.csv")), 1 + plan_calls);  // header + calls
  const nlohmann::json m =
      nlohmann::json::parse(ReadAll(out / "metrics.json"), nullptr, /*allow_exceptions=*/false);
  EXPECT_TRUE(m.is_object());
  EXPECT_EQ(m.value("plan_calls", 0u), plan_calls);
  EXPECT_GT(m.value("frames_fused", 0u), 0u);  // the start sweep was recorded
  return m;
}

TEST(ExploreFaultsCli, ACrashingPlannerEndsTheRunWithExit3AndEveryOutput) {
  test::TempDir dir("explore_crash");
  const fs::path out = dir / "out";
  const RunResult r = RunCli(TinyRun(Config(dir, R"({"fault": "null", "call": 1})"), out), kGuard);
  ASSERT_EQ(r.exit_code, 3) << Describe(r);
  EXPECT_NE(r.err.find("error: planner faulty crashed (SIGSEGV) in plan call 1 ("),
            std::string::npos)
      << Describe(r);
  EXPECT_NE(r.err.find("its outputs are in " + out.string()), std::string::npos) << Describe(r);
  ASSERT_TRUE(r.last_json.is_object()) << Describe(r);
  EXPECT_EQ(r.last_json.value("terminated", ""), "planner_crashed");
  const nlohmann::json m = ExpectOutputs(out, 2);
  EXPECT_EQ(m.value("terminated", ""), "planner_crashed");
  const nlohmann::json f = m.value("planner_fault", nlohmann::json::object());
  EXPECT_EQ(f.value("call", ""), "plan");
  EXPECT_EQ(f.value("call_index", -1), 1);
  EXPECT_EQ(f.value("signal", ""), "SIGSEGV");
  EXPECT_NE(ReadAll(out / "plan_log.txt").find("crashed (SIGSEGV) in plan call 1"),
            std::string::npos);
}

TEST(ExploreFaultsCli, AHangingPlannerIsGivenUpAtTheHardLimit) {
  test::TempDir dir("explore_hang");
  const fs::path out = dir / "out";
  std::vector<std::string> args = TinyRun(Config(dir, R"({"fault": "loop", "call": 0})"), out);
  for (const char* a :
       {"--plan-budget", "0.05", "--planner-hard-limit", "4", "--planner-hard-limit-min", "0.3"})
    args.push_back(a);
  const RunResult r = RunCli(args, kGuard);
  ASSERT_EQ(r.exit_code, 3) << Describe(r);  // not 124: the spinning thread did not hold it
  EXPECT_NE(r.err.find("error: planner faulty hung in plan call 0 (start): no return within its "
                       "hard limit of 0.300 s"),
            std::string::npos)
      << Describe(r);
  const nlohmann::json m = ExpectOutputs(out, 1);
  EXPECT_EQ(m.value("terminated", ""), "planner_hung");
  const nlohmann::json f = m.value("planner_fault", nlohmann::json::object());
  EXPECT_EQ(f.value("event", ""), "start");
  EXPECT_TRUE(f.contains("signal") && f.at("signal").is_null());
  EXPECT_DOUBLE_EQ(f.value("hard_limit_s", 0.0), 0.3);
  EXPECT_GE(f.value("elapsed_s", 0.0), 0.3);
}

TEST(ExploreFaultsCli, ACrashInCreateExits3BeforeAnyOutput) {
  test::TempDir dir("explore_create_crash");
  const RunResult r =
      RunCli(TinyRun(Config(dir, R"({"fault": "abort", "in": "create"})"), dir / "out"), kGuard);
  EXPECT_EQ(r.exit_code, 3) << Describe(r);
  EXPECT_NE(r.err.find("crashed (SIGABRT) in create"), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(ExploreFaultsCli, RefusesBadHardLimitsAndFilesThatAreNotSharedObjects) {
  test::TempDir dir("explore_planner_file");
  const fs::path config = Config(dir, "{}");
  for (const auto& [option, value, expect] : std::vector<std::array<std::string, 3>>{
           {"--planner-hard-limit", "0.5", "--planner-hard-limit must be a factor >= 1"},
           {"--planner-hard-limit", "nan", "--planner-hard-limit must be"},
           {"--planner-hard-limit-min", "0", "--planner-hard-limit-min must be a finite"}}) {
    std::vector<std::string> args = TinyRun(config, dir / "out");
    args.push_back(option);
    args.push_back(value);
    const RunResult r = RunCli(args, kGuard);
    EXPECT_EQ(r.exit_code, 2) << Describe(r);
    EXPECT_NE(r.err.find(expect), std::string::npos) << Describe(r);
  }
  // Half a real planner: dlopen would map pages past its end and die of SIGBUS.
  const std::string whole = ReadAll(VOXPLAN_FAULTY_PLANNER);
  const fs::path cut = dir / "libvoxplan_planner_cut.so";
  std::ofstream(cut, std::ios::binary) << whole.substr(0, whole.size() / 2);
  std::vector<std::string> args = TinyRun(config, dir / "out");
  args[6] = cut.string();  // --planner
  const RunResult r = RunCli(args, kGuard);
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("error: " + cut.string() + ": not a shared object for this machine: "),
            std::string::npos)
      << Describe(r);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

}  // namespace
}  // namespace voxplan
