#include "io/sharded_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/fnv1a.h"
#include "io/file_util.h"
#include "io/map_io.h"

namespace voxplan {

namespace {

namespace fs = std::filesystem;

constexpr uint64_t kMaxManifestBytes = uint64_t(64) << 20;

std::string Folder(const std::string& path) {
  const fs::path folder = fs::path(path).parent_path();
  return folder.empty() ? std::string(".") : folder.string();
}

Status Corrupt(const std::string& path, const std::string& why) {
  return CorruptData("sharded map " + path + ": " + why);
}

}  // namespace

std::string ShardFileName(const std::string& manifest, uint64_t generation, int rank, int ranks) {
  return fs::path(manifest).filename().string() + ".g" + std::to_string(generation) + ".r" +
         std::to_string(rank) + "-of-" + std::to_string(ranks) + ".vpmap";
}

std::string ShardFilePath(const std::string& manifest, const std::string& name) {
  return (fs::path(Folder(manifest)) / name).string();
}

// A shard's name must stay in the manifest's folder: no separators, no "..", not hidden.
bool SafeShardName(const std::string& name) {
  return !name.empty() && name.size() < 256 && name.find('/') == std::string::npos &&
         name.find('\\') == std::string::npos && name[0] != '.';
}

namespace {

// Consumes one or more decimal digits at `at`.
bool SkipDigits(const std::string& s, size_t& at) {
  const size_t from = at;
  while (at < s.size() && s[at] >= '0' && s[at] <= '9') ++at;
  return at > from;
}

// Whether `name` is `<prefix>g<digits>.r<digits>-of-<digits>.vpmap`, as ShardFileName writes.
bool IsShardFileName(const std::string& name, const std::string& prefix) {
  if (name.rfind(prefix, 0) != 0) return false;
  size_t at = prefix.size();
  const auto skip = [&](const char* text) {
    const size_t n = std::strlen(text);
    if (name.compare(at, n, text) != 0) return false;
    at += n;
    return true;
  };
  return skip("g") && SkipDigits(name, at) && skip(".r") && SkipDigits(name, at) && skip("-of-") &&
         SkipDigits(name, at) && skip(".vpmap") && at == name.size();
}

}  // namespace

std::vector<std::string> StaleShardFiles(const std::string& manifest,
                                         const ShardManifest& current) {
  const std::string prefix = fs::path(manifest).filename().string() + ".";
  std::vector<std::string> stale;
  std::error_code ec;
  for (fs::directory_iterator it(Folder(manifest), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!IsShardFileName(name, prefix)) continue;
    bool named = false;
    for (const ShardManifest::Shard& s : current.shards) named = named || s.file == name;
    if (!named) stale.push_back(name);
  }
  std::sort(stale.begin(), stale.end());
  return stale;
}

void RemoveStaleShards(const std::string& manifest, const ShardManifest& current) {
  for (const std::string& stale : StaleShardFiles(manifest, current)) {
    std::error_code ec;
    fs::remove(ShardFilePath(manifest, stale), ec);  // already gone: no error
  }
}

std::string ShardManifestText(const ShardManifest& m) {
  nlohmann::json j;
  j["format"] = kShardedMapFormat;
  j["version"] = kShardedMapVersion;
  j["ranks"] = m.ranks;
  j["owner_function"] = m.owner_function;
  j["voxel_size_m"] = m.params.voxel_size_m;
  j["trunc_m"] = m.params.trunc_m;
  j["generation"] = m.generation;
  j["complete"] = m.complete;
  j["up"] = WorldUpName(m.up);
  nlohmann::json shards = nlohmann::json::array();
  uint64_t blocks = 0;
  for (const ShardManifest::Shard& s : m.shards) {
    // Checksums as hex strings: JSON readers elsewhere lose 64-bit integers' low bits.
    char hex[17];
    std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(s.checksum));
    shards.push_back({{"file", s.file}, {"blocks", s.blocks}, {"checksum", hex}});
    blocks += s.blocks;
  }
  j["blocks"] = blocks;
  j["shards"] = shards;
  j["run"] = nlohmann::json::parse(m.run_json, nullptr, /*allow_exceptions=*/false);
  if (j["run"].is_discarded()) j["run"] = nlohmann::json::object();
  return j.dump(1) + "\n";
}

uint64_t VolumeChecksum(const TsdfVolume& volume) {
  Fnv1a64 hash;
  for (const BlockIndex& b : volume.SortedBlockIndices()) {
    const int32_t xyz[3] = {b.x, b.y, b.z};
    hash.Update(xyz, sizeof(xyz));
    hash.Update(volume.FindBlock(b), sizeof(TsdfBlock));
  }
  return hash.value();
}

bool IsShardedMapFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  char head[96] = {};
  f.read(head, sizeof(head) - 1);
  const std::string text(head, size_t(f.gcount()));
  return !text.empty() && text[0] == '{' && text.find(kShardedMapFormat) != std::string::npos;
}

Result<ShardManifest> ReadShardManifest(const std::string& path) {
  std::error_code ec;
  const uint64_t size = fs::file_size(path, ec);
  if (ec) return IoError("cannot read " + path + ": " + ec.message());
  if (size > kMaxManifestBytes)
    return Corrupt(path, "manifest of " + std::to_string(size) + " bytes (at most " +
                             std::to_string(kMaxManifestBytes) + ")");
  Result<std::string> text = ReadFileToString(path);
  if (!text.ok()) return text.status();
  nlohmann::json j = nlohmann::json::parse(*text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return Corrupt(path, "not a JSON object");
  try {
    if (j.value("format", std::string()) != kShardedMapFormat)
      return Corrupt(path, "format is not " + std::string(kShardedMapFormat));
    if (j.at("version").get<int>() != kShardedMapVersion)
      return Corrupt(path, "version " + j.at("version").dump() + ", this build reads " +
                               std::to_string(kShardedMapVersion));
    ShardManifest m;
    const int64_t ranks = j.at("ranks").get<int64_t>();
    if (ranks < 1 || ranks > kMaxShardRanks)
      return Corrupt(path, "ranks " + std::to_string(ranks) + " outside 1 to " +
                               std::to_string(kMaxShardRanks));
    m.ranks = uint32_t(ranks);
    m.owner_function = j.at("owner_function").get<std::string>();
    if (m.owner_function != kShardOwnerFunction)
      return Corrupt(path, "owner function \"" + m.owner_function + "\", this build uses \"" +
                               kShardOwnerFunction + "\"");
    m.params.voxel_size_m = j.at("voxel_size_m").get<float>();
    m.params.trunc_m = j.at("trunc_m").get<float>();
    if (Status s = m.params.Validate(); !s.ok()) return Corrupt(path, s.message());
    m.generation = j.at("generation").get<uint64_t>();
    m.complete = j.at("complete").get<bool>();
    Result<WorldUp> up = ParseWorldUp(j.value("up", std::string("unknown")));
    if (!up.ok()) return Corrupt(path, up.status().message());
    m.up = *up;
    const nlohmann::json& shards = j.at("shards");
    if (!shards.is_array() || shards.size() != m.ranks)
      return Corrupt(path, "needs one shard per rank (" + std::to_string(m.ranks) + ")");
    for (const nlohmann::json& s : shards) {
      ShardManifest::Shard shard;
      shard.file = s.at("file").get<std::string>();
      if (!SafeShardName(shard.file))
        return Corrupt(path, "shard \"" + shard.file + "\" is not a file name in its folder");
      shard.blocks = s.at("blocks").get<uint64_t>();
      const std::string hex = s.at("checksum").get<std::string>();
      char* end = nullptr;
      shard.checksum = std::strtoull(hex.c_str(), &end, 16);
      if (hex.size() != 16 || !end || *end) return Corrupt(path, "bad checksum \"" + hex + "\"");
      m.shards.push_back(shard);
    }
    m.run_json = j.value("run", nlohmann::json::object()).dump();
    return m;
  } catch (const nlohmann::json::exception& e) {
    return Corrupt(path, std::string("missing or mistyped field (") + e.what() + ")");
  }
}

Result<TsdfVolume> LoadShardedMap(const std::string& path, const ShardSpec& keep,
                                  ShardManifest* manifest_out) {
  Result<ShardManifest> manifest = ReadShardManifest(path);
  if (!manifest.ok()) return manifest.status();
  TsdfVolume volume(manifest->params);
  for (const ShardManifest::Shard& s : manifest->shards) {
    const std::string shard_path = ShardFilePath(path, s.file);
    Result<TsdfVolume> shard = LoadMap(shard_path);
    if (!shard.ok()) return shard.status().WithContext("shard of sharded map " + path);
    if (shard->num_blocks() != s.blocks || VolumeChecksum(*shard) != s.checksum)
      return Corrupt(path, "shard " + shard_path + " does not match the manifest (" +
                               std::to_string(shard->num_blocks()) + " blocks, manifest says " +
                               std::to_string(s.blocks) +
                               "; a shard from another run or generation?)");
    if (shard->params().voxel_size_m != volume.voxel_size_m() ||
        shard->params().trunc_m != volume.trunc_m())
      return Corrupt(path, "shard " + shard_path + " has other voxel parameters");
    shard->ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
      if (keep.Owns(b)) volume.FindOrAllocate(b) = block;
    });
  }
  if (manifest_out) *manifest_out = std::move(*manifest);
  return volume;
}

Result<TsdfVolume> LoadAnyMap(const std::string& path, WorldUp* up) {
  if (!IsShardedMapFile(path)) return LoadMap(path, up);
  ShardManifest manifest;
  Result<TsdfVolume> volume = LoadShardedMap(path, ShardSpec{}, &manifest);
  if (volume.ok() && up) *up = manifest.up;
  return volume;
}

}  // namespace voxplan
