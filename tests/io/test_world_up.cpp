// The world's up axis (io/world_up.h): names, the estimate from poses, and what every reader
// says of its dataset (the format's convention, or the estimate), on the shared sequences and
// on written ScanNet / ROS fixtures.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>

#include "io/dataset.h"
#include "io/world_up.h"
#include "tests/io/bag_fixture.h"
#include "tests/io/sens_fixture.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

fs::path Rgbd() { return test::SharedDataDir() / "rgbd"; }

TEST(WorldUp, NamesParseAndVectors) {
  for (WorldUp up : {WorldUp::kUnknown, WorldUp::kPlusX, WorldUp::kMinusX, WorldUp::kPlusY,
                     WorldUp::kMinusY, WorldUp::kPlusZ, WorldUp::kMinusZ}) {
    Result<WorldUp> parsed = ParseWorldUp(WorldUpName(up));
    ASSERT_TRUE(parsed.ok()) << WorldUpName(up);
    EXPECT_EQ(*parsed, up);
    EXPECT_EQ(WorldUpFromCode(uint32_t(up)), up);
  }
  EXPECT_EQ(*ParseWorldUp("y"), WorldUp::kPlusY);
  EXPECT_EQ(*ParseWorldUp("z"), WorldUp::kPlusZ);
  EXPECT_FALSE(ParseWorldUp("up").ok());
  EXPECT_FALSE(ParseWorldUp("-").ok());
  EXPECT_FALSE(WorldUpFromCode(7));
  EXPECT_FALSE(WorldUpVector(WorldUp::kUnknown));
  EXPECT_EQ(*WorldUpVector(WorldUp::kMinusY), Eigen::Vector3f(0, -1, 0));
  EXPECT_EQ(WorldUpOrZ(WorldUp::kUnknown), Eigen::Vector3f::UnitZ());
}

// A level camera looking along world +x in a z-up world: x_C = -y_W, y_C = -z_W, z_C = +x_W.
Eigen::Matrix3d LevelInZUp(double yaw_rad, double roll_rad = 0.0) {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, -1, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(1, 0, 0);
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R *
         Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

TEST(WorldUp, EstimateFromLevelCamerasAndWhenItCannotTell) {
  WorldUpEstimator level(500.f);
  for (int k = 0; k < 8; ++k) level.Add(LevelInZUp(0.8 * k, 0.1 * (k % 3)));
  EXPECT_EQ(level.Result().up, WorldUp::kPlusZ);
  EXPECT_EQ(level.Result().poses, 8u);
  EXPECT_NE(level.Result().Describe().find("estimated from 8 poses"), std::string::npos);

  // The same poses for a y-flipped camera: its images are upright with +y up, so the world's
  // up is where the y axes point.
  WorldUpEstimator flipped(-500.f);
  for (int k = 0; k < 8; ++k) flipped.Add(LevelInZUp(0.8 * k));
  EXPECT_EQ(flipped.Result().up, WorldUp::kMinusZ);

  // Cameras rolled all the way round disagree; 45 degrees off every axis is no axis.
  WorldUpEstimator rolled(500.f);
  for (int k = 0; k < 8; ++k) rolled.Add(LevelInZUp(0.3 * k, 0.785 * k));
  EXPECT_EQ(rolled.Result().up, WorldUp::kUnknown);
  EXPECT_LT(rolled.Result().agreement, WorldUpEstimator::kMinAgreement);
  WorldUpEstimator tilted(500.f);
  tilted.Add(Eigen::AngleAxisd(0.785, Eigen::Vector3d::UnitX()).toRotationMatrix());
  EXPECT_EQ(tilted.Result().up, WorldUp::kUnknown);
  EXPECT_NEAR(tilted.Result().off_axis_deg, 45.0, 0.1);
  EXPECT_EQ(WorldUpEstimator(500.f).Result().Describe(), "unknown: no poses");
}

struct Expected {
  const char* folder;
  WorldUp up;
  const char* source;  // a word of up_source
};

// Conventions where the format states one; the poses' estimate otherwise. ICL-NUIM's is +y
// with its y-flipped camera; 7-Scenes' world is its first (upright, y-down) camera's, so -y;
// the SUN3D frames of 3DMatch and Open3D's ICL living room have their y axes pointing down.
TEST(WorldUp, EveryReaderOnItsSharedSequence) {
  const Expected cases[] = {
      {"iclnuim_office_traj0", WorldUp::kPlusY, "ICL-NUIM convention"},
      {"replica_office0", WorldUp::kPlusZ, "Replica convention"},
      {"7scenes_redkitchen", WorldUp::kMinusY, "estimated from 400 poses"},
      {"3dmatch_sun3d5", WorldUp::kPlusY, "estimated from 5 poses"},
      {"open3d_livingroom5", WorldUp::kPlusY, "estimated from 5 poses"},
  };
  for (const Expected& e : cases) {
    SCOPED_TRACE(e.folder);
    Result<std::unique_ptr<Dataset>> ds = OpenDataset((Rgbd() / e.folder).string());
    ASSERT_TRUE(ds.ok()) << ds.status().message();
    EXPECT_EQ((*ds)->info().up, e.up) << (*ds)->info().up_source;
    EXPECT_NE((*ds)->info().up_source.find(e.source), std::string::npos) << (*ds)->info().up_source;
  }
  // ICL-NUIM's convention is what the rule reads from its y-flipped camera's poses too.
  Result<std::unique_ptr<Dataset>> icl = OpenDataset((Rgbd() / "iclnuim_office_traj0").string());
  ASSERT_TRUE(icl.ok());
  WorldUpEstimator votes((*icl)->info().camera.fy);
  for (size_t i = 1; i < (*icl)->info().num_frames; i += 20) {
    Result<Frame> frame = (*icl)->Load(i);
    ASSERT_TRUE(frame.ok() && frame->T_W_C);
    votes.Add(frame->T_W_C->linear());
  }
  EXPECT_EQ(votes.Result().up, WorldUp::kPlusY);
}

TEST(WorldUp, ScanNetAndRosBagsStateZUp) {
  const test::TempDir dir("voxplan-world-up");
  // The wall scan's cameras are identity poses (y down along world y): the format's convention
  // still says z, as ScanNet's scans are aligned so.
  const fs::path sens = dir / "scene0000_00.sens";
  const test::SensScan scan = test::MakeWallScan(4, 9);
  test::WriteBytes(sens, test::EncodeSens(scan.header, scan.frames));
  Result<std::unique_ptr<Dataset>> scannet = OpenDataset(sens.string());
  ASSERT_TRUE(scannet.ok()) << scannet.status().message();
  EXPECT_EQ((*scannet)->info().up, WorldUp::kPlusZ);
  EXPECT_NE((*scannet)->info().up_source.find("ScanNet"), std::string::npos);

  const fs::path bag = dir / "run.bag";
  test::WriteBag(bag.string(), test::BagScene{});
  Result<std::unique_ptr<Dataset>> ros = OpenDataset(bag.string());
  ASSERT_TRUE(ros.ok()) << ros.status().message();
  EXPECT_EQ((*ros)->info().up, WorldUp::kPlusZ);
  EXPECT_NE((*ros)->info().up_source.find("REP 103"), std::string::npos);
}

}  // namespace
}  // namespace voxplan
