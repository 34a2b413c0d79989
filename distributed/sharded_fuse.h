#pragma once
// Fusion with the map split over ranks (`mpirun -n N voxplan fuse`): rank 0 reads and checks
// every frame once and broadcasts it; each rank walks its share of the frame's truncation band
// and sends the blocks it found to their owners (core/shard.h), or without split_band_walk walks
// all of it and keeps its own; each integrates its blocks with the usual kernels, so each voxel
// gets exactly the updates it gets in one process. Tracking needs the whole model each frame and is
// not supported here (refused). Checkpoints are sharded maps (distributed/sharded_map.h) with
// the run's frame cursor; a resumed run continues from the last one, under any rank count.
// The same code runs in one process with a SerialCommunicator (checkpoints and resume there too).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/status.h"
#include "core/volume.h"
#include "distributed/communicator.h"
#include "distributed/shard_writer.h"
#include "fusion/mesh_extract.h"
#include "io/dataset.h"
#include "pipeline/fuse_dataset.h"

namespace voxplan {

// Collective: rank 0's dataset description (all but its warnings, which rank 0 prints) and
// selected frames to every rank. `info` and `indices` are read on rank 0 and filled elsewhere.
Status ShareDatasetInfo(Communicator& comm, DatasetInfo& info, std::vector<size_t>& indices);

struct ShardedFuseParams {
  FuseParams fuse;
  // The sharded map checkpoints go to (and a resumed run starts from); empty: none.
  std::string checkpoint_path;
  size_t checkpoint_every = 0;  // selected frames between checkpoints; 0: none
  bool resume = false;          // continue from the checkpoint at checkpoint_path
  // Each rank walks its share of a frame's band and the ranks exchange the blocks found
  // (IntegrateParams::band_exchange), instead of every rank walking all of it. Same map. The
  // exchange waits for every rank: with more ranks than cores (time-sliced) the whole walk is
  // faster (distributed/README.md).
  bool split_band_walk = true;
  // Whatever must match for a checkpoint to be resumed: dataset, selection, parameters.
  nlohmann::json fingerprint;
};

struct ShardedFuseReport {
  FuseReport report;                 // the whole run, resumed frames included (on every rank)
  size_t frames_resumed = 0;         // selected frames a checkpoint had done before this run
  uint64_t broadcast_bytes = 0;      // frames sent by rank 0, in all
  std::vector<double> broadcast_ms;  // per selected frame: its broadcast
};

// Collective. `dataset` is read on rank 0 only (elsewhere it may be null): info and indices
// come from ShareDatasetInfo. `local` receives this rank's blocks. Observer callbacks run on
// every rank (the CLI shows progress on rank 0 only). Fails on every rank when one fails.
Result<ShardedFuseReport> FuseDatasetSharded(Communicator& comm, const Dataset* dataset,
                                             const DatasetInfo& info,
                                             const std::vector<size_t>& indices,
                                             const ShardedFuseParams& params, TsdfVolume& local,
                                             const FuseObserver& observer = {});

// Collective. Meshes the split map as ExtractMesh meshes the whole one (same bytes): each rank
// fetches the +x/+y/+z neighbours of its blocks that others own (the halo), meshes its own
// blocks, and rank 0 welds every rank's pieces in block order. The halo is removed from `local`
// again before returning. Rank 0 gets the mesh; the others an empty one.
Result<Mesh> ExtractMeshSharded(Communicator& comm, TsdfVolume& local, const MeshParams& params);

// Per-rank figures, gathered on rank 0 (in rank order; empty elsewhere): blocks, the map's
// bytes, blocks refused by the budget and the peak resident memory (MiB).
struct RankFigures {
  uint64_t blocks = 0, map_bytes = 0;
  uint64_t blocks_refused = 0;  // new blocks its memory budget refused
  double peak_rss_mb = 0.0;
};
Result<std::vector<RankFigures>> GatherRankFigures(Communicator& comm, const TsdfVolume& local);

// What a sharded map records of the run that wrote it (ShardManifest::run_json): the run's
// fingerprint, the selected frames done and the report so far — checkpoints and the final map.
nlohmann::json CheckpointRun(const ShardedFuseParams& params, size_t done,
                             const FuseReport& report);

// A fuse report as JSON and back, as checkpoints keep it (frames with their poses bit-exact).
nlohmann::json FuseReportToJson(const FuseReport& report);
Result<FuseReport> FuseReportFromJson(const nlohmann::json& j);

}  // namespace voxplan
