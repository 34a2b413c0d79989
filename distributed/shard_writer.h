#pragma once
// Writing a sharded map (io/sharded_map.h) from the ranks that hold it, and a run's final map
// (sharded when split, else plain).
#include <nlohmann/json.hpp>
#include <string>

#include "core/status.h"
#include "core/volume.h"
#include "distributed/communicator.h"
#include "io/sharded_map.h"

namespace voxplan {

// Collective. Writes this rank's blocks as its shard of generation `generation`, then (rank 0)
// the manifest, then (rank 0) every shard of this map the manifest does not name: the previous
// generation's, and a killed run's half-written one (RemoveStaleShards). Every rank gets the same
// status, and the new manifest (its shard names; checksums on rank 0 only). `up`: the world's up
// axis, in the manifest and the shards.
Result<ShardManifest> WriteShardedMap(Communicator& comm, const TsdfVolume& local,
                                      const std::string& path, uint64_t generation, bool complete,
                                      const nlohmann::json& run, WorldUp up = WorldUp::kUnknown);

// Collective. A run's final map at `path`: split over ranks, the complete sharded map of
// generation `generation` (WriteShardedMap); in one process a plain map, after which every shard
// of this name goes (a checkpoint's, a killed run's). Every rank gets the same status.
Status WriteFinalMap(Communicator& comm, const TsdfVolume& local, const std::string& path,
                     uint64_t generation, const nlohmann::json& run, WorldUp up);

}  // namespace voxplan
