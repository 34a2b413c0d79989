// The checks FuseDataset makes before trusting a frame (pipeline/frame_checks.h): a pose out of
// range (or one the reader rejected) is skipped and counted as such, never integrated with its
// blocks silently dropped; a wrong depth scale is named in a warning with the likely scale.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/image_io.h"
#include "pipeline/fuse_dataset.h"
#include "tests/fusion/box_room.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

const test::BoxRoom kRoom{Eigen::Vector3f(0.f, 0.f, 0.f), Eigen::Vector3f(4.f, 3.f, 2.5f)};
const VolumeParams kVolume{0.02f, 0.08f};

Pose3f RoomPose() {
  return LookAt(Eigen::Vector3f(2.f, 1.5f, 1.2f), Eigen::Vector3f(3.9f, 2.9f, 0.1f),
                Eigen::Vector3f::UnitZ());
}

// Frames of the room, each with the pose (or rejection) its test gives it.
class PosedRoom : public Dataset {
 public:
  explicit PosedRoom(std::vector<Frame> frames) : frames_(std::move(frames)) {
    info_.camera = test::RoomCamera();
    info_.num_frames = frames_.size();
    info_.root = "room";
  }
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t i) const override {
    Frame f = frames_[i];
    f.index = i;
    f.depth_path = "frame_" + std::to_string(i) + ".png";
    f.depth = test::RenderRoomDepth(kRoom, info_.camera, RoomPose());
    return f;
  }

 private:
  std::vector<Frame> frames_;
  DatasetInfo info_;
};

Frame WithPose(const Pose3d& T_W_C) {
  Frame f;
  f.T_W_C = T_W_C;
  return f;
}

Frame Translated(double x) {
  Pose3d T = RoomPose().cast<double>();
  T.translation().x() = x;
  return WithPose(T);
}

struct FuseRun {
  FuseReport report;
  std::vector<std::string> warnings;
};

FuseRun Fuse(const Dataset& dataset, const FuseParams& params = {}) {
  TsdfVolume volume(kVolume);
  FuseRun run;
  FuseObserver observer;
  observer.warning = [&](const std::string& w) { run.warnings.push_back(w); };
  std::vector<size_t> all(dataset.info().num_frames);
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  FuseParams p = params;
  p.integrate.max_depth_m = 5.f;
  auto report = FuseDataset(dataset, all, p, volume, observer);
  EXPECT_TRUE(report.ok()) << report.status().message();
  if (report.ok()) run.report = *report;
  return run;
}

bool AnyContains(const std::vector<std::string>& v, const std::string& what) {
  return std::any_of(v.begin(), v.end(),
                     [&](const std::string& s) { return s.find(what) != std::string::npos; });
}

TEST(FuseChecks, AbsurdOrNonFinitePoseIsSkippedAndCounted) {
  Pose3d nan_pose = RoomPose().cast<double>();
  nan_pose.translation().y() = std::numeric_limits<double>::quiet_NaN();
  const PosedRoom room({WithPose(RoomPose().cast<double>()), Translated(1e6), WithPose(nan_pose),
                        WithPose(RoomPose().cast<double>())});
  const FuseRun run = Fuse(room);
  EXPECT_EQ(run.report.frames.size(), 2u);
  EXPECT_EQ(run.report.skipped_bad_pose, 2u);
  EXPECT_EQ(run.report.skipped_no_pose, 0u);
  EXPECT_TRUE(AnyContains(run.warnings,
                          "frame 1 (frame_1.png) has a pose not to trust (pose "
                          "translation 1e+06 m is beyond the 10000 m allowed)"));
  EXPECT_TRUE(AnyContains(run.warnings,
                          "frame 2 (frame_2.png) has a pose not to trust (pose has "
                          "NaN"));
}

TEST(FuseChecks, PoseWhoseViewLeavesTheBlockIndexRangeIsAlwaysSkipped) {
  FuseParams params;
  params.max_pose_translation_m = 1e12;  // no bound of its own: the index range still holds
  // 2^20 blocks of 8 voxels of 2 cm: about 168 km.
  const PosedRoom room({Translated(1.6e5), Translated(1.7e5), WithPose(RoomPose().cast<double>())});
  const FuseRun run = Fuse(room, params);
  EXPECT_EQ(run.report.frames.size(), 2u);
  EXPECT_EQ(run.report.skipped_bad_pose, 1u);
  EXPECT_TRUE(AnyContains(run.warnings,
                          "frame 1 (frame_1.png) has a pose not to trust (camera at "
                          "170000 m sees outside the volume's block index range"));
}

TEST(FuseChecks, PosesTheReaderRejectedAreCountedByReason) {
  Frame bad, gap;
  bad.pose_rejected = PoseRejection::kBadValues;
  bad.pose_rejected_why = "frame-000001.pose.txt:1: pose has NaN or infinite entries";
  gap.pose_rejected = PoseRejection::kGroundTruthGap;
  gap.pose_rejected_why = "depth.txt:7: depth 3.5 lies in a 2 s gap of groundtruth.txt";
  const PosedRoom room({WithPose(RoomPose().cast<double>()), bad, gap, Frame{}});
  const FuseRun run = Fuse(room);
  EXPECT_EQ(run.report.frames.size(), 1u);
  EXPECT_EQ(run.report.skipped_bad_pose, 1u);
  EXPECT_EQ(run.report.skipped_pose_gap, 1u);
  EXPECT_EQ(run.report.skipped_no_pose, 1u);
  EXPECT_TRUE(AnyContains(run.warnings,
                          "frame 1 (frame_1.png) has a pose not to trust "
                          "(frame-000001.pose.txt:1: pose has NaN"));
  EXPECT_TRUE(AnyContains(run.warnings, "frame 2 (frame_2.png) has no pose (depth.txt:7:"));
}

// A Redwood folder of three 16 x 12 frames of a wall 1.5 m away, written in millimetres.
void MakeMillimetreRedwood(const fs::path& root) {
  fs::create_directories(root / "depth");
  std::ofstream log(root / "trajectory.log");
  for (int k = 0; k < 3; ++k) {
    const std::string name = (root / ("depth/0000" + std::to_string(k) + ".png")).string();
    ASSERT_TRUE(WriteDepthPng16(name, DepthImage(16, 12, 1.5f), 1000.0).ok());
    log << k << " " << k << " 3\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  }
}

TEST(FuseChecks, WrongDepthScaleIsWarnedWithTheLikelyScale) {
  test::TempDir dir("mm");
  MakeMillimetreRedwood(dir.path());
  DatasetOptions as_metres;
  as_metres.depth_scale = 1.0;  // the millimetres read as metres: a wall 1500 m away
  as_metres.intrinsics = PinholeCamera{0, 0, 12.f, 12.f, 7.5f, 5.5f};
  auto wrong = OpenDataset(dir.path().string(), as_metres);
  ASSERT_TRUE(wrong.ok()) << wrong.status().message();
  const FuseRun run = Fuse(**wrong);
  EXPECT_DOUBLE_EQ(run.report.first_frames_median_depth_m, 1500.0);
  EXPECT_EQ(run.report.suggested_depth_scale, 1000.0);
  EXPECT_TRUE(AnyContains(run.warnings, dir.path().string() + ": the median valid depth of the "
                                                              "first 3 frame(s)"));
  EXPECT_TRUE(AnyContains(run.warnings,
                          "is 1500 m, outside 0.2 to 15 m, with depth scale 1 units "
                          "per metre; the likely scale is 1000 (median 1.5 m)"));

  DatasetOptions right = as_metres;
  right.depth_scale.reset();  // Redwood's own 1000
  auto ok = OpenDataset(dir.path().string(), right);
  ASSERT_TRUE(ok.ok()) << ok.status().message();
  const FuseRun good = Fuse(**ok);
  EXPECT_DOUBLE_EQ(good.report.first_frames_median_depth_m, 1.5);
  EXPECT_EQ(good.report.suggested_depth_scale, 0.0);
  EXPECT_FALSE(AnyContains(good.warnings, "median valid depth"));
  EXPECT_EQ(good.report.frames.size(), 3u);
}

}  // namespace
}  // namespace voxplan
