// voxplan demo: a self-contained run with nothing to download. Renders a synthetic room with
// Embree, fuses the frames with their true poses, meshes the map and scores the mesh against
// the room it came from.
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/signals.h"
#include "core/parallel.h"
#include "eval/eval_mesh.h"
#include "eval/visibility.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "pipeline/fuse_dataset.h"
#include "sim/demo_room.h"
#include "sim/raycaster.h"
#include "sim/rendered_dataset.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct DemoOptions {
  std::string out_dir = "data/demo";
  int frames = kDemoFrames;
  double voxel_size_m = 0.02;
  int threads = 0;
  MemoryBudgetOptions memory;
};

// The targets the demo is meant to meet, in voxels of the chosen size.
constexpr double kRmsTargetVoxels = 0.5;
constexpr double kCompletenessTarget = 0.95;
constexpr double kThresholdVoxels = 2.0;
constexpr double kTruncVoxels = 4.0;
constexpr int kVisibilityPoseStride = 2;

// Completeness counts the surface the trajectory could observe: the same camera, poses and
// depth range that produced the frames. Every other pose suffices; it halves the renders.
Result<MeshEvalResult> ScoreDemoMesh(const Mesh& mesh, const Mesh& room,
                                     const MeshRaycaster& raycaster, const PinholeCamera& camera,
                                     const std::vector<Pose3d>& poses,
                                     const IntegrateParams& params, MeshEvalParams eval_params) {
  VisibilityParams visibility;
  visibility.min_depth_m = params.min_depth_m;
  visibility.max_depth_m = params.max_depth_m;
  visibility.pose_stride = kVisibilityPoseStride;
  Result<PointSetFilter> observable = ObservableSurfaceFilter(raycaster, camera, poses, visibility);
  if (!observable.ok()) return observable.status().WithContext("visibility");
  eval_params.ground_truth_filter = *observable;
  Result<MeshEvalResult> eval = EvaluateMesh(mesh, room, eval_params);
  if (!eval.ok()) return eval.status().WithContext("evaluation failed");
  return eval;
}

int RunDemo(const DemoOptions& o) {
  std::error_code ec;
  OutputTransaction transaction;  // every file lands, or none (and no folder it made)
  transaction.WatchFolder(o.out_dir);
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir, ec)) return Fail("cannot create output folder: " + o.out_dir);
  const fs::path dir(o.out_dir);
  const std::string mesh_path = (dir / "demo_mesh.ply").string();
  const std::string gt_path = (dir / "demo_room_gt.ply").string();
  const std::string map_path = (dir / "demo.vpmap").string();
  const std::string stats_path = (dir / "demo_stats.json").string();

  ThreadLimit thread_limit(o.threads);
  const DemoRoomParams room_params;
  const Mesh room = BuildDemoRoom(room_params);
  const std::vector<Pose3d> poses = DemoTrajectory(room_params, o.frames);
  const PinholeCamera camera = DemoCamera();
  Result<std::unique_ptr<MeshRaycaster>> raycaster = MeshRaycaster::Create(room);
  if (!raycaster.ok()) return Fail("raycaster: " + raycaster.status().message());

  const double trunc_m = kTruncVoxels * o.voxel_size_m;
  TsdfVolume volume(
      VolumeParams{float(o.voxel_size_m), float(trunc_m), MemoryBudgetBytes(o.memory)});
  IntegrateParams params;
  params.min_depth_m = 0.1f;
  // Noise-free renders: every wall of the room is worth integrating.
  params.max_depth_m = 10.0f;
  std::cerr << "demo: " << poses.size() << " frames of a " << room_params.size_x_m << " x "
            << room_params.size_y_m << " x " << room_params.height_m << " m room ("
            << room.num_triangles() << " triangles), voxel " << o.voxel_size_m << " m, trunc "
            << trunc_m << " m, " << MaxThreads() << " threads\n";

  // The frames are rendered as the pipeline loads them ("load" is the render time).
  const RenderedDataset frames(**raycaster, camera, poses, "demo room");
  std::vector<size_t> indices(poses.size());
  for (size_t k = 0; k < indices.size(); ++k) indices[k] = k;
  FuseParams fuse;
  fuse.integrate = params;
  Progress progress("demo", poses.size());
  FuseObserver observer;
  observer.progress = [&](size_t done, size_t) { progress.Update(done); };
  observer.warning = [&](const std::string& message) { progress.Warn(message); };
  const StopPolling polling;  // a signal ends the loop after the current frame
  observer.stop_requested = StopRequestedFn();
  Result<FuseReport> report = FuseDataset(frames, indices, fuse, volume, observer);
  progress.Finish();
  if (!report.ok() && report.status().code() == StatusCode::kCancelled)
    return Interrupted(report.status().message() + "; nothing written");
  if (!report.ok()) return Fail(report.status().message());

  const Stopwatch mesh_clock;
  const Mesh mesh = ExtractMesh(volume);
  const double mesh_ms = mesh_clock.ElapsedMs();
  if (mesh.empty()) return Fail("the demo produced an empty mesh");
  if (Status s = WriteMesh(mesh, mesh_path); !s.ok()) return Fail(MessageNaming(s, mesh_path));
  if (Status s = WriteMesh(room, gt_path); !s.ok()) return Fail(MessageNaming(s, gt_path));
  if (Status s = SaveMap(volume, map_path, frames.info().up); !s.ok())
    return Fail(MessageNaming(s, map_path));

  MeshEvalParams eval_params;
  eval_params.threshold_m = float(kThresholdVoxels * o.voxel_size_m);
  eval_params.seed = 1;
  const Stopwatch eval_clock;
  Result<MeshEvalResult> eval =
      ScoreDemoMesh(mesh, room, **raycaster, camera, poses, params, eval_params);
  if (!eval.ok()) return Fail(eval.status().message());
  const double eval_ms = eval_clock.ElapsedMs();
  const double rms_target_m = kRmsTargetVoxels * o.voxel_size_m;
  const bool rms_met = eval->accuracy_rms_m <= rms_target_m;
  const bool completeness_met = eval->completeness >= kCompletenessTarget;

  const TimingSummary render_t = Summarize(report->load_ms),
                      integrate_t = Summarize(report->integrate_ms);
  nlohmann::json j;
  j["command"] = "demo";
  j["frames"] = poses.size();
  j["voxel_size_m"] = o.voxel_size_m;
  j["trunc_m"] = trunc_m;
  j["threads"] = MaxThreads();
  j["kernel"] = KernelName(ResolveKernel(params.kernel));
  j["render_ms_median"] = RoundTo(render_t.median, 3);
  j["integrate_ms_median"] = RoundTo(integrate_t.median, 3);
  j["integrate_ms_p90"] = RoundTo(integrate_t.p90, 3);
  AddMapStats(j, volume);
  AddMeshStats(j, mesh, mesh_ms);
  j["eval_ms"] = RoundTo(eval_ms, 3);
  j["threshold_m"] = ShortestDouble(eval_params.threshold_m);
  j["accuracy_mean_m"] = eval->accuracy_mean_m;
  j["accuracy_rms_m"] = eval->accuracy_rms_m;
  j["accuracy_median_m"] = eval->accuracy_median_m;
  // completeness: of the observable surface (the target); completeness_all_surface: of every
  // ground-truth triangle, hidden contacts included.
  j["completeness"] = eval->completeness;
  j["completeness_percent"] = RoundTo(100.0 * eval->completeness, 3);
  j["completeness_all_surface"] = eval->completeness_all;
  j["completeness_all_surface_percent"] = RoundTo(100.0 * eval->completeness_all, 3);
  j["observable_fraction"] =
      double(eval->ground_truth_samples) / double(eval->ground_truth_samples_all);
  j["rms_target_m"] = rms_target_m;
  j["completeness_target"] = kCompletenessTarget;
  j["rms_target_met"] = rms_met;
  j["completeness_target_met"] = completeness_met;
  j["targets_met"] = rms_met && completeness_met;
  j["mesh"] = mesh_path;
  j["ground_truth"] = gt_path;
  j["map"] = map_path;
  j["stats"] = stats_path;
  j["peak_rss_mb"] = PeakRssMb();
  if (Status s = WriteJsonFile(j, stats_path); !s.ok()) return Fail(MessageNaming(s, stats_path));
  if (int code = CommitOutputs(transaction); code != kExitOk) return code;

  std::cerr << "integrated " << poses.size() << " frames: integrate median "
            << j["integrate_ms_median"] << " ms, render median " << j["render_ms_median"] << " ms; "
            << volume.num_blocks() << " blocks, " << j["map_mb"] << " MiB\n"
            << "mesh: " << mesh.num_vertices() << " vertices, " << mesh.num_triangles()
            << " triangles in " << j["mesh_ms"] << " ms\n"
            << "accuracy: RMS " << eval->accuracy_rms_m * 1000
            << " mm (target <= " << rms_target_m * 1000 << " mm: " << (rms_met ? "met" : "NOT met")
            << "), mean " << eval->accuracy_mean_m * 1000 << " mm\n"
            << "completeness: " << eval->completeness * 100 << " % of the observable surface ("
            << j["observable_fraction"].get<double>() * 100 << " % of the room) within "
            << eval_params.threshold_m * 1000 << " mm (target >= " << kCompletenessTarget * 100
            << " %: " << (completeness_met ? "met" : "NOT met") << "), "
            << eval->completeness_all * 100 << " % of all surface\n"
            << "outputs in " << o.out_dir << ":\n"
            << "  " << mesh_path << "  reconstruction\n"
            << "  " << gt_path << "  ground-truth room\n"
            << "  " << map_path << "  TSDF map (voxplan mesh / info)\n"
            << "  " << stats_path << "  these numbers\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddDemoCommand(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* sub = app.add_subcommand(
      "demo", "Render a synthetic room, fuse it, mesh it and score the mesh (no data needed)");
  sub->add_option("--out", o->out_dir, "Output folder")->capture_default_str();
  sub->add_option("--frames", o->frames, "Frames along the demo trajectory")
      ->check(IntInRange(1, 100000))
      ->capture_default_str();
  sub->add_option("--voxel-size", o->voxel_size_m, "Voxel size in metres")
      ->check(VoxelSize())
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  AddMemoryBudgetOptions(sub, o->memory, /*with_on_limit=*/false);
  return {sub, [o] { return RunDemo(*o); }};
}

}  // namespace voxplan::cli
