// `voxplan sim scene` run as a user would: generating an apartment (same seed, same files),
// loading the AWS small house, and usage errors refused before anything is written.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sim/scene_loader.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::ReadAll;
using test::RunCli;
using test::RunResult;

TEST(SimSceneCli, GeneratesTheSameApartmentTwice) {
  test::TempDir dir("sim_scene_cli");
  std::vector<std::vector<std::string>> paths;
  for (const char* sub : {"a", "b"}) {
    const RunResult r = RunCli({"sim", "scene", "--generate", "apartment", "--size", "M", "--seed",
                                "3", "--out", (dir / sub).string()});
    ASSERT_EQ(r.exit_code, 0) << Describe(r);
    const nlohmann::json& j = r.last_json;
    ASSERT_TRUE(j.is_object()) << Describe(r);
    EXPECT_GE(j["area_m2"].get<double>(), 110.0);
    EXPECT_LE(j["area_m2"].get<double>(), 200.0);
    EXPECT_GE(j["rooms"].get<int>(), 5);
    EXPECT_GT(j["instances"].get<int>(), 20);
    EXPECT_GT(j["triangles"].get<int>(), 1000);
    paths.push_back(j["paths"].get<std::vector<std::string>>());
    for (const std::string& p : paths.back()) EXPECT_TRUE(fs::is_regular_file(p)) << p;
  }
  ASSERT_EQ(paths[0].size(), paths[1].size());
  EXPECT_EQ(paths[0].size(), 6u);
  for (size_t i = 0; i < paths[0].size(); ++i)
    EXPECT_EQ(ReadAll(paths[0][i]), ReadAll(paths[1][i])) << paths[0][i];
}

TEST(SimSceneCli, LoadsTheAwsHouseWithItsInstances) {
  test::TempDir dir("sim_scene_aws");
  const std::string scene =
      (test::SharedDataDir() / "scenes/aws_small_house/derived/small_house_visual.ply").string();
  const RunResult r =
      RunCli({"sim", "scene", "--scene", scene, "--out", dir.path().string(), "--no-glb"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  EXPECT_EQ(r.last_json["instances"].get<int>(), 85);
  EXPECT_EQ(r.last_json["triangles"].get<int>(), 145844);
  EXPECT_EQ(r.last_json["rooms"].get<int>(), 0);
  // The written world reads back with its instances.
  Result<World> back = LoadWorld((dir / "world.ply").string());
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->instances.size(), 85u);
}

TEST(SimSceneCli, FloorZMovesTheReplicaOfficeFloorToZero) {
  // Replica's office stands on a floor at z = -1.13: as it is, nothing lies in the floor plan's
  // floor band (no free cell); with --floor-z auto, or that height given, the room is free floor.
  test::TempDir dir("sim_scene_floor");
  const std::string scene =
      (test::SharedDataDir() / "scenes/replica_office0/office0_mesh.ply").string();
  auto run = [&](const std::vector<std::string>& extra, const std::string& sub) {
    std::vector<std::string> args = {
        "sim", "scene", "--scene", scene, "--out", (dir / sub).string(), "--no-glb"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunCli(args);
  };
  const RunResult as_is = run({}, "as_is");
  ASSERT_EQ(as_is.exit_code, 0) << Describe(as_is);
  EXPECT_EQ(as_is.last_json["free_area_m2"].get<double>(), 0.0);
  EXPECT_FALSE(as_is.last_json.contains("floor_z_m"));
  const RunResult detected = run({"--floor-z", "auto"}, "auto");
  ASSERT_EQ(detected.exit_code, 0) << Describe(detected);
  const double floor_z = detected.last_json["floor_z_m"].get<double>();
  EXPECT_NEAR(floor_z, -1.124, 0.02);
  EXPECT_GT(detected.last_json["free_area_m2"].get<double>(), 5.0);  // of 18.6 m² inside
  const RunResult given = run({"--floor-z", "-1.129675"}, "given");
  ASSERT_EQ(given.exit_code, 0) << Describe(given);
  EXPECT_NEAR(given.last_json["floor_z_m"].get<double>(), -1.129675, 1e-6);
  EXPECT_EQ(given.last_json["free_area_m2"], detected.last_json["free_area_m2"]);
  // The written world is the moved one: its floor at 0.
  Result<World> back = LoadWorld((dir / "auto" / "world.ply").string());
  ASSERT_TRUE(back.ok()) << back.status().message();
  Result<FloorDetection> f = DetectFloor(back->mesh);
  ASSERT_TRUE(f.ok()) << f.status().message();
  EXPECT_NEAR(f->z_m, 0.0f, 1e-5f);
}

TEST(SimSceneCli, UsageErrorsExitTwoAndWriteNothing) {
  test::TempDir dir("sim_scene_bad");
  const std::string scene =
      (test::SharedDataDir() / "scenes/aws_small_house/derived/small_house_visual.ply").string();
  const std::string out = (dir / "out").string();
  const std::vector<std::vector<std::string>> cases = {
      {"sim", "scene", "--generate", "apartment", "--size", "XXL", "--out", out},
      {"sim", "scene", "--generate", "house", "--out", out},
      {"sim", "scene", "--out", out},
      {"sim", "scene", "--generate", "apartment", "--scene", scene, "--out", out},
      {"sim", "scene", "--scene", scene, "--scale", "1000", "--out", out},
      {"sim", "scene", "--scene", scene, "--up", "x", "--out", out},
      {"sim", "scene", "--scene", scene, "--floor-z", "floor", "--out", out},
      {"sim", "scene", "--scene", scene, "--floor-z", "1e9", "--out", out},
      {"sim", "scene", "--scene", scene, "--floor-z", "nan", "--out", out},
      {"sim", "scene", "--generate", "apartment", "--out", (dir / "no/such/dir").string()},
  };
  for (const auto& args : cases) {
    const RunResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << Describe(r);
    EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
    EXPECT_FALSE(fs::exists(out)) << Describe(r);
  }
  const RunResult missing = RunCli({"sim", "scene", "--scene", "/no/such.ply", "--out", out});
  EXPECT_EQ(missing.exit_code, 1) << Describe(missing);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace voxplan
