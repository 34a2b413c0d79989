// System tests of the voxplan CLI: each runs the built executable as a user would and checks
// exit codes, the JSON last line, the files written and, on failure, the files not written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/map_io.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

using test::IclDir;

// A small valid map written through the library, for tests that need one without fusing.
void WriteSmallMap(const fs::path& path) {
  TsdfVolume volume(VolumeParams{0.05f, 0.2f});
  for (int x = -1; x <= 1; ++x) volume.FindOrAllocate(BlockIndex{x, 0, 0});
  ASSERT_TRUE(SaveMap(volume, path.string()).ok());
}

TEST(CliTest, HelpAndUsageErrors) {
  EXPECT_EQ(RunCli({"--help"}).exit_code, 0);
  const RunResult none = RunCli({});
  EXPECT_EQ(none.exit_code, 2) << Describe(none);
  EXPECT_NE(none.err.find("error:"), std::string::npos) << Describe(none);

  const RunResult format = RunCli({"fuse", IclDir().string(), "--format", "bogus"});
  EXPECT_EQ(format.exit_code, 2) << Describe(format);
  EXPECT_NE(format.err.find("error:"), std::string::npos);
  const RunResult kernel = RunCli({"fuse", IclDir().string(), "--kernel", "gpu"});
  EXPECT_EQ(kernel.exit_code, 2) << Describe(kernel);
}

TEST(CliTest, EveryCommandsHelpEndsWithExamplesAndVersionIsTheProjects) {
  for (const std::string path :
       {"fuse", "mesh", "info", "render", "eval mesh", "eval trajectory", "eval run",
        "eval objects", "demo", "bench fusion", "bench raycast", "bench mesh", "bench maps",
        "sim scene", "sim tour", "sim render", "explore"}) {
    std::vector<std::string> args;
    std::stringstream words(path);
    for (std::string w; words >> w;) args.push_back(w);
    args.push_back("--help");
    const RunResult r = RunCli(args);
    ASSERT_EQ(r.exit_code, 0) << Describe(r);
    // Each example is a command of this path as typed.
    EXPECT_NE(r.out.find("Examples:\n  voxplan " + path + " "), std::string::npos) << path << "\n"
                                                                                   << r.out;
  }
  const RunResult explore = RunCli({"explore", "--help"});
  EXPECT_NE(explore.out.find("Planners found:"), std::string::npos) << explore.out;
  EXPECT_NE(explore.out.find(" greedy"), std::string::npos) << explore.out;
  const RunResult version = RunCli({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out, "voxplan " VOXPLAN_TEST_VERSION "\n");
}

// One run covers fuse -> mesh -> info -> eval, so the 30-frame fusion is done only once.
TEST(CliTest, FuseIclThenMeshInfoAndEval) {
  const test::TempDir dir("voxplan-cli-fuse");
  const fs::path mesh = dir / "icl.ply", map = dir / "icl.vpmap", stats = dir / "icl.json";
  const RunResult fuse =
      RunCli({"fuse", IclDir().string(), "--frames", "30", "--voxel-size", "0.02", "--threads", "2",
              "--mesh", mesh.string(), "--map", map.string(), "--stats", stats.string()});
  ASSERT_EQ(fuse.exit_code, 0) << Describe(fuse);
  const json& j = fuse.last_json;
  ASSERT_TRUE(j.is_object()) << Describe(fuse);
  // ICL frame id 1 has no pose: skipped by the CLI or dropped by the reader.
  const int frames = j.at("frames").get<int>();
  EXPECT_TRUE(frames == 29 || frames == 30) << frames;
  EXPECT_EQ(frames + j.at("frames_skipped").get<int>(), j.at("frames_selected").get<int>());
  EXPECT_EQ(j.at("frames_selected").get<int>(), 30);
  EXPECT_DOUBLE_EQ(j.at("voxel_size_m").get<double>(), 0.02);
  EXPECT_EQ(j.at("threads").get<int>(), 2);
  EXPECT_GT(j.at("blocks").get<int>(), 0);
  EXPECT_GT(j.at("voxels").get<int>(), j.at("blocks").get<int>());
  EXPECT_GT(j.at("mesh_triangles").get<int>(), 1000);
  EXPECT_GT(j.at("mesh_vertices").get<int>(), 0);
  EXPECT_GT(j.at("integrate_ms_median").get<double>(), 0.0);
  EXPECT_GE(j.at("integrate_ms_p90").get<double>(), j.at("integrate_ms_median").get<double>());
  EXPECT_GT(j.at("load_ms_median").get<double>(), 0.0);
  EXPECT_GT(j.at("fps").get<double>(), 0.0);
  EXPECT_GT(j.at("map_mb").get<double>(), 0.0);
  EXPECT_GT(j.at("peak_rss_mb").get<double>(), 0.0);
  EXPECT_GT(j.at("bytes_per_voxel").get<double>(), 0.0);
  EXPECT_EQ(j.at("mesh").get<std::string>(), mesh.string());
  EXPECT_TRUE(fs::is_regular_file(mesh));
  EXPECT_TRUE(fs::is_regular_file(map));
  ASSERT_TRUE(fs::is_regular_file(stats));
  EXPECT_EQ(json::parse(ReadAll(stats)), j);

  // The map file alone gives back the same mesh.
  const fs::path remesh = dir / "remesh.glb";
  const RunResult mesh_run = RunCli({"mesh", map.string(), "--out", remesh.string()});
  ASSERT_EQ(mesh_run.exit_code, 0) << Describe(mesh_run);
  EXPECT_TRUE(fs::is_regular_file(remesh));
  EXPECT_EQ(mesh_run.last_json.at("mesh_triangles"), j.at("mesh_triangles"));
  EXPECT_EQ(mesh_run.last_json.at("blocks"), j.at("blocks"));

  const RunResult info = RunCli({"info", map.string()});
  ASSERT_EQ(info.exit_code, 0) << Describe(info);
  EXPECT_EQ(info.last_json.at("kind"), "map");
  EXPECT_EQ(info.last_json.at("blocks"), j.at("blocks"));
  EXPECT_NEAR(info.last_json.at("voxel_size_m").get<double>(), 0.02, 1e-6);
  EXPECT_GT(info.last_json.at("observed_voxels").get<int>(), 0);

  // A mesh scored against itself is exact and complete.
  const RunResult eval = RunCli({"eval", "mesh", mesh.string(), mesh.string(), "--threshold",
                                 "0.04", "--samples-per-m2", "200"});
  ASSERT_EQ(eval.exit_code, 0) << Describe(eval);
  EXPECT_LT(eval.last_json.at("accuracy_rms_m").get<double>(), 1e-3);
  EXPECT_GT(eval.last_json.at("completeness").get<double>(), 0.99);
  EXPECT_GT(eval.last_json.at("reconstruction_samples").get<int>(), 0);
}

TEST(CliTest, InfoOnDataset) {
  const RunResult info = RunCli({"info", IclDir().string()});
  ASSERT_EQ(info.exit_code, 0) << Describe(info);
  const json& j = info.last_json;
  EXPECT_EQ(j.at("kind"), "dataset");
  EXPECT_GE(j.at("frames").get<int>(), 199);
  EXPECT_EQ(j.at("camera").at("width").get<int>(), 640);
  EXPECT_FLOAT_EQ(j.at("camera").at("fy").get<float>(), -480.f);  // ICL's flipped y axis
  EXPECT_DOUBLE_EQ(j.at("depth_scale").get<double>(), 5000.0);
  EXPECT_NE(info.err.find("format"), std::string::npos);  // the table on stderr, as every summary
}

TEST(CliTest, MissingDatasetFolder) {
  const test::TempDir dir("voxplan-cli-missing");
  const fs::path missing = dir / "no_such_dataset", mesh = dir / "out.ply";
  const RunResult r = RunCli({"fuse", missing.string(), "--mesh", mesh.string()});
  EXPECT_EQ(r.exit_code, 1) << Describe(r);
  EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(mesh));
  EXPECT_TRUE(r.last_json.is_null());
}

TEST(CliTest, UnsupportedMeshExtensionRefusedBeforeWork) {
  const test::TempDir dir("voxplan-cli-ext");
  const fs::path mesh = dir / "out.xyz", stats = dir / "stats.json";
  const RunResult r =
      RunCli({"fuse", IclDir().string(), "--mesh", mesh.string(), "--stats", stats.string()});
  EXPECT_EQ(r.exit_code, 2) << Describe(r);
  EXPECT_NE(r.err.find("out.xyz"), std::string::npos) << Describe(r);
  EXPECT_EQ(r.err.find("fuse:"), std::string::npos) << "integration started: " << Describe(r);
  EXPECT_FALSE(fs::exists(mesh));
  EXPECT_FALSE(fs::exists(stats));
}

TEST(CliTest, MapIntoMissingFolderRefusedBeforeWork) {
  const test::TempDir dir("voxplan-cli-mapdir");
  const fs::path map = dir / "missing" / "out.vpmap";
  const RunResult r = RunCli({"fuse", IclDir().string(), "--map", map.string()});
  EXPECT_NE(r.exit_code, 0) << Describe(r);
  EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find(map.string()), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(map));
  EXPECT_FALSE(fs::exists(map.parent_path()));
}

TEST(CliTest, TruncatedMapRefusedByMesh) {
  const test::TempDir dir("voxplan-cli-trunc");
  const fs::path map = dir / "truncated.vpmap", mesh = dir / "out.ply";
  WriteSmallMap(map);
  fs::resize_file(map, fs::file_size(map) / 2);
  const RunResult r = RunCli({"mesh", map.string(), "--out", mesh.string()});
  EXPECT_EQ(r.exit_code, 1) << Describe(r);
  EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
  EXPECT_NE(r.err.find("truncated.vpmap"), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(mesh));

  const RunResult info = RunCli({"info", map.string()});
  EXPECT_EQ(info.exit_code, 1) << Describe(info);
  EXPECT_NE(info.err.find("truncated.vpmap"), std::string::npos) << Describe(info);
}

// An ICL-layout copy of the first frames with one depth PNG cut short: the run fails halfway,
// after frames were integrated, and must leave the existing map where --map points untouched.
TEST(CliTest, FailedRunLeavesExistingMapUntouched) {
  const test::TempDir dir("voxplan-cli-keep");
  const fs::path map = dir / "keep.vpmap", mesh = dir / "out.ply", stats = dir / "stats.json";
  WriteSmallMap(map);
  const std::string before = ReadAll(map);

  // Refused before work: bad mesh extension.
  const RunResult early = RunCli(
      {"fuse", IclDir().string(), "--map", map.string(), "--mesh", (dir / "out.abc").string()});
  EXPECT_NE(early.exit_code, 0) << Describe(early);
  EXPECT_EQ(ReadAll(map), before);

  // Fails during the frame loop: a corrupt depth image.
  const fs::path broken = dir / "icl_broken";
  test::CopyIclFrames(broken, 6);
  const fs::path bad = broken / "depth" / "4.png";
  fs::resize_file(bad, fs::file_size(bad) / 3);

  const RunResult late =
      RunCli({"fuse", broken.string(), "--voxel-size", "0.05", "--trunc", "0.2", "--map",
              map.string(), "--mesh", mesh.string(), "--stats", stats.string()});
  EXPECT_EQ(late.exit_code, 1) << Describe(late);
  EXPECT_NE(late.err.find("error:"), std::string::npos) << Describe(late);
  EXPECT_NE(late.err.find("4.png"), std::string::npos) << Describe(late);
  EXPECT_EQ(ReadAll(map), before);
  EXPECT_FALSE(fs::exists(mesh));
  EXPECT_FALSE(fs::exists(stats));
  EXPECT_TRUE(late.last_json.is_null());
}

}  // namespace
}  // namespace voxplan
