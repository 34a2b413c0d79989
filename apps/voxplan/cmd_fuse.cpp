// voxplan fuse: dataset -> TSDF volume -> mesh / map / stats.
#include "apps/voxplan/cmd_fuse.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "apps/voxplan/signals.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/dataset.h"
#include "io/frame_list.h"
#include "pipeline/fuse_dataset.h"
#include "pipeline/fuse_outputs.h"
#include "planning/octomap_export.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

nlohmann::json OrNull(const std::string& path) {
  return path.empty() ? nlohmann::json(nullptr) : nlohmann::json(path);
}

}  // namespace

// The stats object: the same on the last stdout line and in --stats.
nlohmann::json FuseStats(const FuseOptions& o, const DatasetInfo& info,
                         const IntegrateParams& params, const FuseReport& report,
                         const TsdfVolume& volume, const Mesh& mesh, double mesh_ms,
                         const std::optional<OctomapExportStats>& octomap) {
  const TimingSummary load_t = Summarize(report.load_ms),
                      integrate_t = Summarize(report.integrate_ms),
                      frame_t = Summarize(report.frame_ms);
  const size_t integrated = report.frames.size();
  const double loop_s = report.loop_s;
  nlohmann::json j;
  j["command"] = "fuse";
  j["dataset"] = o.in.dataset;
  j["format"] = DatasetFormatName(info.format);
  j["frames"] = integrated;
  j["frames_selected"] = report.frames_selected;
  j["frames_skipped"] = report.skipped_no_pose + report.skipped_no_depth + report.skipped_bad_pose +
                        report.skipped_pose_gap;
  j["frames_skipped_no_pose"] = report.skipped_no_pose;
  j["frames_skipped_bad_pose"] = report.skipped_bad_pose;
  j["frames_skipped_pose_gap"] = report.skipped_pose_gap;
  j["max_pose_gap_s"] = o.max_pose_gap_s;
  j["tracking"] = o.track;
  j["frames_lost"] = report.frames_lost;
  j["track_ms_median"] = RoundTo(Summarize(report.track_ms).median, 3);
  j["trajectory"] = OrNull(o.trajectory_path);
  j["frames_skipped_no_depth"] = report.skipped_no_depth;
  j["voxel_size_m"] = o.voxel_size_m;
  j["trunc_m"] = o.trunc_m;
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["max_weight"] = o.max_weight;
  j["weighting"] = o.weighting;
  j["threads"] = MaxThreads();
  j["kernel"] = KernelName(ResolveKernel(params.kernel));
  j["camera"] = CameraJson(info.camera);
  j["depth_scale"] = info.depth_scale;
  j["depth_encoding"] = OrNull(info.depth_encoding);
  j["depth_scale_applies"] = !info.depth_metres;
  j["depth_median_first_frames_m"] = RoundTo(report.first_frames_median_depth_m, 4);
  j["depth_scale_suggested"] = report.suggested_depth_scale > 0.0
                                   ? nlohmann::json(report.suggested_depth_scale)
                                   : nlohmann::json(nullptr);
  j["integrate_ms_median"] = RoundTo(integrate_t.median, 3);
  j["integrate_ms_p90"] = RoundTo(integrate_t.p90, 3);
  j["integrate_ms_mean"] = RoundTo(integrate_t.mean, 3);
  // Within integration: finding the band's blocks and updating them (a split map repeats the
  // first on every rank and splits the second).
  j["collect_ms_median"] = RoundTo(Summarize(report.collect_ms).median, 3);
  j["update_ms_median"] = RoundTo(Summarize(report.update_ms).median, 3);
  j["load_ms_median"] = RoundTo(load_t.median, 3);
  j["load_ms_p90"] = RoundTo(load_t.p90, 3);
  j["frame_ms_median"] = RoundTo(frame_t.median, 3);
  j["frame_ms_p90"] = RoundTo(frame_t.p90, 3);
  j["loop_s"] = RoundTo(loop_s, 3);
  // Throughput of the whole frame loop (decode + integrate + skipped frames).
  j["fps"] = RoundTo(loop_s > 0 ? double(integrated) / loop_s : 0.0, 2);
  AddMapStats(j, volume);
  AddMeshStats(j, mesh, mesh_ms);
  j["mesh"] = OrNull(o.mesh_path);
  j["points"] = OrNull(o.points_path);
  j["point_count"] = o.points_path.empty() ? 0 : mesh.num_vertices();
  j["octomap"] = OrNull(o.octomap_path);
  j["octomap_occupied_voxels"] = octomap ? octomap->occupied_voxels : 0;
  j["octomap_free_voxels"] = octomap ? octomap->free_voxels : 0;
  j["map"] = OrNull(o.map_path);
  j["stats"] = OrNull(o.stats_path);
  j["peak_rss_mb"] = PeakRssMb();
  j["max_memory_mb"] = Mib(volume.params().max_memory_bytes);
  j["on_memory_limit"] = o.memory.on_limit;
  j["blocks_refused"] = report.blocks_refused;
  j["frames_over_budget"] = report.frames_over_budget;
  return j;
}

FuseParams FuseParamsOf(const FuseOptions& o) {
  FuseParams fuse;
  IntegrateParams& params = fuse.integrate;
  params.min_depth_m = float(o.in.min_depth_m);
  params.max_depth_m = float(o.in.max_depth_m);
  params.max_weight = float(o.max_weight);
  params.weighting = o.weighting == "depth" ? Weighting::kDepthDependent : Weighting::kConstant;
  params.kernel = kIntegrationKernels.at(o.kernel);
  fuse.track = o.track;
  fuse.prefetch = o.prefetch;
  fuse.on_memory_limit = MemoryLimitAction(o.memory);
  fuse.tracking.photometric_weight = float(o.photometric_weight);
  fuse.tracking.raycast.max_depth_m = float(o.in.max_depth_m);
  fuse.tracking.raycast.min_depth_m = float(o.in.min_depth_m);
  return fuse;
}

int DatasetOptionsOf(const FuseOptions& o, DatasetOptions* options) {
  if (!o.intrinsics.empty()) {
    Result<PinholeCamera> camera = ParseIntrinsics(o.intrinsics);
    if (!camera.ok()) return Fail(camera.status().message(), kExitUsage);
    options->intrinsics = *camera;
  }
  if (o.depth_scale > 0.0) options->depth_scale = o.depth_scale;
  options->max_pose_gap_s = o.max_pose_gap_s;
  return kExitOk;
}

VolumeParams VolumeParamsOf(const FuseOptions& o) {
  return {float(o.voxel_size_m), float(o.trunc_m), MemoryBudgetBytes(o.memory)};
}

// No output may be another output or one of the dataset's files.
int RefuseCollisions(const FuseOptions& o, const Dataset& dataset) {
  std::vector<PathUse> inputs;
  AddInputs(inputs, "the dataset", dataset.InputFiles());
  return RefusePathCollisions({{"--mesh", o.mesh_path},
                               {"--map", o.map_path},
                               {"--stats", o.stats_path},
                               {"--trajectory", o.trajectory_path},
                               {"--frame-list", o.frame_list_path},
                               {"--points", o.points_path},
                               {"--octomap", o.octomap_path}},
                              inputs);
}

namespace {

int RunFuse(const FuseOptions& o) {
  // Everything the arguments alone can refuse is refused before the dataset is read.
  if (std::string why = CheckVoxelAndTrunc(o.voxel_size_m, o.trunc_m); !why.empty())
    return Fail(why, kExitUsage);
  if ((o.checkpoint_every > 0 || o.resume) && o.map_path.empty())
    return Fail("--checkpoint-every and --resume need --map (the checkpoint is the map)",
                kExitUsage);
  Result<std::unique_ptr<Communicator>> world = WorldCommunicator();
  if (!world.ok()) return Fail(world.status().message());
  if ((*world)->size() > 1 || o.checkpoint_every > 0 || o.resume) return RunFuseSharded(o, **world);
  DatasetOptions dataset_options;
  if (int code = DatasetOptionsOf(o, &dataset_options); code != kExitOk) return code;
  ThreadLimit thread_limit(o.threads);
  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, dataset_options, &opened); code != kExitOk) return code;
  const Dataset& dataset = *opened.dataset;
  const DatasetInfo& info = dataset.info();
  const std::vector<size_t>& indices = opened.indices;
  if (int code = RefuseCollisions(o, dataset); code != kExitOk) return code;

  const FuseParams fuse = FuseParamsOf(o);
  const IntegrateParams& params = fuse.integrate;
  TsdfVolume volume(VolumeParamsOf(o));

  std::cerr << "fuse: " << info.root << " (" << DatasetFormatName(info.format) << "), "
            << indices.size() << " of " << info.num_frames << " frames, voxel " << o.voxel_size_m
            << " m, trunc " << o.trunc_m << " m, " << MaxThreads() << " threads, kernel "
            << KernelName(ResolveKernel(params.kernel)) << ", memory budget "
            << Mib(volume.params().max_memory_bytes) << " MiB" << std::endl;

  Progress progress("fuse", indices.size());
  FuseObserver observer;
  observer.progress = [&](size_t done, size_t) { progress.Update(done); };
  observer.warning = [&](const std::string& message) { progress.Warn(message); };
  const StopPolling polling;  // a signal ends the loop after the current frame
  observer.stop_requested = StopRequestedFn();
  Result<FuseReport> fused = FuseDataset(dataset, indices, fuse, volume, observer);
  progress.Finish();
  if (!fused.ok() && fused.status().code() == StatusCode::kCancelled)
    return Interrupted(fused.status().message() + "; nothing written");
  if (!fused.ok()) return Fail(fused.status().message());
  const FuseReport& report = *fused;
  if (report.frames.empty()) {
    return Fail("no frame was integrated (" + std::to_string(indices.size()) +
                " selected, all skipped): " + o.in.dataset);
  }

  MeshParams mesh_params;
  mesh_params.min_weight = float(o.mesh_min_weight);
  const FrameListParams list{info.camera, info.depth_scale, o.voxel_size_m,
                             o.trunc_m,   o.in.min_depth_m, o.in.max_depth_m};
  OutputTransaction written;  // every output lands, or none
  FuseOutputPaths paths{o.mesh_path, o.map_path, o.trajectory_path, o.frame_list_path,
                        o.points_path};
  paths.map_up = FusedWorldUp(info, report, o.track);
  Result<FuseOutputs> outputs = WriteFuseOutputs(paths, volume, report, mesh_params, list);
  if (!outputs.ok()) return Fail(outputs.status().message());
  const Mesh& mesh = outputs->mesh;
  // The occupancy as an OctoMap tree (planning/octomap_export.h), staged with the rest.
  std::optional<OctomapExportStats> octomap;
  if (!o.octomap_path.empty()) {
    Result<OctomapExportStats> exported = ExportOctomap(volume, o.octomap_path);
    if (!exported.ok()) return Fail(MessageNaming(exported.status(), o.octomap_path));
    octomap = *exported;
  }
  nlohmann::json j = FuseStats(o, info, params, report, volume, mesh, outputs->mesh_ms, octomap);
  // The world's up axis the map records (render orbits about it), and where it came from.
  j["up"] = WorldUpName(paths.map_up);
  j["up_source"] = !o.track                            ? info.up_source
                   : paths.map_up == WorldUp::kUnknown ? "unknown: the tracked poses do not tell"
                                                       : "estimated from the tracked poses";
  const size_t integrated = report.frames.size();
  if (!o.stats_path.empty()) {
    if (Status s = WriteJsonFile(j, o.stats_path); !s.ok()) {
      return Fail(MessageNaming(s, o.stats_path));
    }
  }
  if (int code = CommitOutputs(written); code != kExitOk) return code;

  std::cerr << "fused " << integrated << " frames (" << j["frames_skipped"] << " skipped) in "
            << j["loop_s"] << " s: integrate median " << j["integrate_ms_median"]
            << " ms, load median " << j["load_ms_median"] << " ms, " << j["fps"] << " fps\n"
            << "map: " << volume.num_blocks() << " blocks, " << j["map_mb"] << " MiB, peak RSS "
            << j["peak_rss_mb"] << " MiB\n";
  if (report.blocks_refused > 0) {
    std::cerr << "memory budget " << j["max_memory_mb"] << " MiB: " << report.blocks_refused
              << " new blocks dropped in " << report.frames_over_budget << " frames\n";
  }
  if (!o.mesh_path.empty()) {
    std::cerr << "mesh: " << o.mesh_path << " (" << mesh.num_vertices() << " vertices, "
              << mesh.num_triangles() << " triangles, " << j["mesh_ms"] << " ms)\n";
  }
  if (!o.map_path.empty())
    std::cerr << "map file: " << o.map_path << " (up " << WorldUpName(paths.map_up) << ")\n";
  if (!o.points_path.empty())
    std::cerr << "points: " << o.points_path << " (" << mesh.num_vertices() << " points)\n";
  if (octomap) {
    std::cerr << "octomap: " << o.octomap_path << " (" << octomap->occupied_voxels << " occupied, "
              << octomap->free_voxels << " free voxels)\n";
  }
  if (!o.stats_path.empty()) std::cerr << "stats: " << o.stats_path << "\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddFuseCommand(CLI::App& app) {
  auto o = std::make_shared<FuseOptions>();
  CLI::App* sub = app.add_subcommand("fuse", "Integrate an RGB-D dataset into a TSDF map");
  AddDatasetInputOptions(sub, o->in, /*with_start=*/true);
  sub->add_option("--voxel-size", o->voxel_size_m, "Voxel size in metres")
      ->check(VoxelSize())
      ->capture_default_str();
  sub->add_option("--trunc", o->trunc_m, "Truncation distance in metres (1 to 64 voxels)")
      ->check(InRange(bounds::kVoxelSizeMinM * bounds::kTruncMinVoxels,
                      bounds::kVoxelSizeMaxM * bounds::kTruncMaxVoxels, "m"))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  sub->add_option("--intrinsics", o->intrinsics, "Override intrinsics: fx,fy,cx,cy");
  sub->add_option("--depth-scale", o->depth_scale, "Override depth units per metre")
      ->check(InRange(bounds::kDepthScaleMin, bounds::kDepthScaleMax));
  sub->add_option("--weighting", o->weighting, "Observation weight")
      ->check(CLI::IsMember({"constant", "depth"}))
      ->capture_default_str();
  sub->add_option("--kernel", o->kernel, "Integration kernel")
      ->check(CLI::IsMember({"auto", "scalar", "simd"}))
      ->capture_default_str();
  sub->add_option("--max-weight", o->max_weight, "Weight cap per voxel")
      ->check(InRange(1.0 / kWeightScale, kMaxWeight))
      ->capture_default_str();
  sub->add_option("--mesh-min-weight", o->mesh_min_weight, "Meshing: ignore voxels below this")
      ->check(InRange(0.0, kMaxWeight))
      ->capture_default_str();
  sub->add_option("--mesh", o->mesh_path, "Write the mesh (.ply .obj .glb .stl)")
      ->check(MeshOutputValidator());
  sub->add_option("--map", o->map_path, "Write the map (.vpmap)")->check(OutputFileValidator());
  sub->add_option("--points", o->points_path,
                  "Write the surface as a point cloud (.ply: the mesh's vertices, with colour and "
                  "normals)")
      ->check(OutputWithExtensionValidator(".ply", "--points"));
  sub->add_option("--octomap", o->octomap_path,
                  "Write the occupancy as an OctoMap binary tree (.bt; occupied and free voxels)")
      ->check(OutputWithExtensionValidator(".bt", "--octomap"));
  sub->add_option("--stats", o->stats_path, "Write the stats JSON")->check(OutputFileValidator());
  sub->add_flag("--track", o->track,
                "Estimate poses by frame-to-model ICP instead of using the dataset's");
  sub->add_option("--photometric-weight", o->photometric_weight,
                  "With --track: weight of the colour term (0: geometry only)")
      ->check(InRange(0.0, 1000.0))
      ->capture_default_str();
  sub->add_option("--max-pose-gap", o->max_pose_gap_s,
                  "Ground truth: do not interpolate a frame's pose across a gap longer than this "
                  "(s); such frames are skipped")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--trajectory", o->trajectory_path,
                  "Write the poses used (TUM format: t tx ty tz qx qy qz qw)")
      ->check(OutputFileValidator());
  sub->add_option("--frame-list", o->frame_list_path,
                  "Write the integrated frames (paths, poses, intrinsics) as JSON")
      ->check(OutputFileValidator());
  sub->add_option("--checkpoint-every", o->checkpoint_every,
                  "Write --map as a checkpoint every N selected frames (a sharded map: a manifest "
                  "and one shard per rank), so that --resume can continue a killed run")
      ->check(CLI::Range(size_t(1), size_t(1) << 30));
  sub->add_flag("--resume", o->resume,
                "Continue the run whose checkpoint is --map (same dataset, frames and "
                "parameters; any rank count)");
  sub->add_option("--band-walk", o->band_walk,
                  "Under mpirun: each rank walks a share of each frame's band and the ranks send "
                  "the blocks they found to their owners, or every rank walks the whole band (same "
                  "map; whole is faster with more ranks than cores, see distributed/README.md)")
      ->check(CLI::IsMember({"split", "whole"}))
      ->capture_default_str();
  sub->add_option("--prefetch", o->prefetch,
                  "Frames decoded ahead while one is fused (0: one after the other; same results)")
      ->check(CLI::Range(size_t(0), FuseParams::kMaxPrefetch))
      ->capture_default_str();
  AddMemoryBudgetOptions(sub, o->memory);
  return {sub, [o] { return RunFuse(*o); }};
}

}  // namespace voxplan::cli
