// `bench maps` on a few real frames beside OctoMap, its .bt export, and its usage errors.
#include <gtest/gtest.h>

#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

TEST(BenchMapsCli, TimesThePlanningMapBesideOctomap) {
  const std::string dataset = (test::SharedDataDir() / "rgbd" / "7scenes_redkitchen").string();
  test::TempDir dir("bench_maps");
  const std::string bt = (dir / "map.bt").string(), json_path = (dir / "maps.json").string();
  const test::RunResult r =
      test::RunCli({"bench", "maps", dataset, "--frames", "3", "--resolution", "0.1", "--threads",
                    "2", "--vs-octomap", "--export-bt", bt, "--json", json_path});
  ASSERT_EQ(r.exit_code, 0) << test::Describe(r);
  const nlohmann::json& j = r.last_json;
  ASSERT_TRUE(j.is_object()) << test::Describe(r);
  EXPECT_EQ(j.at("frames"), 3);
  EXPECT_EQ(j.at("threads"), 2);
  EXPECT_DOUBLE_EQ(j.at("resolution").get<double>(), 0.1);
  EXPECT_GT(j.at("maps_ms_median").get<double>(), 0.0);
  EXPECT_GT(j.at("octomap_ms_median").get<double>(), 0.0);
  EXPECT_NEAR(j.at("speedup").get<double>(),
              j.at("octomap_ms_median").get<double>() / j.at("maps_ms_median").get<double>(),
              0.01 * j.at("speedup").get<double>() + 0.01);
  EXPECT_GT(j.at("blocks").get<int>(), 0);
  // Where OctoMap saw free space, the planning map mostly does too.
  EXPECT_GT(j.at("free_agreement").get<double>(), 0.5);
  EXPECT_TRUE(std::filesystem::exists(bt));
  EXPECT_EQ(nlohmann::json::parse(test::ReadAll(json_path)), j);
}

TEST(BenchMapsCli, RefusesBadInput) {
  const test::RunResult missing = test::RunCli({"bench", "maps", "/nonexistent/dataset"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("not found"), std::string::npos) << test::Describe(missing);
  const std::string dataset = (test::SharedDataDir() / "rgbd" / "7scenes_redkitchen").string();
  const test::RunResult range =
      test::RunCli({"bench", "maps", dataset, "--min-depth", "3", "--max-depth", "2"});
  EXPECT_EQ(range.exit_code, 2) << test::Describe(range);
  const test::RunResult resolution = test::RunCli({"bench", "maps", dataset, "--resolution", "0"});
  EXPECT_NE(resolution.exit_code, 0);
}

}  // namespace
}  // namespace voxplan
