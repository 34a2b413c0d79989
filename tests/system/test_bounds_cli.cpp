// Numeric options out of range are refused (exit 2) before any work, with the option and the
// range in the message, and the memory budget of `fuse` holds: past it new blocks are dropped
// and counted, or with --on-memory-limit fail the run stops (exit 1) naming the budget.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::RunCli;
using test::RunResult;

using test::IclDir;
fs::path KitchenDir() { return test::SharedDataDir() / "rgbd" / "7scenes_redkitchen"; }

// Runs the command and expects a usage error, quickly, whose message holds every `expected`.
void ExpectRefused(const std::vector<std::string>& args, const std::vector<std::string>& expected) {
  const auto start = std::chrono::steady_clock::now();
  const RunResult r = RunCli(args);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  for (const std::string& e : expected) EXPECT_NE(r.err.find(e), std::string::npos) << Describe(r);
  EXPECT_LT(seconds, 10.0) << Describe(r);  // refused before any work, never a spin
}

TEST(BoundsCliTest, VoxelSizeAndTruncation) {
  const std::string icl = IclDir().string();
  ExpectRefused({"fuse", icl, "--voxel-size", "1e-9"}, {"--voxel-size", "[0.001, 1] m"});
  ExpectRefused({"fuse", icl, "--voxel-size", "1e-4"}, {"--voxel-size", "[0.001, 1] m"});
  ExpectRefused({"fuse", icl, "--voxel-size", "nan"}, {"--voxel-size", "[0.001, 1] m"});
  ExpectRefused({"fuse", icl, "--trunc", "1000"}, {"--trunc", "[0.001, 64] m"});
  // Within the metres range but not within 1-64 voxels of this voxel size.
  ExpectRefused({"fuse", icl, "--voxel-size", "0.01", "--trunc", "5"},
                {"--trunc", "[1, 64] voxels", "[0.01, 0.64] m"});
  ExpectRefused({"bench", "fusion", icl, "--voxel-size", "1e-4"}, {"--voxel-size", "[0.001, 1]"});
  ExpectRefused({"demo", "--voxel-size", "1e-9"}, {"--voxel-size", "[0.001, 1]"});
}

TEST(BoundsCliTest, DepthThreadsFramesAndScales) {
  const std::string icl = IclDir().string();
  ExpectRefused({"fuse", icl, "--max-depth", "1e9"}, {"--max-depth", "[0, 100] m"});
  ExpectRefused({"fuse", icl, "--min-depth", "inf"}, {"--min-depth", "[0, 100] m"});
  ExpectRefused({"fuse", icl, "--threads", "100000"}, {"--threads", "[0, 1024]"});
  ExpectRefused({"fuse", icl, "--frames", "-1"}, {"--frames"});
  ExpectRefused({"fuse", icl, "--depth-scale", "1e300"}, {"--depth-scale", "[0.01, 1e+06]"});
  ExpectRefused({"fuse", icl, "--max-weight", "1000"}, {"--max-weight", "511.99"});
  ExpectRefused({"eval", "mesh", "a.ply", "b.ply", "--samples-per-m2", "1e12"},
                {"--samples-per-m2", "[1, 1e+06]"});
}

TEST(BoundsCliTest, IntrinsicsAgainstTheImageSize) {
  // fx = 1 on 640-pixel-wide images: a 179.6 degree field of view.
  ExpectRefused({"fuse", IclDir().string(), "--intrinsics", "1,1,320,240"},
                {"--intrinsics", "|fx|", "[64, 64000] pixels"});
  ExpectRefused({"fuse", IclDir().string(), "--intrinsics", "525,525,5000,240"},
                {"--intrinsics", "cx", "[0, 640] pixels"});
  // The same from a dataset's camera file: a 7-Scenes folder whose camera-intrinsics.txt says
  // fx = fy = 1 (its frames linked from the shared data).
  const test::TempDir dir("voxplan-bounds-camera");
  for (const char* name :
       {"frame-000000.depth.png", "frame-000000.color.jpg", "frame-000000.pose.txt"})
    fs::create_symlink(KitchenDir() / name, dir / name);
  std::ofstream(dir / "camera-intrinsics.txt") << "1 0 320\n0 1 240\n0 0 1\n";
  ExpectRefused({"fuse", dir.path().string()}, {"camera-intrinsics.txt", "|fx|", "[64, 64000]"});
}

TEST(BoundsCliTest, RenderSizesAndNaN) {
  const test::TempDir dir("voxplan-bounds-render");
  const std::string mesh = (dir / "m.ply").string(), out = (dir / "out").string();
  std::ofstream(mesh) << "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  ExpectRefused({"render", mesh, "--size", "100000x100", "--out", out}, {"--size", "16384"});
  ExpectRefused({"render", mesh, "--size", "16000x16000", "--out", out}, {"67108864 pixels"});
  ExpectRefused({"render", mesh, "--fov-deg", "nan", "--out", out}, {"--fov-deg", "[1, 179]"});
  ExpectRefused({"render", mesh, "--orbit-height", "nan", "--out", out},
                {"--orbit-height", "[-10000, 10000] m"});
  ExpectRefused({"render", mesh, "--orbit-radius", "inf", "--out", out}, {"--orbit-radius"});
  ExpectRefused({"render", mesh, "--near", "nan", "--out", out}, {"--near"});
  ExpectRefused(
      {"explore", "--scene", "apartment", "--planner", "greedy", "--out", out, "--width", "100000"},
      {"--width", "[1, 16384] pixels"});
  ExpectRefused({"sim", "render", "--scene", mesh, "--trajectory", mesh, "--out", out, "--fx", "1"},
                {"--fx", "|fx|"});
}

TEST(BoundsCliTest, MemorySizes) {
  const std::string icl = IclDir().string();
  ExpectRefused({"fuse", icl, "--max-memory", "lots"}, {"--max-memory", "not a memory size"});
  ExpectRefused({"fuse", icl, "--max-memory", "1K"}, {"--max-memory", "[1M, 1024T]"});
  ExpectRefused({"fuse", icl, "--on-memory-limit", "swap"}, {"--on-memory-limit"});
}

// ICL-NUIM at 5 mm: 20 frames need far more than 16 MiB of blocks.
std::vector<std::string> TightFuse(const fs::path& stats) {
  return {"fuse",         IclDir().string(),
          "--frames",     "20",
          "--voxel-size", "0.005",
          "--trunc",      "0.02",
          "--threads",    "2",
          "--max-memory", "16M",
          "--stats",      stats.string()};
}

TEST(BoundsCliTest, MemoryBudgetDropsBlocksAndCountsThem) {
  const test::TempDir dir("voxplan-bounds-budget");
  const RunResult r = RunCli(TightFuse(dir / "stats.json"));
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const nlohmann::json& j = r.last_json;
  ASSERT_TRUE(j.is_object()) << Describe(r);
  EXPECT_EQ(j.at("max_memory_mb").get<double>(), 16.0);
  EXPECT_GT(j.at("blocks_refused").get<int>(), 0);
  EXPECT_GT(j.at("frames_over_budget").get<int>(), 0);
  EXPECT_LE(j.at("map_mb").get<double>(), 16.0);
  EXPECT_GT(j.at("blocks").get<int>(), 1000);  // the budget was used, not refused up front
  // One warning, naming the budget, for the whole run.
  const std::string warning = "warning: memory budget of 16 MiB reached";
  const size_t first = r.err.find(warning);
  ASSERT_NE(first, std::string::npos) << Describe(r);
  EXPECT_EQ(r.err.find(warning, first + 1), std::string::npos) << Describe(r);
}

TEST(BoundsCliTest, MemoryBudgetFailStops) {
  const test::TempDir dir("voxplan-bounds-budget-fail");
  std::vector<std::string> args = TightFuse(dir / "stats.json");
  args.push_back("--on-memory-limit");
  args.push_back("fail");
  const RunResult r = RunCli(args);
  EXPECT_EQ(r.exit_code, 1) << Describe(r);
  EXPECT_NE(r.err.find("error: "), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find("memory budget of 16 MiB reached"), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(dir / "stats.json"));
}

}  // namespace
}  // namespace voxplan
