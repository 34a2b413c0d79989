#pragma once
// Sharded maps: a map split over ranks, as one small JSON manifest (at the path the user named,
// e.g. map.vpmap) and one ordinary .vpmap file per rank beside it,
// `<manifest>.g<generation>.r<rank>-of-<ranks>.vpmap`. Every rank writes its shard atomically,
// then rank 0 writes the manifest atomically, last: it names the shards, their block counts and
// checksums, the owner function (core/shard.h) and what the writer needs to resume (a fuse run's
// frame cursor and report so far). Shards of a new generation never replace the ones the current
// manifest names, so a run killed at any point leaves a manifest and the shards it names; the
// previous generation's shards, and any a killed run wrote without a manifest, are removed only
// after the new manifest is in place.
// Readers (`voxplan mesh`, `info`, `render`) load every shard into one volume whatever the rank
// count (LoadAnyMap); a sharded run can keep only the blocks it owns under another rank count.
// Written by distributed/shard_writer.h; read here, in io, so every reader of maps can.
#include <cstdint>
#include <string>
#include <vector>

#include "core/shard.h"
#include "core/status.h"
#include "core/volume.h"
#include "io/world_up.h"

namespace voxplan {

inline constexpr const char* kShardedMapFormat = "voxplan-sharded-map";
inline constexpr int kShardedMapVersion = 1;

struct ShardManifest {
  uint32_t ranks = 1;
  std::string owner_function = kShardOwnerFunction;
  VolumeParams params;
  uint64_t generation = 0;
  bool complete = true;
  WorldUp up = WorldUp::kUnknown;  // the world's up axis, as plain maps record it  // false: a
                                   // checkpoint of a run still going (or killed)
  struct Shard {
    std::string file;  // a name in the manifest's folder, never a path
    uint64_t blocks = 0;
    uint64_t checksum = 0;  // VolumeChecksum of the shard's blocks
  };
  std::vector<Shard> shards;  // by rank
  // The writer's own, as JSON text (fuse: fingerprint, cursor, report so far); "{}" if none.
  std::string run_json = "{}";
};

// Whether `path` is a manifest (its first bytes say so); false for a plain map or no file.
bool IsShardedMapFile(const std::string& path);
// Reads and checks a manifest: format and version, the owner function this build uses, shard
// names inside the manifest's folder, bounded counts; CorruptData naming the file otherwise.
Result<ShardManifest> ReadShardManifest(const std::string& path);

// The name of rank `rank`'s shard of generation `generation` beside manifest `manifest`, and
// the manifest's JSON text (distributed/shard_writer.h writes both).
std::string ShardFileName(const std::string& manifest, uint64_t generation, int rank, int ranks);
std::string ShardFilePath(const std::string& manifest, const std::string& name);
std::string ShardManifestText(const ShardManifest& manifest);
bool SafeShardName(const std::string& name);
// The shard files beside `manifest` (names of the form above, for its file name) that `current`
// does not name, sorted: a killed run's half-written generation, or a replaced one's. Empty when
// the folder cannot be listed.
std::vector<std::string> StaleShardFiles(const std::string& manifest, const ShardManifest& current);
// Removes them (once `current` is in place at `manifest`, or a plain map that names none).
void RemoveStaleShards(const std::string& manifest, const ShardManifest& current);

// Loads the blocks `keep` owns (all by default) from every shard the manifest names, checking
// each shard's block count and checksum against the manifest.
Result<TsdfVolume> LoadShardedMap(const std::string& path, const ShardSpec& keep = {},
                                  ShardManifest* manifest = nullptr);
// A plain map (io/map_io.h) or a sharded one, whole; `up`, when given, gets its up axis.
Result<TsdfVolume> LoadAnyMap(const std::string& path, WorldUp* up = nullptr);

// FNV-1a over the sorted blocks' indices and bytes: equal for equal maps, whatever their
// insertion order or how they were split (the checksums of shards are of their blocks alone).
uint64_t VolumeChecksum(const TsdfVolume& volume);

}  // namespace voxplan
