// The pieces of sharded fusion in one process: the owner function, integration and meshing of
// a map split over ranks against the whole map (the band walk split too), sharded maps and their
// checks, checkpoints and resume with the serial communicator, the wire format's bounds and the
// task farm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "core/shard.h"
#include "distributed/communicator.h"
#include "distributed/shard_writer.h"
#include "distributed/sharded_fuse.h"
#include "distributed/task_farm.h"
#include "distributed/wire.h"
#include "fusion/integrate.h"
#include "fusion/mesh_block.h"
#include "fusion/mesh_extract.h"
#include "io/map_io.h"
#include "io/sharded_map.h"
#include "tests/fusion/box_room.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr float kVoxel = 0.05f, kTrunc = 0.2f;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A box room seen from a camera turning about the vertical at one point: exact depth, a colour
// per frame, the poses as ground truth.
class RoomDataset final : public Dataset {
 public:
  explicit RoomDataset(size_t frames) {
    info_.format = DatasetFormat::kTum;
    info_.root = "box room";
    info_.camera = test::RoomCamera(64);
    info_.depth_scale = 1000.0;
    info_.num_frames = frames;
    info_.has_color = true;
  }
  const DatasetInfo& info() const override { return info_; }
  Result<Frame> Load(size_t i) const override {
    Frame f;
    f.index = i;
    f.timestamp = double(i) / 30.0;
    const float a = 0.4f * float(i);
    const Eigen::Vector3f eye(0.2f * std::cos(a), 0.2f * std::sin(a), 0.1f);
    const Pose3f T = LookAt(eye, eye + Eigen::Vector3f(std::cos(a), std::sin(a), -0.2f));
    f.T_W_C = T.cast<double>();
    f.depth = test::RenderRoomDepth(room_, info_.camera, T);
    f.color = ColorImage(f.depth.width, f.depth.height, PackRgb(uint8_t(20 * i), 100, 200));
    f.depth_path = "frame" + std::to_string(i);
    return f;
  }

 private:
  DatasetInfo info_;
  test::BoxRoom room_{{-1.5f, -1.2f, -1.0f}, {1.4f, 1.3f, 1.1f}};
};

std::vector<size_t> AllFrames(const Dataset& d) {
  std::vector<size_t> v(d.info().num_frames);
  for (size_t i = 0; i < v.size(); ++i) v[i] = i;
  return v;
}

TsdfVolume FuseWhole(const Dataset& d) {
  TsdfVolume volume(VolumeParams{kVoxel, kTrunc});
  FuseParams params;
  params.prefetch = 0;
  Result<FuseReport> r = FuseDataset(d, AllFrames(d), params, volume);
  EXPECT_TRUE(r.ok()) << r.status().message();
  return volume;
}

bool SameBlocks(const TsdfBlock& a, const TsdfBlock& b) {
  return std::memcmp(&a, &b, sizeof(TsdfBlock)) == 0;
}

TEST(Shard, OwnerIsFixedPerChunkAndSpreadsOverRanks) {
  EXPECT_EQ(BlockOwner({5, -3, 9}, 1), 0u);
  // Every block of a chunk (8^3 blocks) has its chunk's owner, for negative indices too.
  for (int x = -8; x < 0; ++x) EXPECT_EQ(BlockOwner({x, 3, -17}, 4), BlockOwner({-8, 0, -24}, 4));
  // Chunks spread over ranks: each of 4 ranks owns 15-35 % of 1000 chunks.
  std::vector<int> count(4, 0);
  for (int c = 0; c < 1000; ++c)
    ++count[BlockOwner({8 * (c % 10), 8 * (c / 10 % 10), 8 * (c / 100)}, 4)];
  for (int n : count) {
    EXPECT_GT(n, 150);
    EXPECT_LT(n, 350);
  }
  IntegrateParams p;
  p.shard = {2, 2};
  EXPECT_FALSE(p.Validate().ok());
  p.shard = {0, kMaxShardRanks + 1};
  EXPECT_FALSE(p.Validate().ok());
}

TEST(Shard, SplitIntegrationEqualsTheWholeVolumeBlockForBlock) {
  const RoomDataset d(8);
  const TsdfVolume whole = FuseWhole(d);
  ASSERT_GT(whole.num_blocks(), 100u);
  for (uint32_t ranks : {2u, 3u, 4u}) {
    size_t blocks = 0;
    std::set<BlockIndex> seen;
    for (uint32_t rank = 0; rank < ranks; ++rank) {
      TsdfVolume part(VolumeParams{kVoxel, kTrunc});
      FuseParams params;
      params.integrate.shard = {rank, ranks};
      ASSERT_TRUE(FuseDataset(d, AllFrames(d), params, part).ok());
      part.ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
        EXPECT_EQ(BlockOwner(b, ranks), rank);
        EXPECT_TRUE(seen.insert(b).second) << "a block on two ranks";
        const TsdfBlock* w = whole.FindBlock(b);
        ASSERT_NE(w, nullptr);
        EXPECT_TRUE(SameBlocks(*w, block));
      });
      blocks += part.num_blocks();
    }
    EXPECT_EQ(blocks, whole.num_blocks()) << ranks << " ranks";
  }
}

// A band exchange between ranks simulated in one process: the first pass records what each rank
// found in its share of the walk; the second hands each rank its owned blocks of everyone's finds.
class RecordingExchange final : public BandExchange {
 public:
  explicit RecordingExchange(uint32_t ranks) : found_(ranks), ranks_(ranks) {}
  void Use(uint32_t rank, bool deliver) {
    rank_ = rank;
    deliver_ = deliver;
  }
  Result<std::vector<BlockIndex>> Exchange(const std::vector<BlockIndex>& found) override {
    if (!deliver_) {
      found_[rank_] = found;
      return std::vector<BlockIndex>{};
    }
    std::vector<BlockIndex> owned;
    for (const auto& part : found_)
      for (const BlockIndex& b : part)
        if (BlockOwner(b, ranks_) == rank_) owned.push_back(b);
    std::sort(owned.begin(), owned.end());
    owned.erase(std::unique(owned.begin(), owned.end()), owned.end());
    return owned;
  }
  std::vector<std::vector<BlockIndex>> found_;

 private:
  uint32_t ranks_, rank_ = 0;
  bool deliver_ = false;
};

TEST(Shard, ASplitBandWalkFindsTheWholeBandAndFusesTheSameBlocks) {
  const RoomDataset d(1);
  const Result<Frame> frame = d.Load(0);
  ASSERT_TRUE(frame.ok());
  const Pose3f T = Pose3f(frame->T_W_C->cast<float>());
  for (const bool carve : {false, true}) {
    IntegrateParams params;
    params.carve_free_space = carve;
    TsdfVolume whole(VolumeParams{kVoxel, kTrunc});
    ASSERT_TRUE(IntegrateFrame(frame->depth, frame->color, d.info().camera, T, params, whole).ok());
    const std::vector<BlockIndex> band =
        BlocksToUpdate(frame->depth, d.info().camera, T, params, whole.params());
    for (uint32_t ranks : {2u, 3u, 5u}) {
      RecordingExchange exchange(ranks);
      params.band_exchange = &exchange;
      std::set<BlockIndex> found;
      for (uint32_t rank = 0; rank < ranks; ++rank) {
        params.shard = {rank, ranks};
        exchange.Use(rank, /*deliver=*/false);
        TsdfVolume scratch(VolumeParams{kVoxel, kTrunc});
        ASSERT_TRUE(
            IntegrateFrame(frame->depth, frame->color, d.info().camera, T, params, scratch).ok());
        EXPECT_EQ(scratch.num_blocks(), 0u);
        // Each rank walks a part: never all of it.
        EXPECT_LT(exchange.found_[rank].size(), band.size()) << ranks << " ranks, carve " << carve;
        found.insert(exchange.found_[rank].begin(), exchange.found_[rank].end());
      }
      EXPECT_EQ(std::vector<BlockIndex>(found.begin(), found.end()), band)
          << ranks << " ranks, carve " << carve;
      size_t blocks = 0;
      for (uint32_t rank = 0; rank < ranks; ++rank) {
        params.shard = {rank, ranks};
        exchange.Use(rank, /*deliver=*/true);
        TsdfVolume part(VolumeParams{kVoxel, kTrunc});
        ASSERT_TRUE(
            IntegrateFrame(frame->depth, frame->color, d.info().camera, T, params, part).ok());
        part.ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
          EXPECT_EQ(BlockOwner(b, ranks), rank);
          EXPECT_TRUE(SameBlocks(*whole.FindBlock(b), block));
        });
        blocks += part.num_blocks();
      }
      EXPECT_EQ(blocks, whole.num_blocks());
    }
  }
}

TEST(Shard, PiecesMeshedPerRankWithTheirHaloWeldToTheWholeMesh) {
  const RoomDataset d(8);
  const TsdfVolume whole = FuseWhole(d);
  const Mesh reference = ExtractMesh(whole);
  ASSERT_GT(reference.num_triangles(), 1000u);
  const uint32_t ranks = 3;
  std::vector<std::pair<BlockIndex, internal::BlockMesh>> pieces;
  for (uint32_t rank = 0; rank < ranks; ++rank) {
    // The rank's blocks plus the halo its cubes read.
    TsdfVolume local(VolumeParams{kVoxel, kTrunc});
    std::vector<BlockIndex> own;
    for (const BlockIndex& b : whole.SortedBlockIndices())
      if (BlockOwner(b, ranks) == rank) {
        own.push_back(b);
        local.FindOrAllocate(b) = *whole.FindBlock(b);
      }
    for (const BlockIndex& b : own)
      for (const BlockIndex& n : MeshStencilNeighbours(b))
        if (const TsdfBlock* block = whole.FindBlock(n)) local.FindOrAllocate(n) = *block;
    std::vector<internal::BlockMesh> mine = MeshBlockPieces(local, own, MeshParams{});
    for (size_t i = 0; i < own.size(); ++i) pieces.emplace_back(own[i], std::move(mine[i]));
  }
  std::sort(pieces.begin(), pieces.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<const internal::BlockMesh*> pointers;
  for (const auto& p : pieces) pointers.push_back(&p.second);
  const Mesh split = AssembleMeshPieces(pointers, MeshParams{});
  EXPECT_EQ(split.positions, reference.positions);
  EXPECT_EQ(split.triangles, reference.triangles);
  EXPECT_EQ(split.colors, reference.colors);
  EXPECT_EQ(split.normals, reference.normals);
  // Without the halo the mesh has holes at the shard borders: the halo is what makes it whole.
  TsdfVolume alone(VolumeParams{kVoxel, kTrunc});
  std::vector<BlockIndex> own0;
  for (const BlockIndex& b : whole.SortedBlockIndices())
    if (BlockOwner(b, ranks) == 0) {
      own0.push_back(b);
      alone.FindOrAllocate(b) = *whole.FindBlock(b);
    }
  size_t with_halo = 0, without = 0;
  for (const auto& [b, piece] : pieces)
    if (BlockOwner(b, ranks) == 0) with_halo += piece.triangles.size();
  for (const auto& piece : MeshBlockPieces(alone, own0, MeshParams{}))
    without += piece.triangles.size();
  EXPECT_LT(without, with_halo);
}

TEST(ShardedMap, WritesReadsAndChecksItsShards) {
  const test::TempDir dir("voxplan-sharded-map");
  const RoomDataset d(6);
  const TsdfVolume whole = FuseWhole(d);
  SerialCommunicator comm;
  const std::string path = (dir / "m.vpmap").string();
  Result<ShardManifest> m =
      WriteShardedMap(comm, whole, path, 7, /*complete=*/false, {{"note", "x"}});
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_TRUE(IsShardedMapFile(path));
  EXPECT_FALSE(IsShardedMapFile((dir / m->shards[0].file).string()));
  Result<ShardManifest> read = ReadShardManifest(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->generation, 7u);
  EXPECT_FALSE(read->complete);
  EXPECT_EQ(read->shards[0].blocks, whole.num_blocks());
  EXPECT_EQ(read->shards[0].checksum, VolumeChecksum(whole));
  Result<TsdfVolume> loaded = LoadAnyMap(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  EXPECT_EQ(VolumeChecksum(*loaded), VolumeChecksum(whole));
  // Kept under another rank count: each block by its owner.
  Result<TsdfVolume> part = LoadShardedMap(path, ShardSpec{1, 2});
  ASSERT_TRUE(part.ok());
  part->ForEachBlock([](BlockIndex b, const TsdfBlock&) { EXPECT_EQ(BlockOwner(b, 2), 1u); });
  EXPECT_LT(part->num_blocks(), whole.num_blocks());

  // A new generation replaces the old shard only once its manifest is in place.
  Result<ShardManifest> next = WriteShardedMap(comm, whole, path, 9, true, {});
  ASSERT_TRUE(next.ok());
  EXPECT_FALSE(fs::exists(dir / m->shards[0].file));
  EXPECT_TRUE(fs::exists(dir / next->shards[0].file));

  // A killed run's half-written generation (shards, no manifest) goes with the next one; files
  // that only look like shards, or are another map's, stay.
  const std::vector<std::string> orphans = {"m.vpmap.g10.r0-of-3.vpmap",
                                            "m.vpmap.g10.r2-of-3.vpmap"};
  const std::vector<std::string> others = {"m.vpmap.g10.r1-of-3.vpmap.bak",
                                           "m.vpmap.gx.r0-of-1.vpmap", "m.vpmap.g10.r1-of-.vpmap",
                                           "n.vpmap.g10.r0-of-1.vpmap"};
  for (const std::string& name : orphans) std::ofstream(dir / name) << "x";
  for (const std::string& name : others) std::ofstream(dir / name) << "x";
  EXPECT_EQ(StaleShardFiles(path, *next), orphans);
  Result<ShardManifest> third = WriteShardedMap(comm, whole, path, 11, true, {});
  ASSERT_TRUE(third.ok());
  EXPECT_TRUE(StaleShardFiles(path, *third).empty());
  for (const std::string& name : orphans) EXPECT_FALSE(fs::exists(dir / name)) << name;
  for (const std::string& name : others) EXPECT_TRUE(fs::exists(dir / name)) << name;
  EXPECT_FALSE(fs::exists(dir / next->shards[0].file));
  ASSERT_TRUE(LoadAnyMap(path).ok());
  next = std::move(third);

  // Broken manifests are refused with the file's name and the reason.
  const std::string text = ReadFile(path);
  const auto refused = [&](const std::string& from, const std::string& to, const std::string& why) {
    std::string bad = text;
    const size_t at = bad.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    bad.replace(at, from.size(), to);
    const std::string bad_path = (dir / "bad.vpmap").string();
    std::ofstream(bad_path) << bad;
    Result<TsdfVolume> r = LoadAnyMap(bad_path);
    ASSERT_FALSE(r.ok()) << from;
    EXPECT_NE(r.status().message().find("bad.vpmap"), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(why), std::string::npos) << r.status().message();
  };
  refused(next->shards[0].file, "../" + next->shards[0].file, "not a file name in its folder");
  refused("\"ranks\": 1", "\"ranks\": 0", "ranks 0");
  refused("\"ranks\": 1", "\"ranks\": 2", "one shard per rank");
  refused("splitmix64", "murmur", "owner function");
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", (unsigned long long)next->shards[0].checksum);
  char other[17];
  std::snprintf(other, sizeof(other), "%016llx",
                (unsigned long long)(next->shards[0].checksum ^ 1));
  refused(hex, other, "does not match the manifest");
}

TEST(ShardedFuse, ACheckpointedRunStoppedAndResumedEqualsOneRun) {
  const test::TempDir dir("voxplan-checkpoint");
  const RoomDataset d(12);
  const TsdfVolume whole = FuseWhole(d);
  const std::vector<size_t> frames = AllFrames(d);
  SerialCommunicator comm;
  ShardedFuseParams params;
  params.fuse.prefetch = 2;
  params.checkpoint_path = (dir / "c.vpmap").string();
  params.checkpoint_every = 3;
  params.fingerprint = {{"run", "room"}};

  // Stopped before frame 8: the last checkpoint holds 6 frames.
  TsdfVolume first(VolumeParams{kVoxel, kTrunc});
  FuseObserver stop_at_8;
  size_t polled = 0;
  stop_at_8.stop_requested = [&] { return polled++ == 8; };
  Result<ShardedFuseReport> stopped =
      FuseDatasetSharded(comm, &d, d.info(), frames, params, first, stop_at_8);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.status().code(), StatusCode::kCancelled);
  Result<ShardManifest> checkpoint = ReadShardManifest(params.checkpoint_path);
  ASSERT_TRUE(checkpoint.ok()) << checkpoint.status().message();
  EXPECT_EQ(checkpoint->generation, 6u);

  // Another run's checkpoint is refused.
  ShardedFuseParams other = params;
  other.resume = true;
  other.fingerprint = {{"run", "another"}};
  TsdfVolume refused(VolumeParams{kVoxel, kTrunc});
  Result<ShardedFuseReport> wrong = FuseDatasetSharded(comm, &d, d.info(), frames, other, refused);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.status().message().find("another run"), std::string::npos);

  params.resume = true;
  TsdfVolume resumed(VolumeParams{kVoxel, kTrunc});
  Result<ShardedFuseReport> rest = FuseDatasetSharded(comm, &d, d.info(), frames, params, resumed);
  ASSERT_TRUE(rest.ok()) << rest.status().message();
  EXPECT_EQ(rest->frames_resumed, 6u);
  EXPECT_EQ(rest->report.frames.size(), 12u);
  EXPECT_EQ(rest->report.frames_selected, 12u);
  EXPECT_EQ(VolumeChecksum(resumed), VolumeChecksum(whole));
  for (size_t i = 0; i < 12; ++i) EXPECT_EQ(rest->report.frames[i].index, i);
}

TEST(ShardedFuse, ReportsSurviveJsonBitForBit) {
  FuseReport r;
  r.frames.push_back({3, 0.1, Pose3f(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitZ())), "d", "c"});
  r.frames[0].T_W_C.translation() = Eigen::Vector3f(0.1f, 1e-7f, -3.3f);
  r.load_ms = {1.5, 2.25};
  r.skipped_bad_pose = 4;
  Result<FuseReport> back = FuseReportFromJson(FuseReportToJson(r));
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_TRUE(back->frames[0].T_W_C.matrix() == r.frames[0].T_W_C.matrix());
  EXPECT_EQ(back->load_ms, r.load_ms);
  EXPECT_EQ(back->skipped_bad_pose, 4u);
  EXPECT_FALSE(FuseReportFromJson(nlohmann::json::object()).ok());
}

TEST(Wire, ReadersStopAtTheEndOfWhatArrived) {
  wire::Writer w;
  w.Put(uint32_t(7));
  w.PutVector(std::vector<uint16_t>{1, 2, 3});
  w.PutString("abc");
  Bytes bytes = w.Take();
  {
    wire::Reader r(bytes);
    uint32_t a = 0;
    std::vector<uint16_t> v;
    std::string s;
    EXPECT_TRUE(r.Get(a) && r.GetVector(v) && r.GetString(s));
    EXPECT_TRUE(r.Finish("x").ok());
    EXPECT_EQ(v, (std::vector<uint16_t>{1, 2, 3}));
    EXPECT_EQ(s, "abc");
  }
  // A length field claiming more than arrived fails instead of reading past the end.
  bytes[4] = 0xff;
  wire::Reader r(bytes);
  uint32_t a = 0;
  std::vector<uint16_t> v;
  EXPECT_TRUE(r.Get(a));
  EXPECT_FALSE(r.GetVector(v));
  EXPECT_FALSE(r.Finish("x").ok());
}

TEST(TaskFarm, RunsEveryTaskWithoutMpiVariablesAndCountsFailures) {
  const test::TempDir dir("voxplan-farm");
  const fs::path tasks = dir / "tasks.txt";
  {
    std::ofstream f(tasks);
    f << "# a comment\n\n";
    for (int i = 0; i < 4; ++i)
      f << "echo " << i << " > " << (dir / ("t" + std::to_string(i))).string() << "\n";
    f << "env | grep -c '^OMPI_' > " << (dir / "env").string() << "; exit 3\n";
  }
  Result<std::vector<FarmTask>> read = ReadFarmTasks(tasks.string());
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->size(), 5u);
  setenv("OMPI_COMM_WORLD_FAKE", "1", 1);
  SerialCommunicator comm;
  size_t finished = 0;
  FarmObserver observer;
  observer.finished = [&](size_t, int, int rank, size_t) {
    EXPECT_EQ(rank, 0);
    ++finished;
  };
  Result<FarmResult> r = RunTaskFarm(comm, *read, observer);
  unsetenv("OMPI_COMM_WORLD_FAKE");
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(finished, 5u);
  EXPECT_EQ(r->failed, 1u);
  EXPECT_EQ(r->exit_codes, (std::vector<int>{0, 0, 0, 0, 3}));
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(ReadFile(dir / ("t" + std::to_string(i))), std::to_string(i) + "\n");
  EXPECT_EQ(ReadFile(dir / "env"), "0\n");

  std::ofstream(dir / "nul.txt") << "echo a\n" << std::string("echo \0b", 7) << "\n";
  Result<std::vector<FarmTask>> bad = ReadFarmTasks((dir / "nul.txt").string());
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("nul.txt:2"), std::string::npos) << bad.status().message();
}

}  // namespace
}  // namespace voxplan
