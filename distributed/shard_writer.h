#pragma once
// Writing a sharded map (io/sharded_map.h) from the ranks that hold it.
#include <nlohmann/json.hpp>
#include <string>

#include "core/status.h"
#include "core/volume.h"
#include "distributed/communicator.h"
#include "io/sharded_map.h"

namespace voxplan {

// Collective. Writes this rank's blocks as its shard of generation `generation`, then (rank 0)
// the manifest, then removes the shards `previous` named (each rank its own; rank 0 all of them
// when the rank count changed). Every rank gets the same status, and the new manifest (its
// shard names; checksums on rank 0 only). `up`: the world's up axis, in the manifest and the
// shards.
Result<ShardManifest> WriteShardedMap(Communicator& comm, const TsdfVolume& local,
                                      const std::string& path, uint64_t generation, bool complete,
                                      const nlohmann::json& run,
                                      const ShardManifest* previous = nullptr,
                                      WorldUp up = WorldUp::kUnknown);

}  // namespace voxplan
