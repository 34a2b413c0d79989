// The robot file (explore/robot_config.h): round trips, partial files over a base, refusals
// naming the key, and the guo2022 and xu2017 profiles.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "explore/robot_config.h"

namespace voxplan {
namespace {

TEST(RobotConfig, EveryKeyRoundTripsAndAPartialFileKeepsTheBase) {
  const RobotParams guo = Guo2022RobotParams();
  Result<RobotParams> back = ParseRobotConfig(RobotConfigJson(guo), RobotParams{});
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(RobotConfigJson(*back), RobotConfigJson(guo));
  EXPECT_EQ(back->reconstructor.mount, MountKind::kArm);
  // One key over Guo's robot: the rest stays Guo's.
  Result<RobotParams> partial =
      ParseRobotConfig(R"({"reconstructor": {"switch_s": 0, "arm": {"reach_max_m": 1.0}}})", guo);
  ASSERT_TRUE(partial.ok()) << partial.status().message();
  EXPECT_EQ(partial->reconstructor.switch_s, 0.f);
  EXPECT_EQ(partial->reconstructor.arm.reach_max_m, 1.f);
  EXPECT_EQ(partial->reconstructor.arm.reach_min_m, guo.reconstructor.arm.reach_min_m);
  EXPECT_EQ(partial->explorer.min_range_m, 0.35f);
  EXPECT_EQ(partial->reconstructor.mount, MountKind::kArm);
}

TEST(RobotConfig, BadFilesAreRefusedNamingTheFileAndTheKey) {
  struct Case {
    const char* text;
    const char* says;
  };
  for (const Case& c :
       {Case{"[1, 2]", "JSON object"}, Case{"{\"radius\": 0.2}", "\"radius\""},
        Case{R"({"explorer": {"max_speed_mps": "fast"}})", "max_speed_mps"},
        Case{R"({"explorer": {"max_speed_mps": 1e9}})", "explorer.max_speed_mps"},
        Case{R"({"reconstructor": {"mount": "shoulder"}})", "mount"},
        Case{R"({"reconstructor": {"arm": {"speed": 1}}})", "\"speed\""},
        Case{R"({"explorer": {"min_range_m": 6}})", "min_range_m"}, Case{"{", "not valid JSON"}}) {
    Result<RobotParams> r = ParseRobotConfig(c.text, RobotParams{}, "robot.json");
    ASSERT_FALSE(r.ok()) << c.text;
    EXPECT_NE(r.status().message().find("robot.json"), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(c.says), std::string::npos) << r.status().message();
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "voxplan_robot_config";
  std::filesystem::create_directories(dir);
  EXPECT_FALSE(ReadRobotConfig((dir / "missing.json").string(), RobotParams{}).ok());
  { std::ofstream(dir / "big.json") << std::string(2 << 20, ' '); }
  Result<RobotParams> big = ReadRobotConfig((dir / "big.json").string(), RobotParams{});
  ASSERT_FALSE(big.ok());
  EXPECT_NE(big.status().message().find("over the limit"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(RobotConfig, TheGuoProfileSetsTheRobotTheFineVolumeAndTheDetector) {
  ExploreParams params;
  params.detector.noise = false;
  ASSERT_TRUE(ApplyExploreProfile("guo2022", &params).ok());
  EXPECT_EQ(params.recon_voxel_size_m, 0.02f);
  EXPECT_EQ(params.recon_weighting, Weighting::kDepthDependent);
  EXPECT_TRUE(params.detector.noise);
  EXPECT_EQ(params.robot.reconstructor.mount, MountKind::kArm);
  EXPECT_EQ(params.robot.explorer.capture_hz, 2.f);
  EXPECT_EQ(params.robot.reconstructor.switch_s, 2.f);
  EXPECT_TRUE(params.Validate().ok());
  EXPECT_EQ(ApplyExploreProfile("dong2019", &params).code(), StatusCode::kNotFound);
}

TEST(RobotConfig, TheXuProfileSetsTheRobotTheFineVolumeAndTheStep) {
  ExploreParams params;
  ASSERT_TRUE(ApplyExploreProfile("xu2017", &params).ok());
  EXPECT_EQ(params.robot.explorer.max_speed_mps, 0.3f);
  EXPECT_EQ(params.robot.explorer.capture_hz, 5.f);
  EXPECT_NEAR(params.robot.camera_yaw_rate_radps, 40.0 * M_PI / 180.0, 1e-6);
  EXPECT_EQ(params.recon_voxel_size_m, 0.02f);
  EXPECT_EQ(params.poses, ExploreParams::Poses::kTruth);  // tracked is asked for apart
  EXPECT_EQ(params.step_s, 0.1);
  EXPECT_TRUE(params.Validate().ok());
}

}  // namespace
}  // namespace voxplan
