// `voxplan fuse --prefetch N`: frames decoded ahead change no byte of what is written, at 1 and 2
// threads; a frame that cannot be decoded fails the run with the same message whatever is
// decoded ahead, and nothing is written.
#include <gtest/gtest.h>

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
using test::ReadAll;
using test::RunCli;
using test::RunResult;

fs::path Kitchen() { return test::SharedDataDir() / "rgbd" / "7scenes_redkitchen"; }
using test::IclDir;

TEST(FusePrefetchCli, PrefetchingWritesTheSameBytes) {
  const test::TempDir dir("voxplan-prefetch-cli");
  std::string mesh0, map0;
  for (const std::string threads : {"1", "2"})
    for (const std::string prefetch : {"0", "3", "16"}) {
      const std::string tag = threads + "_" + prefetch;
      const fs::path mesh = dir / ("k" + tag + ".ply"), map = dir / ("k" + tag + ".vpmap");
      const RunResult r =
          RunCli({"fuse", Kitchen().string(), "--frames", "40", "--stride", "2", "--voxel-size",
                  "0.03", "--trunc", "0.12", "--threads", threads, "--prefetch", prefetch, "--mesh",
                  mesh.string(), "--map", map.string()});
      ASSERT_EQ(r.exit_code, 0) << Describe(r);
      EXPECT_EQ(r.last_json["frames"], 40) << Describe(r);
      if (mesh0.empty()) {
        mesh0 = ReadAll(mesh);
        map0 = ReadAll(map);
        ASSERT_GT(mesh0.size(), 1000u);
      }
      EXPECT_TRUE(ReadAll(mesh) == mesh0) << tag;
      EXPECT_TRUE(ReadAll(map) == map0) << tag;
    }
  const RunResult bad = RunCli({"fuse", Kitchen().string(), "--prefetch", "65"});
  EXPECT_EQ(bad.exit_code, 2) << Describe(bad);
}

TEST(FusePrefetchCli, ABadFrameFailsTheRunTheSameWayWithNothingWritten) {
  const test::TempDir dir("voxplan-prefetch-bad");
  const fs::path broken = dir / "icl";
  test::CopyIclFrames(broken, 14);
  const fs::path bad = broken / "rgb" / "9.jpg";  // colour this time; frame 8
  fs::resize_file(bad, fs::file_size(bad) / 2);
  std::string first_error;
  for (const std::string prefetch : {"0", "2", "8"}) {
    const fs::path mesh = dir / "out.ply", map = dir / "out.vpmap", stats = dir / "out.json";
    const RunResult r = RunCli({"fuse", broken.string(), "--voxel-size", "0.05", "--trunc", "0.2",
                                "--threads", "2", "--prefetch", prefetch, "--mesh", mesh.string(),
                                "--map", map.string(), "--stats", stats.string()});
    EXPECT_EQ(r.exit_code, 1) << Describe(r);
    const size_t at = r.err.find("error: ");
    ASSERT_NE(at, std::string::npos) << Describe(r);
    const std::string error = r.err.substr(at, r.err.find('\n', at) - at);
    EXPECT_NE(error.find("frame 8: " + bad.string()), std::string::npos) << error;
    if (first_error.empty()) first_error = error;
    EXPECT_EQ(error, first_error) << "prefetch " << prefetch;
    EXPECT_FALSE(fs::exists(mesh));
    EXPECT_FALSE(fs::exists(map));
    EXPECT_FALSE(fs::exists(stats));
    EXPECT_TRUE(r.last_json.is_null());
    size_t leftovers = 0;  // no temporary file left either
    for (const auto& e : fs::directory_iterator(dir.path())) leftovers += e.is_regular_file();
    EXPECT_EQ(leftovers, 0u);
  }
}

}  // namespace
}  // namespace voxplan
