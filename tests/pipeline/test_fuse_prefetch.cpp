// FuseDataset with frames decoded ahead (FuseParams::prefetch): the same volume, mesh, report,
// warnings and progress as the sequential loop for any prefetch depth and 1 or 2 threads, on
// generated frames (colour included) and on shared ICL-NUIM frames through the real decoders;
// a frame that cannot be decoded stops the run there, naming its file, whatever is ahead.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "fusion/mesh_extract.h"
#include "pipeline/fuse_dataset.h"
#include "tests/fusion/box_room.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

const test::BoxRoom kRoom{Eigen::Vector3f(0.f, 0.f, 0.f), Eigen::Vector3f(4.f, 3.f, 2.5f)};

Pose3f ArcPose(size_t k) {
  const Eigen::Vector3f eye =
      Eigen::Vector3f(2.f, 1.5f, 1.2f) + 0.03f * float(k) * Eigen::Vector3f(1.f, 0.5f, 0.f);
  const float turn = 0.15f * float(k);
  const Eigen::Vector3f target(2.f + 1.9f * std::cos(turn), 1.5f + 1.4f * std::sin(turn), 0.3f);
  return LookAt(eye, target, Eigen::Vector3f::UnitZ());
}

// Rendered room frames with colour; frames named in `bad` fail to load, `no_pose` have none,
// `no_depth` are all zero.
class RoomFrames : public Dataset {
 public:
  RoomFrames(size_t n, std::vector<size_t> bad = {}, std::vector<size_t> no_pose = {},
             std::vector<size_t> no_depth = {})
      : bad_(std::move(bad)), no_pose_(std::move(no_pose)), no_depth_(std::move(no_depth)) {
    info_.camera = test::RoomCamera(64);
    info_.num_frames = n;
    info_.has_color = true;
    info_.root = "room";
  }
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t i) const override {
    const std::string name = "room/depth_" + std::to_string(i) + ".png";
    if (Has(bad_, i)) return CorruptData(name + ": corrupt or truncated PNG");
    Frame f;
    f.index = i;
    f.timestamp = 0.1 * double(i);
    f.depth_path = name;
    f.color_path = "room/color_" + std::to_string(i) + ".png";
    f.depth = test::RenderRoomDepth(kRoom, info_.camera, ArcPose(i));
    f.color = ColorImage(f.depth.width, f.depth.height);
    for (int v = 0; v < f.depth.height; ++v)
      for (int u = 0; u < f.depth.width; ++u)
        f.color.at(u, v) = PackRgb(uint8_t(u * 4 + i), uint8_t(v * 4), uint8_t(37 * i));
    if (Has(no_depth_, i)) f.depth.data.assign(f.depth.data.size(), 0.f);
    if (!Has(no_pose_, i)) f.T_W_C = ArcPose(i).cast<double>();
    return f;
  }

 private:
  static bool Has(const std::vector<size_t>& v, size_t i) {
    return std::find(v.begin(), v.end(), i) != v.end();
  }
  DatasetInfo info_;
  std::vector<size_t> bad_, no_pose_, no_depth_;
};

std::vector<size_t> All(const Dataset& d) {
  std::vector<size_t> indices(d.info().num_frames);
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = i;
  return indices;
}

// Everything a run gives but its timings.
struct Outcome {
  Status status;
  std::vector<FusedFrame> frames;
  size_t skipped_no_pose = 0, skipped_no_depth = 0;
  std::vector<std::string> warnings;
  std::vector<size_t> progress, integrated;
  std::vector<BlockIndex> blocks;
  std::vector<TsdfBlock> block_data;
  Mesh mesh;
};

Outcome Fuse(const Dataset& dataset, const std::vector<size_t>& indices, size_t prefetch,
             int threads, const VolumeParams& volume_params, float max_depth_m) {
  ThreadLimit limit(threads);
  FuseParams params;
  params.prefetch = prefetch;
  params.integrate.max_depth_m = max_depth_m;
  TsdfVolume volume(volume_params);
  Outcome o;
  FuseObserver observer;
  observer.progress = [&](size_t done, size_t) { o.progress.push_back(done); };
  observer.warning = [&](const std::string& w) { o.warnings.push_back(w); };
  observer.integrated = [&](const Frame& f, const Pose3f&, TsdfVolume&) {
    o.integrated.push_back(f.index);
    return Status::Ok();
  };
  Result<FuseReport> r = FuseDataset(dataset, indices, params, volume, observer);
  o.status = r.status();
  if (r.ok()) {
    o.frames = r->frames;
    o.skipped_no_pose = r->skipped_no_pose;
    o.skipped_no_depth = r->skipped_no_depth;
  }
  o.blocks = volume.SortedBlockIndices();
  for (const BlockIndex& b : o.blocks) o.block_data.push_back(*volume.FindBlock(b));
  o.mesh = ExtractMesh(volume);
  return o;
}

void ExpectSame(const Outcome& a, const Outcome& b, const std::string& what) {
  EXPECT_EQ(a.status.ok(), b.status.ok()) << what;
  EXPECT_EQ(a.status.message(), b.status.message()) << what;
  ASSERT_EQ(a.frames.size(), b.frames.size()) << what;
  for (size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].index, b.frames[i].index) << what;
    EXPECT_TRUE(a.frames[i].T_W_C.matrix() == b.frames[i].T_W_C.matrix()) << what;
    EXPECT_EQ(a.frames[i].depth_path, b.frames[i].depth_path) << what;
  }
  EXPECT_EQ(a.skipped_no_pose, b.skipped_no_pose) << what;
  EXPECT_EQ(a.skipped_no_depth, b.skipped_no_depth) << what;
  EXPECT_EQ(a.warnings, b.warnings) << what;
  EXPECT_EQ(a.progress, b.progress) << what;
  EXPECT_EQ(a.integrated, b.integrated) << what;
  ASSERT_EQ(a.blocks, b.blocks) << what;
  for (size_t i = 0; i < a.blocks.size(); ++i)
    ASSERT_EQ(std::memcmp(&a.block_data[i], &b.block_data[i], sizeof(TsdfBlock)), 0)
        << what << ": block " << i;
  EXPECT_EQ(a.mesh.positions, b.mesh.positions) << what;
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles) << what;
  EXPECT_EQ(a.mesh.colors, b.mesh.colors) << what;
  EXPECT_EQ(a.mesh.normals, b.mesh.normals) << what;
}

const VolumeParams kVolume{0.04f, 0.16f};

TEST(FusePrefetch, AnyDepthAndThreadCountBuildsTheSequentialLoopsVolumeAndMesh) {
  const RoomFrames dataset(24, {}, {5, 6}, {11});
  const Outcome sequential = Fuse(dataset, All(dataset), 0, 1, kVolume, 5.f);
  ASSERT_TRUE(sequential.status.ok()) << sequential.status.message();
  ASSERT_EQ(sequential.frames.size(), 21u);
  EXPECT_EQ(sequential.skipped_no_pose, 2u);
  EXPECT_EQ(sequential.skipped_no_depth, 1u);
  ASSERT_GT(sequential.mesh.num_triangles(), 0u);
  ASSERT_FALSE(sequential.mesh.colors.empty());
  for (int threads : {1, 2})
    for (size_t prefetch : {0, 1, 3, 8, 64})
      ExpectSame(sequential, Fuse(dataset, All(dataset), prefetch, threads, kVolume, 5.f),
                 std::to_string(threads) + " threads, prefetch " + std::to_string(prefetch));
}

TEST(FusePrefetch, ADecodeErrorStopsTheRunAtItsFrameNamingTheFile) {
  // Frame 9 cannot be read; frames after it are decoded ahead (and one after it fails too).
  const RoomFrames dataset(20, {9, 11});
  for (int threads : {1, 2})
    for (size_t prefetch : {0, 2, 8}) {
      const std::string what =
          std::to_string(threads) + " threads, prefetch " + std::to_string(prefetch);
      const Outcome o = Fuse(dataset, All(dataset), prefetch, threads, kVolume, 5.f);
      ASSERT_FALSE(o.status.ok()) << what;
      EXPECT_EQ(o.status.message(), "frame 9: room/depth_9.png: corrupt or truncated PNG") << what;
      // Frames 0..8 were fused, in order, and nothing after the bad one.
      EXPECT_EQ(o.integrated, (std::vector<size_t>{0, 1, 2, 3, 4, 5, 6, 7, 8})) << what;
      EXPECT_EQ(o.progress, (std::vector<size_t>{1, 2, 3, 4, 5, 6, 7, 8, 9})) << what;
    }
}

TEST(FusePrefetch, AStopRequestEndsTheRunBeforeTheSameFrame) {
  const RoomFrames dataset(16);
  for (size_t prefetch : {0, 4}) {
    ThreadLimit limit(2);
    FuseParams params;
    params.prefetch = prefetch;
    size_t polls = 0;
    FuseObserver observer;
    observer.stop_requested = [&] { return ++polls > 6; };
    TsdfVolume volume(kVolume);
    Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume, observer);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kCancelled);
    EXPECT_EQ(r.status().message(), "stopped before frame 6 (6 of 16 selected frames done)");
  }
}

TEST(FusePrefetch, TooDeepAPrefetchIsRefused) {
  const RoomFrames dataset(2);
  FuseParams params;
  params.prefetch = FuseParams::kMaxPrefetch + 1;
  TsdfVolume volume(kVolume);
  Result<FuseReport> r = FuseDataset(dataset, All(dataset), params, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("prefetch"), std::string::npos) << r.status().message();
}

// Shared data through the real readers and decoders (PNG depth, JPEG colour).
fs::path Icl() { return test::SharedDataDir() / "rgbd" / "iclnuim_office_traj0"; }

TEST(FusePrefetch, SharedIclFramesFuseIdenticallyWithAndWithoutPrefetch) {
  Result<std::unique_ptr<Dataset>> dataset = OpenDataset(Icl().string());
  ASSERT_TRUE(dataset.ok()) << dataset.status().message();
  std::vector<size_t> indices;
  for (size_t i = 0; i < 60; i += 3) indices.push_back(i);  // frame 0 has no pose: skipped
  const VolumeParams volume{0.03f, 0.12f};
  const Outcome sequential = Fuse(**dataset, indices, 0, 1, volume, 3.f);
  ASSERT_TRUE(sequential.status.ok()) << sequential.status.message();
  ASSERT_EQ(sequential.frames.size(), indices.size() - 1);
  for (int threads : {1, 2})
    for (size_t prefetch : {1, 3})
      ExpectSame(
          sequential, Fuse(**dataset, indices, prefetch, threads, volume, 3.f),
          "ICL, " + std::to_string(threads) + " threads, prefetch " + std::to_string(prefetch));
}

TEST(FusePrefetch, ACorruptSharedFrameIsNamedWhateverIsDecodedAhead) {
  // An ICL-layout copy of 12 frames with frame 7's depth PNG cut short.
  const test::TempDir dir("voxplan-prefetch");
  const fs::path root = dir.path() / "icl";
  fs::create_directories(root / "depth");
  fs::create_directories(root / "rgb");
  std::ofstream assoc(root / "associations.txt");
  for (int id = 1; id <= 12; ++id) {
    const std::string n = std::to_string(id);
    assoc << n << " depth/" << n << ".png " << n << " rgb/" << n << ".jpg\n";
    fs::copy_file(Icl() / "depth" / (n + ".png"), root / "depth" / (n + ".png"));
    fs::copy_file(Icl() / "rgb" / (n + ".jpg"), root / "rgb" / (n + ".jpg"));
  }
  assoc.close();
  fs::copy_file(Icl() / "traj0.gt.freiburg", root / "traj0.gt.freiburg");
  const fs::path bad = root / "depth" / "8.png";  // frame index 7
  fs::resize_file(bad, fs::file_size(bad) / 2);
  Result<std::unique_ptr<Dataset>> dataset = OpenDataset(root.string());
  ASSERT_TRUE(dataset.ok()) << dataset.status().message();
  const VolumeParams volume{0.05f, 0.2f};
  const Outcome sequential = Fuse(**dataset, All(**dataset), 0, 1, volume, 3.f);
  ASSERT_FALSE(sequential.status.ok());
  EXPECT_EQ(sequential.status.message().rfind("frame 7: " + bad.string() + ": ", 0), 0u)
      << sequential.status.message();
  for (int threads : {1, 2})
    for (size_t prefetch : {2, 6})
      ExpectSame(sequential, Fuse(**dataset, All(**dataset), prefetch, threads, volume, 3.f),
                 "corrupt ICL, " + std::to_string(threads) + " threads, prefetch " +
                     std::to_string(prefetch));
}

}  // namespace
}  // namespace voxplan
