// System test of `voxplan bench`: a short fusion benchmark on real data (without Open3D, which
// the default suite does not need) and the usage errors it refuses. Timings are checked only
// for sanity, never against targets: benchmarks are measured, not asserted.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/block_pool.h"
#include "core/volume.h"
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

TEST(BenchCliTest, FusionOnTenIclFrames) {
  const test::TempDir dir("voxplan-bench");
  const fs::path json_path = dir / "bench.json";
  const RunResult r =
      RunCli({"bench", "fusion", IclDir().string(), "--frames", "10", "--voxel-size", "0.02",
              "--threads", "1,2", "--repeat", "1", "--json", json_path.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const json& j = r.last_json;
  ASSERT_TRUE(j.is_object()) << Describe(r);
  for (const char* key : {"integrate_ms_median",
                          "integrate_ms_p90",
                          "load_ms_median",
                          "open3d_legacy_ms_median",
                          "open3d_vbg_ms_median",
                          "speedup_integrate",
                          "raycast_ms_median",
                          "open3d_raycast_ms_median",
                          "speedup_raycast",
                          "mesh_ms",
                          "open3d_mesh_ms",
                          "speedup_mesh",
                          "bytes_per_voxel",
                          "payload_bytes_per_voxel",
                          "map_mb",
                          "peak_rss_mb",
                          "open3d_peak_rss_mb",
                          "thread_scaling_integrate",
                          "rows",
                          "dataset",
                          "format",
                          "frames",
                          "voxel_size_m",
                          "trunc_m",
                          "min_depth_m",
                          "max_depth_m",
                          "repeat",
                          "threads",
                          "kernel",
                          "raycast_kernel",
                          "machine"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  ASSERT_EQ(j.at("rows").size(), 2u);
  EXPECT_EQ(j.at("rows")[0].at("threads").get<int>(), 1);
  EXPECT_EQ(j.at("rows")[1].at("threads").get<int>(), 2);
  EXPECT_EQ(j.at("threads"), json::array({1, 2}));
  EXPECT_EQ(j.at("format").get<std::string>(), "icl");
  EXPECT_DOUBLE_EQ(j.at("voxel_size_m").get<double>(), 0.02);
  EXPECT_EQ(j.at("repeat").get<int>(), 1);
  // ICL frame id 1 has no pose: skipped by the bench or dropped by the reader.
  const int frames = j.at("frames").get<int>();
  EXPECT_TRUE(frames == 9 || frames == 10) << frames;
  EXPECT_GT(j.at("integrate_ms_median").get<double>(), 0.0);
  EXPECT_GE(j.at("integrate_ms_p90").get<double>(), j.at("integrate_ms_median").get<double>());
  EXPECT_GT(j.at("load_ms_median").get<double>(), 0.0);
  EXPECT_GT(j.at("raycast_ms_median").get<double>(), 0.0);
  EXPECT_GT(j.at("raycast_hit_fraction").get<double>(), 0.1);
  EXPECT_GT(j.at("mesh_ms").get<double>(), 0.0);
  EXPECT_GT(j.at("mesh_triangles").get<int>(), 1000);
  EXPECT_GT(j.at("peak_rss_mb").get<double>(), 0.0);
  EXPECT_GT(j.at("thread_scaling_integrate").get<double>(), 0.0);
  // Without --vs-open3d the Open3D keys are there but null.
  EXPECT_TRUE(j.at("open3d_vbg_ms_median").is_null());
  EXPECT_TRUE(j.at("speedup_integrate").is_null());
  // Everything the map holds per voxel: the 7-byte payload, plus the pool's last partly used
  // chunk and the hash map (a few hundred blocks here, so the chunk rounding shows).
  const double payload = TsdfVolume::BytesPerVoxel();
  EXPECT_DOUBLE_EQ(j.at("payload_bytes_per_voxel").get<double>(), payload);
  const double blocks = j.at("blocks").get<double>();
  ASSERT_GT(blocks, 0.0);
  const double chunk = BlockPool::kChunkBlocks;
  const double rounded_up = std::ceil(blocks / chunk) * chunk / blocks;
  const double bytes_per_voxel = j.at("bytes_per_voxel").get<double>();
  EXPECT_GE(bytes_per_voxel, payload);
  EXPECT_LE(bytes_per_voxel, payload * rounded_up + 1.0) << blocks << " blocks";
  EXPECT_GT(j.at("machine").at("nproc").get<int>(), 0);
  // --json holds the same object.
  ASSERT_TRUE(fs::exists(json_path));
  EXPECT_EQ(json::parse(ReadAll(json_path)), j);
}

TEST(BenchCliTest, BadArgumentsExitTwoAndWriteNothing) {
  const test::TempDir dir("voxplan-bench-bad");
  const fs::path json_path = dir / "bench.json";
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"--threads", "1,x"},
                                              {"--threads", "0"},
                                              {"--repeat", "0"},
                                              {"--format", "bogus"}}) {
    std::vector<std::string> args = {"bench", "fusion", IclDir().string(), "--frames",
                                     "2",     "--json", json_path.string()};
    args.insert(args.end(), bad.begin(), bad.end());
    const RunResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << bad[0] << " " << bad[1] << "\n" << Describe(r);
    EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
    EXPECT_FALSE(fs::exists(json_path)) << bad[0] << " " << bad[1];
  }
  const RunResult missing = RunCli({"bench", "raycast", (dir / "nothing").string()});
  EXPECT_EQ(missing.exit_code, 1) << Describe(missing);
  EXPECT_NE(missing.err.find("nothing"), std::string::npos) << Describe(missing);
  EXPECT_EQ(RunCli({"bench"}).exit_code, 2);  // a benchmark must be named
}

// A Python that cannot import Open3D (here: one that cannot start at all) is refused before
// any work, naming the setup script, and leaves nothing behind.
TEST(BenchCliTest, VsOpen3dWithoutOpen3dIsRefused) {
  const test::TempDir dir("voxplan-bench-no-open3d");
  const fs::path json_path = dir / "bench.json";
  const RunResult r = RunCli({"bench", "fusion", IclDir().string(), "--frames", "2", "--vs-open3d",
                              "--json", json_path.string()},
                             "PYTHONHOME=/nonexistent");
  EXPECT_EQ(r.exit_code, 1) << Describe(r);
  EXPECT_NE(r.err.find("scripts/setup-deps --bench"), std::string::npos) << Describe(r);
  EXPECT_FALSE(fs::exists(json_path));
  EXPECT_TRUE(r.out.empty()) << Describe(r);
}

}  // namespace
}  // namespace voxplan
