// voxplan fuse split over mpirun's ranks, or with checkpoints: rank 0 reads the dataset and
// writes every output but the map's shards; each rank fuses and writes its own shard. Exit codes
// as for the one-process run, the same on every rank (the others print nothing but their own
// warnings, prefixed with their rank).
#include <iostream>
#include <optional>

#include "apps/voxplan/cmd_fuse.h"
#include "apps/voxplan/progress.h"
#include "apps/voxplan/signals.h"
#include "core/fnv1a.h"
#include "core/parallel.h"
#include "core/summary.h"
#include "distributed/sharded_fuse.h"
#include "io/file_util.h"
#include "io/output_transaction.h"
#include "pipeline/fuse_outputs.h"

namespace voxplan::cli {

namespace {

// Rank 0's exit code to every rank (the others pass kExitOk); a communication failure is 1.
int AgreeOnExit(Communicator& comm, int code) {
  Result<uint64_t> agreed = comm.AllMax(uint64_t(code < 0 ? 0 : code));
  return agreed.ok() ? int(*agreed) : kExitFailure;
}

// What a checkpoint must share with the run resuming it.
nlohmann::json Fingerprint(const FuseOptions& o, const DatasetInfo& info,
                           const std::vector<size_t>& indices) {
  Fnv1a64 selected;  // over the selected frames' indices, 8 little-endian bytes each
  for (size_t i : indices) {
    const uint64_t index = i;
    selected.Update(&index, sizeof(index));
  }
  return {{"dataset", info.root},
          {"format", DatasetFormatName(info.format)},
          {"frames_selected", indices.size()},
          {"frames_hash", std::to_string(selected.value())},
          {"voxel_size_m", o.voxel_size_m},
          {"trunc_m", o.trunc_m},
          {"min_depth_m", o.in.min_depth_m},
          {"max_depth_m", o.in.max_depth_m},
          {"max_weight", o.max_weight},
          {"weighting", o.weighting},
          {"depth_scale", info.depth_scale},
          {"camera", CameraJson(info.camera)}};
}

// A failure's message: rank 0 prints it, another rank only its own (not "rank R stopped", which
// rank 0 prints), prefixed with its rank. The exit code is the same on every rank.
int FailOnRank(Communicator& comm, const Status& s) {
  // A stop comes from rank 0 (it polls the signals): the others follow it quietly.
  const bool own = s.message().find(kOtherRankStopped) == std::string::npos &&
                   s.code() != StatusCode::kCancelled;
  if (comm.is_root() || own) {
    const std::string prefix = comm.is_root() ? "" : "rank " + std::to_string(comm.rank()) + ": ";
    if (s.code() == StatusCode::kCancelled) return Interrupted(prefix + s.message());
    return Fail(prefix + s.message());
  }
  return s.code() == StatusCode::kCancelled ? kExitSigint : kExitFailure;
}

}  // namespace

int RunFuseSharded(const FuseOptions& o, Communicator& comm) {
  const bool split = comm.size() > 1;
  if (split && !o.octomap_path.empty())
    return Fail(
        "--octomap under mpirun: the OctoMap tree is built from the whole map in one "
        "process; write --map here and convert it in one process",
        kExitUsage);
  if (split && o.track)
    return Fail(
        "--track under mpirun: tracking ray casts the whole model every frame, which a "
        "split map holds on no single rank; track in one process",
        kExitUsage);
  if (o.track)
    return Fail(
        "--track with --checkpoint-every or --resume: a checkpoint holds the map, not the "
        "tracker's state, so a resumed run could not continue the trajectory; track "
        "without checkpoints",
        kExitUsage);
  DatasetOptions dataset_options;
  if (int code = DatasetOptionsOf(o, &dataset_options); code != kExitOk) return code;
  ThreadLimit thread_limit(o.threads);

  // Rank 0 opens and checks the dataset; the others learn what it found.
  OpenedDataset opened;
  DatasetInfo info;
  std::vector<size_t> indices;
  int code = kExitOk;
  if (comm.is_root()) {
    code = OpenDatasetInput(o.in, dataset_options, &opened);
    if (code == kExitOk) code = RefuseCollisions(o, *opened.dataset);
    if (code == kExitOk) {
      info = opened.dataset->info();
      indices = opened.indices;
    }
  }
  if (int agreed = AgreeOnExit(comm, code); agreed != kExitOk) return agreed;
  if (Status s = ShareDatasetInfo(comm, info, indices); !s.ok()) return Fail(s.message());

  ShardedFuseParams params;
  params.fuse = FuseParamsOf(o);
  params.checkpoint_path = o.map_path;
  params.checkpoint_every = o.checkpoint_every;
  params.resume = o.resume;
  params.split_band_walk = o.band_walk == "split";
  params.fingerprint = Fingerprint(o, info, indices);
  TsdfVolume local(VolumeParamsOf(o));
  if (comm.is_root()) {
    std::cerr << "fuse: " << info.root << " (" << DatasetFormatName(info.format) << "), "
              << indices.size() << " of " << info.num_frames << " frames, voxel " << o.voxel_size_m
              << " m, trunc " << o.trunc_m << " m, " << comm.size()
              << (comm.size() == 1 ? " rank" : " ranks") << " x " << MaxThreads()
              << " threads, memory budget " << Mib(local.params().max_memory_bytes)
              << " MiB per rank" << (o.checkpoint_every ? ", checkpoint every " : "")
              << (o.checkpoint_every ? std::to_string(o.checkpoint_every) + " frames" : "")
              << (o.resume ? ", resuming " + o.map_path : "") << std::endl;
  }
  std::optional<Progress> progress;
  if (comm.is_root()) progress.emplace("fuse", indices.size());
  FuseObserver observer;
  if (progress) observer.progress = [&](size_t done, size_t) { progress->Update(done); };
  observer.warning = [&](const std::string& message) {
    // Every rank sees the same frames, so their skip and depth warnings are rank 0's; only the
    // memory budget is a rank's own.
    if (progress)
      progress->Warn(message);
    else if (message.rfind("memory budget", 0) == 0)
      std::cerr << "rank " << comm.rank() << ": warning: " << message << "\n";
  };
  const StopPolling polling;  // rank 0 decides when to stop; the others follow
  if (comm.is_root()) observer.stop_requested = StopRequestedFn();
  Result<ShardedFuseReport> fused =
      FuseDatasetSharded(comm, comm.is_root() ? opened.dataset.get() : nullptr, info, indices,
                         params, local, observer);
  if (progress) progress->Finish();
  if (!fused.ok()) {
    Status s = fused.status();
    if (s.code() == StatusCode::kCancelled && fused.status().message().find("rank") != 0 &&
        !o.map_path.empty() && o.checkpoint_every > 0)
      s = Cancelled(s.message() + "; the last checkpoint is " + o.map_path +
                    " (continue with --resume)");
    return FailOnRank(comm, s);
  }
  const FuseReport& report = fused->report;
  if (report.frames.empty()) {
    if (comm.is_root())
      return Fail("no frame was integrated (" + std::to_string(indices.size()) +
                  " selected, all skipped): " + o.in.dataset);
    return kExitFailure;
  }

  // The map: split, a sharded map (the final generation, complete); in one process a plain map
  // replacing the checkpoint.
  const Stopwatch write_clock;
  const WorldUp up = FusedWorldUp(info, report, /*tracked=*/false);
  if (!o.map_path.empty()) {
    const Status s = WriteFinalMap(comm, local, o.map_path, uint64_t(indices.size()),
                                   CheckpointRun(params, indices.size(), report), up);
    if (!s.ok()) return FailOnRank(comm, s);
  }
  Mesh mesh;
  double mesh_ms = 0.0;
  if (!o.mesh_path.empty() || !o.points_path.empty()) {
    const Stopwatch mesh_clock;
    MeshParams mesh_params;
    mesh_params.min_weight = float(o.mesh_min_weight);
    Result<Mesh> meshed = ExtractMeshSharded(comm, local, mesh_params);
    if (!meshed.ok()) return FailOnRank(comm, meshed.status());
    mesh = std::move(*meshed);
    mesh_ms = mesh_clock.ElapsedMs();
  }
  Result<std::vector<RankFigures>> figures = GatherRankFigures(comm, local);
  if (!figures.ok()) return FailOnRank(comm, figures.status());
  if (!comm.is_root()) return AgreeOnExit(comm, kExitOk);

  // Rank 0: the other outputs, together, and the stats.
  code = [&] {
    MeshParams mesh_params;
    mesh_params.min_weight = float(o.mesh_min_weight);
    const FrameListParams list{info.camera, info.depth_scale, o.voxel_size_m,
                               o.trunc_m,   o.in.min_depth_m, o.in.max_depth_m};
    OutputTransaction written;
    Result<FuseOutputs> outputs =
        WriteFuseOutputs({o.mesh_path, "", o.trajectory_path, o.frame_list_path, o.points_path},
                         local, report, mesh_params, list, &mesh, mesh_ms);
    if (!outputs.ok()) return Fail(outputs.status().message());
    std::optional<OctomapExportStats> octomap;
    if (!o.octomap_path.empty()) {  // one process only (refused above when split)
      Result<OctomapExportStats> exported = ExportOctomap(local, o.octomap_path);
      if (!exported.ok()) return Fail(MessageNaming(exported.status(), o.octomap_path));
      octomap = *exported;
    }
    nlohmann::json j =
        FuseStats(o, info, params.fuse.integrate, report, local, mesh, mesh_ms, octomap);
    // The map over all ranks, and each rank's part.
    uint64_t blocks = 0, bytes = 0, refused = 0;
    nlohmann::json rank_blocks = nlohmann::json::array(), rank_mb = nlohmann::json::array(),
                   rank_rss = nlohmann::json::array();
    for (const RankFigures& f : *figures) {
      blocks += f.blocks;
      bytes += f.map_bytes;
      refused += f.blocks_refused;
      rank_blocks.push_back(f.blocks);
      rank_mb.push_back(RoundTo(Mib(f.map_bytes), 3));
      rank_rss.push_back(f.peak_rss_mb);
    }
    j["up"] = WorldUpName(up);
    j["up_source"] = info.up_source;
    j["ranks"] = comm.size();
    j["blocks"] = blocks;
    j["voxels"] = blocks * kBlockVoxels;
    j["map_mb"] = RoundTo(Mib(bytes), 3);
    j["blocks_refused"] = refused;  // by every rank's budget (frames_over_budget is rank 0's)
    j["rank_blocks"] = rank_blocks;
    j["rank_map_mb"] = rank_mb;
    j["rank_peak_rss_mb"] = rank_rss;
    j["peak_rss_mb"] = figures->empty() ? 0.0 : (*figures)[0].peak_rss_mb;
    j["frames_resumed"] = fused->frames_resumed;
    j["checkpoint_every"] = o.checkpoint_every;
    j["map_sharded"] = split && !o.map_path.empty();
    const TimingSummary bcast = Summarize(fused->broadcast_ms);
    j["broadcast_mb_per_frame"] =
        fused->broadcast_ms.empty()
            ? 0.0
            : RoundTo(Mib(fused->broadcast_bytes) / double(fused->broadcast_ms.size()), 3);
    j["broadcast_ms_median"] = RoundTo(bcast.median, 3);
    j["band_walk"] = split ? o.band_walk : "whole";
    j["exchange_ms_median"] = RoundTo(Summarize(report.exchange_ms).median, 3);
    j["write_s"] = RoundTo(write_clock.ElapsedS(), 3);
    if (!o.stats_path.empty()) {
      if (Status s = WriteJsonFile(j, o.stats_path); !s.ok())
        return Fail(MessageNaming(s, o.stats_path));
    }
    if (int c = CommitOutputs(written); c != kExitOk) return c;
    std::cerr << "fused " << report.frames.size() << " frames (" << j["frames_skipped"]
              << " skipped" << (fused->frames_resumed ? ", " : "")
              << (fused->frames_resumed
                      ? std::to_string(fused->frames_resumed) + " selected frames resumed"
                      : "")
              << ") on " << comm.size() << (comm.size() == 1 ? " rank" : " ranks") << ": " << blocks
              << " blocks, " << j["map_mb"] << " MiB in all\n";
    if (!o.map_path.empty())
      std::cerr << "map file: " << o.map_path
                << (j["map_sharded"].get<bool>() ? " (manifest; one shard per rank beside it)" : "")
                << "\n";
    if (!o.mesh_path.empty())
      std::cerr << "mesh: " << o.mesh_path << " (" << mesh.num_vertices() << " vertices, "
                << mesh.num_triangles() << " triangles)\n";
    PrintJsonLine(j);
    return kExitOk;
  }();
  return AgreeOnExit(comm, code);
}

}  // namespace voxplan::cli
