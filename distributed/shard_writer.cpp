#include "distributed/shard_writer.h"

#include <cstring>

#include "io/file_util.h"
#include "io/map_io.h"

namespace voxplan {

Result<ShardManifest> WriteShardedMap(Communicator& comm, const TsdfVolume& local,
                                      const std::string& path, uint64_t generation, bool complete,
                                      const nlohmann::json& run, WorldUp up) {
  const std::string name = ShardFileName(path, generation, comm.rank(), comm.size());
  const Status mine = SaveMap(local, ShardFilePath(path, name), up);
  VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, mine));

  // Rank 0 learns every shard's count and checksum, and writes the manifest.
  const uint64_t fields[2] = {uint64_t(local.num_blocks()), VolumeChecksum(local)};
  Bytes bytes(sizeof(fields));
  std::memcpy(bytes.data(), fields, sizeof(fields));
  Result<std::vector<Bytes>> all = comm.Gather(bytes, 0);
  if (!all.ok()) return all.status();
  ShardManifest m;
  m.ranks = uint32_t(comm.size());
  m.params = local.params();
  m.generation = generation;
  m.complete = complete;
  m.up = up;
  m.run_json = run.dump();
  for (int r = 0; r < comm.size(); ++r) {
    uint64_t f[2] = {0, 0};
    if (comm.is_root()) std::memcpy(f, (*all)[size_t(r)].data(), sizeof(f));
    m.shards.push_back({ShardFileName(path, generation, r, comm.size()), f[0], f[1]});
  }
  Status written = Status::Ok();
  if (comm.is_root()) written = WriteFileAtomically(path, ShardManifestText(m)).Naming(path);
  VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, written));

  // The new manifest is in place: every shard of this map it does not name can go, the previous
  // generation's and any a killed run wrote without a manifest. The other ranks wait, so none
  // writes its next generation's shard while the folder is swept.
  if (comm.is_root()) RemoveStaleShards(path, m);
  VOXPLAN_RETURN_IF_ERROR(AgreeOnStatus(comm, Status::Ok()));
  return m;
}

Status WriteFinalMap(Communicator& comm, const TsdfVolume& local, const std::string& path,
                     uint64_t generation, const nlohmann::json& run, WorldUp up) {
  if (comm.size() > 1)
    return WriteShardedMap(comm, local, path, generation, /*complete=*/true, run, up).status();
  VOXPLAN_RETURN_IF_ERROR(SaveMap(local, path, up).Naming(path));
  RemoveStaleShards(path, ShardManifest{});  // the plain map names no shard
  return Status::Ok();
}

}  // namespace voxplan
