// FuseDataset's frame policy below the CLI: which frames are integrated, skipped or lost, at
// which pose, with which warnings, and that the volume is exactly the one a plain
// IntegrateFrame loop builds. Frames are exact depth of a box room, seen from inside at known
// poses looking into a corner (three walls: tracking is well posed).
#include <gtest/gtest.h>

#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/fuse_dataset.h"
#include "tests/fusion/box_room.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

const test::BoxRoom kRoom{Eigen::Vector3f(0.f, 0.f, 0.f), Eigen::Vector3f(4.f, 3.f, 2.5f)};

// Camera k a little further along a line through the room, looking into the far corner.
Pose3f ArcPose(int k) {
  const Eigen::Vector3f eye =
      Eigen::Vector3f(2.f, 1.5f, 1.2f) + 0.02f * float(k) * Eigen::Vector3f(1.f, 0.5f, 0.f);
  return LookAt(eye, Eigen::Vector3f(3.9f, 2.9f, 0.1f), Eigen::Vector3f::UnitZ());
}

enum class Kind { kPosed, kNoPose, kNoDepth, kUnreadable };

// In-memory frames of the room, one per entry of `kinds`.
class RoomDataset : public Dataset {
 public:
  explicit RoomDataset(std::vector<Kind> kinds, PinholeCamera camera = test::RoomCamera())
      : kinds_(std::move(kinds)) {
    info_.camera = camera;
    info_.num_frames = kinds_.size();
    info_.root = "room";
  }
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t i) const override {
    if (kinds_[i] == Kind::kUnreadable) return CorruptData("frame_" + std::to_string(i) + ".png");
    Frame f;
    f.index = i;
    f.timestamp = 0.1 * double(i);
    f.depth_path = "frame_" + std::to_string(i) + ".png";
    f.depth = test::RenderRoomDepth(kRoom, info_.camera, ArcPose(int(i)));
    if (kinds_[i] == Kind::kNoDepth) f.depth.data.assign(f.depth.data.size(), 0.f);
    if (kinds_[i] != Kind::kNoPose) f.T_W_C = ArcPose(int(i)).cast<double>();
    return f;
  }

 private:
  std::vector<Kind> kinds_;
  DatasetInfo info_;
};

std::vector<size_t> All(const Dataset& d) {
  std::vector<size_t> indices(d.info().num_frames);
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = i;
  return indices;
}

const VolumeParams kVolume{0.02f, 0.08f};

FuseParams WholeRoom() {
  FuseParams params;
  params.integrate.max_depth_m = 5.f;
  return params;
}

TEST(FuseDataset, SkipsFramesWithoutDepthOrPoseAndCountsThem) {
  const RoomDataset dataset(
      {Kind::kPosed, Kind::kNoPose, Kind::kNoDepth, Kind::kPosed, Kind::kNoPose});
  TsdfVolume volume(kVolume);
  std::vector<size_t> progress;
  FuseObserver observer;
  observer.progress = [&](size_t done, size_t total) {
    EXPECT_EQ(total, 5u);
    progress.push_back(done);
  };
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), WholeRoom(), volume, observer);
  ASSERT_TRUE(r.ok()) << r.status().message();
  ASSERT_EQ(r->frames.size(), 2u);
  EXPECT_EQ(r->frames[0].index, 0u);
  EXPECT_EQ(r->frames[1].index, 3u);
  EXPECT_TRUE(r->frames[1].T_W_C.isApprox(ArcPose(3)));
  EXPECT_DOUBLE_EQ(r->frames[1].timestamp_s, 0.3);
  EXPECT_EQ(r->frames[1].depth_path, "frame_3.png");
  EXPECT_EQ(r->frames_selected, 5u);
  EXPECT_EQ(r->skipped_no_pose, 2u);
  EXPECT_EQ(r->skipped_no_depth, 1u);
  EXPECT_EQ(r->frames_lost, 0u);
  EXPECT_EQ(r->load_ms.size(), 2u);
  EXPECT_EQ(r->integrate_ms.size(), 2u);
  EXPECT_EQ(r->frame_ms.size(), 2u);
  EXPECT_TRUE(r->track_ms.empty());
  EXPECT_EQ(progress, (std::vector<size_t>{1, 2, 3, 4, 5}));
  EXPECT_GT(volume.num_blocks(), 0u);
}

TEST(FuseDataset, BuildsExactlyTheVolumeOfAPlainIntegrationLoop) {
  const RoomDataset dataset({Kind::kPosed, Kind::kPosed, Kind::kNoPose, Kind::kPosed});
  FuseParams params;
  params.integrate.max_depth_m = 2.5f;
  TsdfVolume fused(kVolume), plain(kVolume);
  ASSERT_TRUE(FuseDataset(dataset, All(dataset), params, fused).ok());
  for (size_t i : {0, 1, 3}) {
    Result<Frame> f = dataset.Load(i);
    ASSERT_TRUE(f.ok());
    ASSERT_TRUE(IntegrateFrame(f->depth, f->color, dataset.info().camera, f->T_W_C->cast<float>(),
                               params.integrate, plain)
                    .ok());
  }
  const std::vector<BlockIndex> blocks = fused.SortedBlockIndices();
  ASSERT_EQ(blocks, plain.SortedBlockIndices());
  for (const BlockIndex& b : blocks)
    EXPECT_EQ(std::memcmp(fused.FindBlock(b), plain.FindBlock(b), sizeof(TsdfBlock)), 0);
}

TEST(FuseDataset, NamesTheFirstSkippedFramesThenCountsTheRest) {
  std::vector<Kind> kinds(8, Kind::kNoPose);
  kinds[0] = Kind::kPosed;
  const RoomDataset dataset(kinds);
  FuseParams params;
  params.max_skip_warnings = 3;
  std::vector<std::string> warnings;
  FuseObserver observer;
  observer.warning = [&](const std::string& w) { warnings.push_back(w); };
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume, observer);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->skipped_no_pose, 7u);
  ASSERT_EQ(warnings.size(), 4u);
  EXPECT_EQ(warnings[0], "frame 1 (frame_1.png) has no pose; skipped");
  EXPECT_EQ(warnings[2], "frame 3 (frame_3.png) has no pose; skipped");
  EXPECT_EQ(warnings[3], "7 frames in all had no pose and were skipped");
}

TEST(FuseDataset, AFrameThatCannotBeLoadedStopsTheRunNamingIt) {
  const RoomDataset dataset({Kind::kPosed, Kind::kUnreadable, Kind::kPosed});
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), {}, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "frame 1: frame_1.png");
}

TEST(FuseDataset, AnObserverFailureStopsTheRun) {
  const RoomDataset dataset({Kind::kPosed, Kind::kPosed, Kind::kPosed});
  int calls = 0;
  FuseObserver observer;
  observer.integrated = [&](const Frame&, const Pose3f&, TsdfVolume&) {
    return ++calls == 2 ? IoError("mesher gave up") : Status::Ok();
  };
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), {}, volume, observer);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "mesher gave up");
  EXPECT_EQ(calls, 2);
}

TEST(FuseDataset, TrackingStartsFromTheDatasetPoseAndFollowsTheCamera) {
  // Only the first frame has a pose: the others need none when tracked.
  const RoomDataset dataset({Kind::kPosed, Kind::kNoPose, Kind::kNoPose, Kind::kNoPose},
                            test::RoomCamera(192));  // the coarsest pyramid level needs pixels
  FuseParams params = WholeRoom();
  params.track = true;
  params.tracking.raycast.max_depth_m = 5.f;
  TsdfVolume volume(kVolume);
  std::vector<std::string> warnings;
  FuseObserver observer;
  observer.warning = [&](const std::string& w) { warnings.push_back(w); };
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume, observer);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  ASSERT_EQ(r->frames.size(), 4u);
  EXPECT_EQ(r->frames_lost, 0u);
  EXPECT_EQ(r->skipped_no_pose, 0u);
  // The first frame is integrated at the dataset's pose exactly; every later one is tracked.
  EXPECT_TRUE(r->frames[0].T_W_C.matrix() == ArcPose(0).matrix());
  EXPECT_EQ(r->track_ms.size(), 3u);
  // Three walls pin the pose down to under a voxel.
  for (const FusedFrame& f : r->frames)
    EXPECT_LT((f.T_W_C.translation() - ArcPose(int(f.index)).translation()).norm(), 0.02f)
        << "frame " << f.index;
}

TEST(FuseDataset, TrackingWithoutADatasetPoseStartsAtTheIdentity) {
  const RoomDataset dataset({Kind::kNoPose});
  FuseParams params;
  params.track = true;
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume);
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->frames.size(), 1u);
  EXPECT_TRUE(r->frames[0].T_W_C.matrix() == Pose3f::Identity().matrix());
  EXPECT_EQ(r->skipped_no_pose, 0u);
}

TEST(FuseDataset, ACameraTrackingCannotUseIsRefusedNotThrown) {
  PinholeCamera tiny = test::RoomCamera(4);  // too small for the tracking pyramid
  const RoomDataset dataset({Kind::kPosed}, tiny);
  FuseParams params;
  params.track = true;
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("tracking"), std::string::npos);
}

}  // namespace
}  // namespace voxplan

// Memory budget and entry checks (issue 29): see pipeline/fuse_dataset.h's OnMemoryLimit.
namespace voxplan {
namespace {

const VolumeParams kTightVolume{0.005f, 0.02f, uint64_t(1) << 20};  // 256 blocks of 4 cm

TEST(FuseDatasetBudget, PastTheBudgetWarnsOnceAndCountsWhatWasDropped) {
  const RoomDataset dataset({Kind::kPosed, Kind::kPosed, Kind::kPosed});
  std::vector<std::string> warnings;
  FuseObserver observer;
  observer.warning = [&](const std::string& w) { warnings.push_back(w); };
  TsdfVolume volume(kTightVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), WholeRoom(), volume, observer);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->frames.size(), 3u);  // every frame still integrated into the blocks there are
  EXPECT_EQ(r->frames_over_budget, 3u);
  EXPECT_GT(r->blocks_refused, 0u);
  EXPECT_EQ(volume.num_blocks(), 256u);
  EXPECT_LE(volume.MemoryBytes(), kTightVolume.max_memory_bytes);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("memory budget of 1 MiB reached at frame 0 (frame_0.png)", 0), 0u)
      << warnings[0];
}

TEST(FuseDatasetBudget, FailModeStopsWithResourceExhausted) {
  const RoomDataset dataset({Kind::kPosed, Kind::kPosed});
  FuseParams params = WholeRoom();
  params.on_memory_limit = OnMemoryLimit::kFail;
  TsdfVolume volume(kTightVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("memory budget of 1 MiB reached at frame 0"),
            std::string::npos)
      << r.status().message();
}

TEST(FuseDatasetBudget, InvalidParamsAreRefusedBeforeAnyFrameIsRead) {
  // The first frame cannot be read: a refusal about it would mean the checks came too late.
  const RoomDataset dataset({Kind::kUnreadable, Kind::kPosed});
  TsdfVolume fine(VolumeParams{0.0001f, 0.0004f});
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), WholeRoom(), fine);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("voxel size must be in [0.001, 1] m"), std::string::npos)
      << r.status().message();
  FuseParams far = WholeRoom();
  far.integrate.max_depth_m = 1e6f;
  TsdfVolume volume(VolumeParams{0.02f, 0.08f});
  r = FuseDataset(dataset, All(dataset), far, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("max depth must be in [0, 100] m"), std::string::npos)
      << r.status().message();
  PinholeCamera wide = test::RoomCamera();
  wide.fx = 1.f;
  const RoomDataset wide_dataset({Kind::kUnreadable}, wide);
  r = FuseDataset(wide_dataset, All(wide_dataset), WholeRoom(), volume);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("|fx|"), std::string::npos) << r.status().message();
}

}  // namespace
}  // namespace voxplan
