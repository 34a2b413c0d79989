// `voxplan fuse` on poses it must not trust, as a user would run it: frames in a ground-truth
// gap and frames with an absurd pose are skipped, warned and counted in the stats, and
// --max-pose-gap is validated before any work.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "io/image_io.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::RunCli;
using test::RunResult;

void WriteText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// Six 16 x 12 frames of a wall 1.5 m away at t = 0.0, 0.1, ... 0.4 and 0.45 s; ground truth
// every 0.05 s up to 0.1 s, then nothing until 0.4 s (frames 0.2 and 0.3 lie in that gap), and
// an absurd pose at 0.45 s.
void MakeTum(const fs::path& root) {
  std::string depth;
  fs::create_directories(root / "depth");
  for (const char* t : {"0.0", "0.1", "0.2", "0.3", "0.4", "0.45"}) {
    const std::string name = "depth/" + std::string(t) + ".png";
    ASSERT_TRUE(WriteDepthPng16((root / name).string(), DepthImage(16, 12, 1.5f), 5000).ok());
    depth += std::string(t) + " " + name + "\n";
  }
  WriteText(root / "depth.txt", depth);
  WriteText(root / "camera.txt", "12 12 7.5 5.5\n");
  WriteText(root / "groundtruth.txt",
            "0.00 0 0 0 0 0 0 1\n0.05 0 0 0 0 0 0 1\n0.10 0 0 0 0 0 0 1\n"
            "0.40 0 0 0 0 0 0 1\n0.45 1e7 0 0 0 0 0 1\n");
}

TEST(FusePosesCli, GapAndAbsurdPosesAreSkippedAndCounted) {
  const test::TempDir dir("voxplan-poses-cli");
  MakeTum(dir / "tum");
  const fs::path stats = dir / "stats.json";
  const RunResult r = RunCli({"fuse", (dir / "tum").string(), "--voxel-size", "0.02", "--threads",
                              "1", "--stats", stats.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const auto& j = r.last_json;
  EXPECT_EQ(j.at("frames").get<int>(), 3) << Describe(r);
  EXPECT_EQ(j.at("frames_skipped_pose_gap").get<int>(), 2) << Describe(r);
  EXPECT_EQ(j.at("frames_skipped_bad_pose").get<int>(), 1) << Describe(r);
  EXPECT_EQ(j.at("frames_skipped").get<int>(), 3) << Describe(r);
  EXPECT_NE(r.err.find("fused 3 frames (3 skipped)"), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find("warning: 2 depth frames have no pose: they lie in gaps"), std::string::npos)
      << Describe(r);
  EXPECT_NE(r.err.find("pose translation 1e+07 m is beyond"), std::string::npos) << Describe(r);

  // A bound above the gap interpolates across it again.
  const RunResult wide =
      RunCli({"fuse", (dir / "tum").string(), "--voxel-size", "0.02", "--max-pose-gap", "0.5"});
  ASSERT_EQ(wide.exit_code, 0) << Describe(wide);
  EXPECT_EQ(wide.last_json.at("frames_skipped_pose_gap").get<int>(), 0) << Describe(wide);
  EXPECT_EQ(wide.last_json.at("frames").get<int>(), 5) << Describe(wide);
}

TEST(FusePosesCli, MaxPoseGapMustBePositiveAndFinite) {
  const test::TempDir dir("voxplan-poses-cli");
  MakeTum(dir / "tum");
  for (const char* bad : {"0", "-1", "nan", "inf"}) {
    const RunResult r = RunCli({"fuse", (dir / "tum").string(), "--max-pose-gap", bad});
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << Describe(r);
    EXPECT_NE(r.err.find("--max-pose-gap"), std::string::npos) << Describe(r);
  }
}

}  // namespace
}  // namespace voxplan
