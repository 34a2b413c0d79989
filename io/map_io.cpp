#include "io/map_io.h"

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <type_traits>

#include "core/fnv1a.h"  // streamed, so neither save nor load holds a second copy
#include "io/file_util.h"

namespace voxplan {

// The format is the in-memory layout of little-endian hosts; a big-endian build would need
// byte swapping here.
static_assert(std::endian::native == std::endian::little, "map files assume a little-endian host");

namespace {

// The header: magic, version (uint32), voxel size and truncation (float32 metres), block count
// (uint64), then from version 2 the world's up axis (uint32, WorldUp's value: 0 unknown, 1 +x,
// 2 -x, 3 +y, 4 -y, 5 +z, 6 -z). Version 1 files end their header before the up axis.
constexpr char kMagic[8] = {'V', 'X', 'P', 'L', 'M', 'A', 'P', '\0'};
constexpr size_t kHeaderBytesV1 = 8 + 4 + 4 + 4 + 8;
constexpr size_t kUpOffset = kHeaderBytesV1;
constexpr size_t kMaxHeaderBytes = kHeaderBytesV1 + 4;
constexpr size_t HeaderBytes(uint32_t version) {
  return version >= 2 ? kMaxHeaderBytes : kHeaderBytesV1;
}
constexpr size_t kBlockRecordBytes = 3 * sizeof(int32_t) + sizeof(TsdfBlock);
constexpr size_t kChecksumBytes = 8;
static_assert(sizeof(kMagic) == 8);

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

template <typename T>
void Put(std::string& out, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
T Get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

std::string BlockName(BlockIndex b) {
  // Appended piecewise: `"(" + std::to_string(...)` trips a false -Wrestrict in GCC 12.
  std::string s = "(";
  s += std::to_string(b.x);
  s += ", ";
  s += std::to_string(b.y);
  s += ", ";
  s += std::to_string(b.z);
  s += ")";
  return s;
}

Status CheckParams(const VolumeParams& p) {
  if (!(std::isfinite(p.voxel_size_m) && p.voxel_size_m > 0.0f))
    return CorruptData("invalid voxel size " + std::to_string(p.voxel_size_m) + " m");
  if (!(std::isfinite(p.trunc_m) && p.trunc_m >= p.voxel_size_m))
    return CorruptData("invalid truncation " + std::to_string(p.trunc_m) + " m for voxel size " +
                       std::to_string(p.voxel_size_m) + " m");
  return Status::Ok();
}

// Parses and checks the header against the file's size. Messages name what is wrong; callers
// add the file name.
Result<MapHeader> ParseHeader(const char* bytes, size_t available, uint64_t file_size) {
  const auto truncated = [&] {
    return CorruptData("truncated: " + std::to_string(file_size) +
                       " bytes, shorter than the map header");
  };
  if (available < kHeaderBytesV1 || file_size < kHeaderBytesV1) return truncated();
  if (std::memcmp(bytes, kMagic, sizeof(kMagic)) != 0)
    return CorruptData("not a voxplan map (bad magic)");
  MapHeader header;
  header.version = Get<uint32_t>(bytes + 8);
  if (header.version < kMapFormatOldestVersion || header.version > kMapFormatVersion)
    return Unsupported("format version " + std::to_string(header.version) +
                       ", this build reads versions " + std::to_string(kMapFormatOldestVersion) +
                       " to " + std::to_string(kMapFormatVersion));
  const size_t header_bytes = HeaderBytes(header.version);
  if (available < header_bytes || file_size < header_bytes) return truncated();
  header.params.voxel_size_m = Get<float>(bytes + 12);
  header.params.trunc_m = Get<float>(bytes + 16);
  header.num_blocks = Get<uint64_t>(bytes + 20);
  if (header.version >= 2) {
    const uint32_t code = Get<uint32_t>(bytes + kUpOffset);
    const std::optional<WorldUp> up = WorldUpFromCode(code);
    if (!up) return CorruptData("invalid up axis " + std::to_string(code) + " (0 to 6)");
    header.up = *up;
  }
  VOXPLAN_RETURN_IF_ERROR(CheckParams(header.params));
  // Compared by division first so a corrupt count cannot overflow the expected size.
  const uint64_t payload = file_size - header_bytes;
  const bool too_many = header.num_blocks > payload / kBlockRecordBytes;
  const uint64_t expected =
      too_many ? 0 : header_bytes + header.num_blocks * kBlockRecordBytes + kChecksumBytes;
  if (too_many || file_size < expected)
    return CorruptData("truncated: the header announces " + std::to_string(header.num_blocks) +
                       " blocks but the file has only " + std::to_string(file_size) + " bytes");
  if (file_size != expected)
    return CorruptData("the header announces " + std::to_string(header.num_blocks) + " blocks (" +
                       std::to_string(expected) + " bytes) but the file has " +
                       std::to_string(file_size) + " bytes");
  return header;
}

Result<uint64_t> FileSize(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return NotFound("no such map file: " + path);
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return IoError("cannot stat " + path + ": " + ec.message());
  return uint64_t(size);
}

Result<File> OpenForReading(const std::string& path) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) return IoError("cannot open " + path + ": " + std::strerror(errno));
  return f;
}

Status WriteMapFile(const TsdfVolume& volume, const std::vector<BlockIndex>& blocks, WorldUp up,
                    const std::string& path) {
  File f(std::fopen(path.c_str(), "wb"));
  if (!f) return IoError("cannot open " + path + " for writing: " + std::strerror(errno));
  Fnv1a64 hash;
  std::string buffer;
  buffer.reserve(size_t(1) << 20);
  auto flush = [&]() -> bool {
    hash.Update(buffer.data(), buffer.size());
    const bool ok = std::fwrite(buffer.data(), 1, buffer.size(), f.get()) == buffer.size();
    buffer.clear();
    return ok;
  };
  buffer.append(kMagic, sizeof(kMagic));
  Put(buffer, kMapFormatVersion);
  Put(buffer, volume.params().voxel_size_m);
  Put(buffer, volume.params().trunc_m);
  Put(buffer, uint64_t(blocks.size()));
  Put(buffer, uint32_t(up));
  for (const BlockIndex& b : blocks) {
    const TsdfBlock* block = volume.FindBlock(b);
    assert(block);
    Put(buffer, b.x);
    Put(buffer, b.y);
    Put(buffer, b.z);
    buffer.append(reinterpret_cast<const char*>(block), sizeof(TsdfBlock));
    if (buffer.size() >= (size_t(1) << 20) && !flush())
      return IoError("cannot write " + path + ": " + std::strerror(errno));
  }
  if (!flush()) return IoError("cannot write " + path + ": " + std::strerror(errno));
  Put(buffer, hash.value());
  if (std::fwrite(buffer.data(), 1, buffer.size(), f.get()) != buffer.size())
    return IoError("cannot write " + path + ": " + std::strerror(errno));
  if (std::fclose(f.release()) != 0)
    return IoError("cannot write " + path + ": " + std::strerror(errno));
  return Status::Ok();
}

}  // namespace

bool IsMapPath(const std::string& path) {
  return std::filesystem::path(path).extension() == ".vpmap";
}

Status SaveMap(const TsdfVolume& volume, const std::string& path, WorldUp up) {
  if (!WorldUpFromCode(uint32_t(up))) return InvalidArgument("invalid up axis for " + path);
  const std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
  return WriteAtomically(
      path, [&](const std::string& tmp) { return WriteMapFile(volume, blocks, up, tmp); });
}

Result<MapHeader> ReadMapHeader(const std::string& path) {
  const Result<uint64_t> size = FileSize(path);
  if (!size.ok()) return size.status();
  Result<File> f = OpenForReading(path);
  if (!f.ok()) return f.status();
  char bytes[kMaxHeaderBytes];
  const size_t got = std::fread(bytes, 1, sizeof(bytes), f->get());
  Result<MapHeader> header = ParseHeader(bytes, got, *size);
  if (!header.ok()) return header.status().WithContext("map " + path);
  return header;
}

Result<TsdfVolume> LoadMap(const std::string& path, WorldUp* up) {
  const Result<uint64_t> size = FileSize(path);
  if (!size.ok()) return size.status();
  Result<File> file = OpenForReading(path);
  if (!file.ok()) return file.status();
  std::FILE* f = file->get();
  const std::string context = "map " + path;

  Fnv1a64 hash;
  // As many bytes as the longest header; a shorter (older) one is followed by the blocks.
  char header_bytes[kMaxHeaderBytes];
  const size_t got = std::fread(header_bytes, 1, sizeof(header_bytes), f);
  const Result<MapHeader> header = ParseHeader(header_bytes, got, *size);
  if (!header.ok()) return header.status().WithContext(context);
  const size_t header_size = HeaderBytes(header->version);
  hash.Update(header_bytes, header_size);
  if (got != header_size && std::fseek(f, long(header_size), SEEK_SET) != 0)
    return IoError("cannot read " + path + ": " + std::strerror(errno));

  // Blocks stream straight into the volume. Structural problems are remembered rather than
  // returned at once, so a damaged file is reported as a checksum mismatch (the likelier cause)
  // when the checksum disagrees too.
  TsdfVolume volume(header->params);
  std::optional<Status> problem;
  std::optional<BlockIndex> previous;
  char index_bytes[3 * sizeof(int32_t)];
  TsdfBlock scratch;
  for (uint64_t i = 0; i < header->num_blocks; ++i) {
    if (std::fread(index_bytes, 1, sizeof(index_bytes), f) != sizeof(index_bytes))
      return IoError("cannot read " + path + ": short read in block " + std::to_string(i));
    hash.Update(index_bytes, sizeof(index_bytes));
    const BlockIndex b{Get<int32_t>(index_bytes), Get<int32_t>(index_bytes + 4),
                       Get<int32_t>(index_bytes + 8)};
    if (!problem) {
      if (!InPackRange(b))
        problem = CorruptData("block " + std::to_string(i) + " index " + BlockName(b) +
                              " is out of range");
      else if (previous && *previous == b)
        problem = CorruptData("duplicate block " + BlockName(b));
      else if (previous && b < *previous)
        problem = CorruptData("block " + BlockName(b) + " is out of sorted order");
    }
    previous = b;
    TsdfBlock& dst = problem ? scratch : volume.FindOrAllocate(b);
    if (std::fread(&dst, 1, sizeof(TsdfBlock), f) != sizeof(TsdfBlock))
      return IoError("cannot read " + path + ": short read in block " + std::to_string(i));
    hash.Update(&dst, sizeof(TsdfBlock));
  }
  char checksum_bytes[kChecksumBytes];
  if (std::fread(checksum_bytes, 1, sizeof(checksum_bytes), f) != sizeof(checksum_bytes))
    return IoError("cannot read " + path + ": short read in the checksum");
  const uint64_t stored = Get<uint64_t>(checksum_bytes);
  if (stored != hash.value())
    return CorruptData("checksum mismatch (the file is damaged)").WithContext(context);
  if (problem) return problem->WithContext(context);
  if (up) *up = header->up;
  return volume;
}

}  // namespace voxplan
