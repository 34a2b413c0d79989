#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <random>

#include "io/file_util.h"
#include "io/map_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr size_t kHeaderBytes = 32;    // version 2: the up axis after the block count
constexpr size_t kHeaderBytesV1 = 28;  // version 1: no up axis
constexpr size_t kRecordBytes = 12 + sizeof(TsdfBlock);

// Blocks at random indices (negative ones included) filled with random bytes; inserted in
// `order` so tests can check the file does not depend on insertion order.
TsdfVolume RandomVolume(uint32_t seed, int num_blocks, bool reverse_order = false) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> coord(-40, 40);
  std::vector<BlockIndex> indices;
  while (int(indices.size()) < num_blocks) {
    const BlockIndex b{coord(rng), coord(rng), coord(rng)};
    if (std::find(indices.begin(), indices.end(), b) == indices.end()) indices.push_back(b);
  }
  std::vector<std::vector<unsigned char>> payloads;
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < num_blocks; ++i) {
    payloads.emplace_back(sizeof(TsdfBlock));
    for (auto& c : payloads.back()) c = static_cast<unsigned char>(byte(rng));
  }
  TsdfVolume volume(VolumeParams{0.05f, 0.2f});
  for (int k = 0; k < num_blocks; ++k) {
    const int i = reverse_order ? num_blocks - 1 - k : k;
    std::memcpy(&volume.FindOrAllocate(indices[i]), payloads[i].data(), sizeof(TsdfBlock));
  }
  return volume;
}

void ExpectIdentical(const TsdfVolume& a, const TsdfVolume& b) {
  EXPECT_EQ(a.voxel_size_m(), b.voxel_size_m());
  EXPECT_EQ(a.trunc_m(), b.trunc_m());
  const auto blocks = a.SortedBlockIndices();
  ASSERT_TRUE(blocks == b.SortedBlockIndices());
  for (const BlockIndex& idx : blocks) {
    const TsdfBlock* pa = a.FindBlock(idx);
    const TsdfBlock* pb = b.FindBlock(idx);
    ASSERT_TRUE(pa && pb);
    EXPECT_EQ(std::memcmp(pa, pb, sizeof(TsdfBlock)), 0);
  }
}

std::string Bytes(const std::string& path) {
  auto r = ReadFileToString(path);
  EXPECT_TRUE(r.ok()) << r.status().message();
  return r.ok() ? *r : std::string();
}
void Store(const std::string& path, const std::string& bytes) {
  ASSERT_TRUE(WriteStringToFile(path, bytes).ok());
}

// The checksum the format uses (FNV-1a 64), to build files that are consistent but wrong.
std::string WithFreshChecksum(std::string bytes) {
  bytes.resize(bytes.size() - 8);
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ull;
  bytes.append(reinterpret_cast<const char*>(&h), 8);
  return bytes;
}

// Loads `bytes` from a file and expects a refusal with `code` whose message names the file and
// contains `what`.
void ExpectRefused(const test::TempDir& dir, const std::string& bytes, StatusCode code,
                   const std::string& what) {
  const std::string path = (dir / "bad.vpmap").string();
  Store(path, bytes);
  auto loaded = LoadMap(path);
  ASSERT_FALSE(loaded.ok()) << what;
  EXPECT_EQ(loaded.status().code(), code) << loaded.status().message();
  EXPECT_NE(loaded.status().message().find(path), std::string::npos) << loaded.status().message();
  EXPECT_NE(loaded.status().message().find(what), std::string::npos) << loaded.status().message();
}

std::vector<std::string> Listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(MapIo, RoundTripIsBitIdentical) {
  test::TempDir dir("map_io");
  const TsdfVolume volume = RandomVolume(7, 300);
  const std::string path = (dir / "room.vpmap").string();
  ASSERT_TRUE(SaveMap(volume, path).ok());
  EXPECT_EQ(fs::file_size(path), kHeaderBytes + 300 * kRecordBytes + 8);
  auto loaded = LoadMap(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  ExpectIdentical(volume, *loaded);

  auto header = ReadMapHeader(path);
  ASSERT_TRUE(header.ok()) << header.status().message();
  EXPECT_EQ(header->version, kMapFormatVersion);
  EXPECT_EQ(header->num_blocks, 300u);
  EXPECT_EQ(header->params.voxel_size_m, 0.05f);
  EXPECT_EQ(header->params.trunc_m, 0.2f);
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"room.vpmap"});
}

TEST(MapIo, EmptyVolumeRoundTrips) {
  test::TempDir dir("map_io");
  const TsdfVolume volume(VolumeParams{0.02f, 0.08f});
  const std::string path = (dir / "empty.vpmap").string();
  ASSERT_TRUE(SaveMap(volume, path).ok());
  auto loaded = LoadMap(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  EXPECT_EQ(loaded->num_blocks(), 0u);
  EXPECT_EQ(loaded->voxel_size_m(), 0.02f);
}

TEST(MapIo, BytesDoNotDependOnInsertionOrderOrRepeat) {
  test::TempDir dir("map_io");
  const std::string a = (dir / "a.vpmap").string(), b = (dir / "b.vpmap").string(),
                    c = (dir / "c.vpmap").string();
  const TsdfVolume volume = RandomVolume(11, 100);
  ASSERT_TRUE(SaveMap(volume, a).ok());
  ASSERT_TRUE(SaveMap(volume, b).ok());
  ASSERT_TRUE(SaveMap(RandomVolume(11, 100, /*reverse_order=*/true), c).ok());
  EXPECT_EQ(Bytes(a), Bytes(b));
  EXPECT_EQ(Bytes(a), Bytes(c));
  // Saving over an existing map replaces it.
  ASSERT_TRUE(SaveMap(RandomVolume(12, 5), a).ok());
  EXPECT_EQ(fs::file_size(a), kHeaderBytes + 5 * kRecordBytes + 8);
}

TEST(MapIo, RefusesTruncatedFiles) {
  test::TempDir dir("map_io");
  const std::string good = (dir / "good.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(3, 20), good).ok());
  const std::string bytes = Bytes(good);
  for (size_t keep :
       {size_t(0), size_t(5), kHeaderBytes - 1, kHeaderBytes, kHeaderBytes + 7,
        kHeaderBytes + kRecordBytes, bytes.size() - 9, bytes.size() - 8, bytes.size() - 1}) {
    SCOPED_TRACE(keep);
    ExpectRefused(dir, bytes.substr(0, keep), StatusCode::kCorruptData, "truncated");
    const std::string path = (dir / "bad.vpmap").string();
    EXPECT_FALSE(ReadMapHeader(path).ok());
  }
  // Extra bytes after the checksum are refused as well.
  ExpectRefused(dir, bytes + std::string(kRecordBytes, '\0'), StatusCode::kCorruptData,
                "announces 20 blocks");
}

TEST(MapIo, RefusesCorruptedBytes) {
  test::TempDir dir("map_io");
  const std::string good = (dir / "good.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(5, 20), good).ok());
  const std::string bytes = Bytes(good);
  // A flipped bit in voxel data, in a block index, and in the checksum itself.
  for (size_t at : {kHeaderBytes + 5 * kRecordBytes + 12 + 1000, kHeaderBytes + 2 * kRecordBytes,
                    bytes.size() - 3}) {
    SCOPED_TRACE(at);
    std::string bad = bytes;
    bad[at] = char(bad[at] ^ 0x10);
    ExpectRefused(dir, bad, StatusCode::kCorruptData, "checksum mismatch");
  }
}

TEST(MapIo, RefusesWrongVersionAndBadMagic) {
  test::TempDir dir("map_io");
  const std::string good = (dir / "good.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(5, 3), good).ok());
  const std::string bytes = Bytes(good);

  std::string version7 = bytes;
  const uint32_t seven = 7;
  std::memcpy(version7.data() + 8, &seven, 4);
  ExpectRefused(dir, WithFreshChecksum(version7), StatusCode::kUnsupported,
                "version 7, this build reads versions 1 to 2");
  auto header = ReadMapHeader((dir / "bad.vpmap").string());
  EXPECT_EQ(header.status().code(), StatusCode::kUnsupported);

  std::string magic = bytes;
  magic[0] = 'P';
  ExpectRefused(dir, WithFreshChecksum(magic), StatusCode::kCorruptData, "magic");
  ExpectRefused(dir, std::string(200, 'x'), StatusCode::kCorruptData, "magic");
}

TEST(MapIo, RefusesInvalidParamsAndDuplicateBlocks) {
  test::TempDir dir("map_io");
  const std::string good = (dir / "good.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(9, 4), good).ok());
  const std::string bytes = Bytes(good);

  std::string params = bytes;
  const float negative = -0.05f;
  std::memcpy(params.data() + 12, &negative, 4);
  ExpectRefused(dir, WithFreshChecksum(params), StatusCode::kCorruptData, "voxel size");
  std::string trunc = bytes;
  const float tiny = 0.001f;
  std::memcpy(trunc.data() + 16, &tiny, 4);
  ExpectRefused(dir, WithFreshChecksum(trunc), StatusCode::kCorruptData, "truncation");

  // Block 1 given block 0's index: a well-formed file with a repeated block.
  std::string duplicate = bytes;
  std::memcpy(duplicate.data() + kHeaderBytes + kRecordBytes, bytes.data() + kHeaderBytes, 12);
  ExpectRefused(dir, WithFreshChecksum(duplicate), StatusCode::kCorruptData, "duplicate block");

  // Blocks out of their sorted order.
  std::string swapped = bytes;
  std::memcpy(swapped.data() + kHeaderBytes, bytes.data() + kHeaderBytes + kRecordBytes,
              kRecordBytes);
  std::memcpy(swapped.data() + kHeaderBytes + kRecordBytes, bytes.data() + kHeaderBytes,
              kRecordBytes);
  ExpectRefused(dir, WithFreshChecksum(swapped), StatusCode::kCorruptData, "sorted order");

  // A block count that would overflow a size computation.
  std::string huge = bytes;
  const uint64_t count = ~0ull / 3;
  std::memcpy(huge.data() + 20, &count, 8);
  ExpectRefused(dir, WithFreshChecksum(huge), StatusCode::kCorruptData, "truncated");
}

TEST(MapIo, UpAxisRoundTrips) {
  test::TempDir dir("map_io");
  const TsdfVolume volume = RandomVolume(13, 20);
  for (WorldUp up : {WorldUp::kUnknown, WorldUp::kPlusX, WorldUp::kMinusX, WorldUp::kPlusY,
                     WorldUp::kMinusY, WorldUp::kPlusZ, WorldUp::kMinusZ}) {
    SCOPED_TRACE(WorldUpName(up));
    const std::string path = (dir / "up.vpmap").string();
    ASSERT_TRUE(SaveMap(volume, path, up).ok());
    const std::string bytes = Bytes(path);
    ASSERT_EQ(bytes.size(), kHeaderBytes + 20 * kRecordBytes + 8);
    uint32_t stored = 99;
    std::memcpy(&stored, bytes.data() + 28, 4);
    EXPECT_EQ(stored, uint32_t(up));
    WorldUp loaded_up = WorldUp::kMinusZ == up ? WorldUp::kPlusX : WorldUp::kMinusZ;
    auto loaded = LoadMap(path, &loaded_up);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    EXPECT_EQ(loaded_up, up);
    ExpectIdentical(volume, *loaded);
    auto header = ReadMapHeader(path);
    ASSERT_TRUE(header.ok());
    EXPECT_EQ(header->version, 2u);
    EXPECT_EQ(header->up, up);
  }
  // A default save records no up axis; the up axis changes the bytes, the blocks not.
  const std::string a = (dir / "a.vpmap").string(), b = (dir / "b.vpmap").string();
  ASSERT_TRUE(SaveMap(volume, a).ok());
  ASSERT_TRUE(SaveMap(volume, b, WorldUp::kPlusY).ok());
  EXPECT_EQ(ReadMapHeader(a)->up, WorldUp::kUnknown);
  const std::string bytes_a = Bytes(a), bytes_b = Bytes(b);
  ASSERT_EQ(bytes_a.size(), bytes_b.size());
  EXPECT_NE(bytes_a.substr(0, kHeaderBytes), bytes_b.substr(0, kHeaderBytes));
  const size_t blocks_bytes = bytes_a.size() - kHeaderBytes - 8;
  EXPECT_EQ(bytes_a.substr(kHeaderBytes, blocks_bytes), bytes_b.substr(kHeaderBytes, blocks_bytes));
}

// Version 1 files, written before the up axis: the same header without it, the checksum over
// what is there. They load as they did, with the up axis unknown.
TEST(MapIo, ReadsVersionOneFilesAsUnknownUp) {
  test::TempDir dir("map_io");
  const TsdfVolume volume = RandomVolume(17, 30);
  const std::string v2 = (dir / "v2.vpmap").string();
  ASSERT_TRUE(SaveMap(volume, v2, WorldUp::kPlusY).ok());
  const std::string bytes = Bytes(v2);
  std::string v1 = bytes.substr(0, kHeaderBytesV1) + bytes.substr(kHeaderBytes);
  const uint32_t one = 1;
  std::memcpy(v1.data() + 8, &one, 4);
  v1 = WithFreshChecksum(v1);
  ASSERT_EQ(v1.size(), kHeaderBytesV1 + 30 * kRecordBytes + 8);
  const std::string path = (dir / "v1.vpmap").string();
  Store(path, v1);
  WorldUp up = WorldUp::kPlusY;
  auto loaded = LoadMap(path, &up);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  EXPECT_EQ(up, WorldUp::kUnknown);
  ExpectIdentical(volume, *loaded);
  auto header = ReadMapHeader(path);
  ASSERT_TRUE(header.ok()) << header.status().message();
  EXPECT_EQ(header->version, 1u);
  EXPECT_EQ(header->num_blocks, 30u);
  EXPECT_EQ(header->up, WorldUp::kUnknown);
  // An empty version 1 map: header and checksum only.
  std::string empty = std::string(v1.data(), kHeaderBytesV1);
  const uint64_t none = 0;
  std::memcpy(empty.data() + 20, &none, 8);
  empty = WithFreshChecksum(empty + std::string(8, '\0'));
  Store(path, empty);
  auto nothing = LoadMap(path, &up);
  ASSERT_TRUE(nothing.ok()) << nothing.status().message();
  EXPECT_EQ(nothing->num_blocks(), 0u);
  // Saved again, it becomes version 2 with the same blocks.
  ASSERT_TRUE(SaveMap(*loaded, (dir / "again.vpmap").string()).ok());
  EXPECT_EQ(ReadMapHeader((dir / "again.vpmap").string())->version, kMapFormatVersion);
  // Its damage is found as before: a truncated version 1 file, a flipped bit.
  ExpectRefused(dir, v1.substr(0, kHeaderBytesV1 + 5), StatusCode::kCorruptData, "truncated");
  std::string flipped = v1;
  flipped[kHeaderBytesV1 + 100] = char(flipped[kHeaderBytesV1 + 100] ^ 1);
  ExpectRefused(dir, flipped, StatusCode::kCorruptData, "checksum mismatch");
}

TEST(MapIo, RefusesAnUnknownUpAxisCode) {
  test::TempDir dir("map_io");
  const std::string good = (dir / "good.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(5, 3), good).ok());
  std::string bad = Bytes(good);
  const uint32_t seven = 7;
  std::memcpy(bad.data() + 28, &seven, 4);
  ExpectRefused(dir, WithFreshChecksum(bad), StatusCode::kCorruptData, "invalid up axis 7");
  EXPECT_FALSE(ReadMapHeader((dir / "bad.vpmap").string()).ok());
  EXPECT_FALSE(SaveMap(RandomVolume(5, 3), good, WorldUp(9)).ok());
}

TEST(MapIo, MissingFileIsNotFound) {
  test::TempDir dir("map_io");
  const std::string path = (dir / "missing.vpmap").string();
  auto loaded = LoadMap(path);
  EXPECT_EQ(loaded.status().code(), StatusCode::kNotFound);
  EXPECT_NE(loaded.status().message().find(path), std::string::npos);
  EXPECT_EQ(ReadMapHeader(path).status().code(), StatusCode::kNotFound);
}

TEST(MapIo, SaveToUnwritablePathLeavesNothing) {
  test::TempDir dir("map_io");
  const std::string nowhere = (dir / "no_such_folder" / "map.vpmap").string();
  const Status s = SaveMap(RandomVolume(1, 3), nowhere);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(nowhere), std::string::npos) << s.message();
  EXPECT_TRUE(Listing(dir.path()).empty());

  // A folder in the way of the target: the rename fails and the temporary file goes away.
  fs::create_directory(dir / "taken.vpmap");
  EXPECT_FALSE(SaveMap(RandomVolume(1, 3), (dir / "taken.vpmap").string()).ok());
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"taken.vpmap"});

  if (::geteuid() != 0) {  // root ignores folder permissions
    fs::create_directory(dir / "readonly");
    fs::permissions(dir / "readonly", fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_FALSE(SaveMap(RandomVolume(1, 3), (dir / "readonly" / "map.vpmap").string()).ok());
    fs::permissions(dir / "readonly", fs::perms::owner_all);
    EXPECT_TRUE(fs::is_empty(dir / "readonly"));
  }
}

// A write that fails halfway (file size limit, as on a full disk) keeps the old map intact.
TEST(MapIo, FailedSaveKeepsExistingMap) {
  test::TempDir dir("map_io");
  const std::string path = (dir / "map.vpmap").string();
  ASSERT_TRUE(SaveMap(RandomVolume(21, 2), path).ok());
  const std::string before = Bytes(path);

  rlimit old_limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit small = old_limit;
  small.rlim_cur = 64 * 1024;
  auto* old_handler = ::signal(SIGXFSZ, SIG_IGN);  // get EFBIG instead of being killed
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const Status s = SaveMap(RandomVolume(22, 200), path);  // about 720 kB
  ::setrlimit(RLIMIT_FSIZE, &old_limit);
  ::signal(SIGXFSZ, old_handler);

  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_EQ(Bytes(path), before);
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"map.vpmap"});
  auto loaded = LoadMap(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  ExpectIdentical(RandomVolume(21, 2), *loaded);
}

}  // namespace
}  // namespace voxplan
