// voxplan fuse: dataset -> TSDF volume -> mesh / map / stats.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "fusion/tracking.h"
#include "io/dataset.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/tum_trajectory.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

const std::map<std::string, Weighting> kWeightings = {{"constant", Weighting::kConstant},
                                                      {"depth", Weighting::kDepthDependent}};
const std::map<std::string, Kernel> kKernels = {
    {"auto", Kernel::kAuto}, {"scalar", Kernel::kScalar}, {"simd", Kernel::kSimd}};

struct FuseOptions {
  DatasetInput in;
  double voxel_size_m = 0.01;
  double trunc_m = 0.04;
  int threads = 0;
  std::string intrinsics;
  double depth_scale = 0.0;
  std::string weighting = "constant";
  std::string kernel = "auto";
  double max_weight = 64.0;
  double mesh_min_weight = 0.5;
  std::string mesh_path, map_path, stats_path, frame_list_path, trajectory_path;
  bool track = false;
  double photometric_weight = 0.0;
};

// Beyond this many, per-frame skip warnings collapse into one count at the end.
constexpr int kMaxSkipWarnings = 5;

bool AllZero(const DepthImage& depth) {
  return std::none_of(depth.data.begin(), depth.data.end(), [](float z) { return z > 0.f; });
}

nlohmann::json OrNull(const std::string& path) {
  return path.empty() ? nlohmann::json(nullptr) : nlohmann::json(path);
}

int RunFuse(const FuseOptions& o) {
  // Everything the arguments alone can refuse is refused before the dataset is read.
  if (o.trunc_m < o.voxel_size_m) {
    std::ostringstream message;
    message << "--trunc (" << o.trunc_m << ") must be at least --voxel-size (" << o.voxel_size_m
            << ")";
    return Fail(message.str(), kExitUsage);
  }
  DatasetOptions dataset_options;
  if (!o.intrinsics.empty()) {
    Result<PinholeCamera> camera = ParseIntrinsics(o.intrinsics);
    if (!camera.ok()) return Fail(camera.status().message(), kExitUsage);
    dataset_options.intrinsics = *camera;
  }
  if (o.depth_scale > 0.0) dataset_options.depth_scale = o.depth_scale;

  ThreadLimit thread_limit(o.threads);
  OpenedDataset opened;
  if (int code = OpenDatasetInput(o.in, dataset_options, &opened); code != kExitOk) return code;
  const Dataset& dataset = *opened.dataset;
  const DatasetInfo& info = dataset.info();
  const std::vector<size_t>& indices = opened.indices;

  IntegrateParams params;
  params.min_depth_m = float(o.in.min_depth_m);
  params.max_depth_m = float(o.in.max_depth_m);
  params.max_weight = float(o.max_weight);
  params.weighting = kWeightings.at(o.weighting);
  params.kernel = kKernels.at(o.kernel);
  TsdfVolume volume(VolumeParams{float(o.voxel_size_m), float(o.trunc_m)});

  std::cerr << "fuse: " << info.root << " (" << DatasetFormatName(info.format) << "), "
            << indices.size() << " of " << info.num_frames << " frames, voxel " << o.voxel_size_m
            << " m, trunc " << o.trunc_m << " m, " << MaxThreads() << " threads, kernel "
            << KernelName(ResolveKernel(params.kernel)) << std::endl;

  std::vector<double> load_ms, integrate_ms, frame_ms;
  nlohmann::json frame_list = nlohmann::json::array();
  size_t skipped_no_pose = 0, skipped_empty = 0, frames_lost = 0;
  std::vector<double> track_ms, trajectory_t;
  std::vector<Pose3f> trajectory;
  std::optional<FrameTracker> tracker;
  bool tracker_started = false;
  if (o.track) {
    TrackingParams tracking;
    tracking.photometric_weight = float(o.photometric_weight);
    tracking.raycast.max_depth_m = float(o.in.max_depth_m);
    tracking.raycast.min_depth_m = float(o.in.min_depth_m);
    tracker.emplace(info.camera, tracking);
  }
  Progress progress("fuse", indices.size());
  const Stopwatch loop_clock;
  for (size_t k = 0; k < indices.size(); ++k) {
    const size_t i = indices[k];
    const Stopwatch load_clock;
    Result<Frame> frame = dataset.Load(i);
    const double load = load_clock.ElapsedMs();
    if (!frame.ok()) {
      progress.Finish();
      return Fail("frame " + std::to_string(i) + ": " + frame.status().message());
    }
    if (AllZero(frame->depth)) {
      if (++skipped_empty <= kMaxSkipWarnings) {
        progress.Warn("frame " + std::to_string(i) + " (" + frame->depth_path +
                      ") has no valid depth; skipped");
      }
      progress.Update(k + 1);
      continue;
    }
    // The pose to integrate with: the dataset's, or with --track the tracker's (the first
    // frame starts from the dataset pose when there is one, else the identity).
    std::optional<Pose3f> T_W_C;
    if (tracker && !tracker_started) {
      T_W_C = frame->T_W_C ? Pose3f(frame->T_W_C->cast<float>()) : Pose3f::Identity();
      tracker->Reset(*T_W_C);
      tracker_started = true;
    } else if (tracker) {
      Result<TrackingResult> tracked = tracker->Track(frame->depth, frame->color, volume);
      if (!tracked.ok()) {
        progress.Finish();
        return Fail(MessageNaming(tracked.status(), frame->depth_path));
      }
      track_ms.push_back(tracked->track_ms);
      if (tracked->ok) {
        T_W_C = tracked->T_W_C;
        tracker->Accept(*T_W_C);
      } else if (++frames_lost <= kMaxSkipWarnings) {
        progress.Warn("frame " + std::to_string(i) + " (" + frame->depth_path +
                      ") lost tracking (" + tracked->failure + "); not integrated");
      }
    } else if (frame->T_W_C) {
      T_W_C = frame->T_W_C->cast<float>();
    } else if (++skipped_no_pose <= kMaxSkipWarnings) {
      progress.Warn("frame " + std::to_string(i) + " (" + frame->depth_path +
                    ") has no pose; skipped");
    }
    if (T_W_C) {
      const Stopwatch integrate_clock;
      Result<IntegrateStats> stats =
          IntegrateFrame(frame->depth, frame->color, info.camera, *T_W_C, params, volume);
      const double integrate = integrate_clock.ElapsedMs();
      if (!stats.ok()) {
        progress.Finish();
        return Fail(MessageNaming(stats.status(), frame->depth_path));
      }
      load_ms.push_back(load);
      integrate_ms.push_back(integrate);
      frame_ms.push_back(load + integrate);
      trajectory_t.push_back(frame->timestamp);
      trajectory.push_back(*T_W_C);
      if (!o.frame_list_path.empty()) {
        frame_list.push_back(
            FrameListEntry(frame->depth_path, frame->color_path, T_W_C->matrix().cast<double>()));
      }
    }
    progress.Update(k + 1);
  }
  progress.Finish();
  const double loop_s = loop_clock.ElapsedMs() / 1000.0;
  if (skipped_no_pose > kMaxSkipWarnings) {
    Warn(std::to_string(skipped_no_pose) + " frames in all had no pose and were skipped");
  }
  if (frames_lost > kMaxSkipWarnings) {
    Warn(std::to_string(frames_lost) + " frames in all lost tracking and were not integrated");
  }
  if (skipped_empty > kMaxSkipWarnings) {
    Warn(std::to_string(skipped_empty) + " frames in all had no valid depth and were skipped");
  }
  if (frame_ms.empty()) {
    return Fail("no frame was integrated (" + std::to_string(indices.size()) +
                " selected, all skipped): " + o.in.dataset);
  }

  Mesh mesh;
  double mesh_ms = 0.0;
  if (!o.mesh_path.empty()) {
    const Stopwatch mesh_clock;
    MeshParams mesh_params;
    mesh_params.min_weight = float(o.mesh_min_weight);
    mesh = ExtractMesh(volume, mesh_params);
    mesh_ms = mesh_clock.ElapsedMs();
    if (Status s = WriteMesh(mesh, o.mesh_path); !s.ok()) {
      return Fail(MessageNaming(s, o.mesh_path));
    }
  }
  if (!o.map_path.empty()) {
    if (Status s = SaveMap(volume, o.map_path); !s.ok()) return Fail(MessageNaming(s, o.map_path));
  }
  if (!o.trajectory_path.empty()) {
    if (Status s = WriteTumTrajectory(o.trajectory_path, trajectory_t, trajectory); !s.ok())
      return Fail(MessageNaming(s, o.trajectory_path));
  }
  if (!o.frame_list_path.empty()) {
    // Exactly the frames integrated, with the parameters, for reference runs of other
    // pipelines (bench/open3d_fusion.py) on identical input.
    const nlohmann::json list = FrameList(info.camera, info.depth_scale, o.voxel_size_m, o.trunc_m,
                                          o.in.min_depth_m, o.in.max_depth_m, frame_list);
    if (Status s = WriteJsonFile(list, o.frame_list_path); !s.ok())
      return Fail(MessageNaming(s, o.frame_list_path));
  }

  const TimingSummary load_t = Summarize(load_ms), integrate_t = Summarize(integrate_ms),
                      frame_t = Summarize(frame_ms);
  const size_t integrated = frame_ms.size();
  nlohmann::json j;
  j["command"] = "fuse";
  j["dataset"] = o.in.dataset;
  j["format"] = DatasetFormatName(info.format);
  j["frames"] = integrated;
  j["frames_selected"] = indices.size();
  j["frames_skipped"] = skipped_no_pose + skipped_empty;
  j["frames_skipped_no_pose"] = skipped_no_pose;
  j["tracking"] = o.track;
  j["frames_lost"] = frames_lost;
  j["track_ms_median"] = RoundTo(Summarize(track_ms).median, 3);
  j["trajectory"] = OrNull(o.trajectory_path);
  j["frames_skipped_no_depth"] = skipped_empty;
  j["voxel_size_m"] = o.voxel_size_m;
  j["trunc_m"] = o.trunc_m;
  j["min_depth_m"] = o.in.min_depth_m;
  j["max_depth_m"] = o.in.max_depth_m;
  j["max_weight"] = o.max_weight;
  j["weighting"] = o.weighting;
  j["threads"] = MaxThreads();
  j["kernel"] = KernelName(ResolveKernel(params.kernel));
  j["camera"] = {{"width", info.camera.width},       {"height", info.camera.height},
                 {"fx", FloatValue(info.camera.fx)}, {"fy", FloatValue(info.camera.fy)},
                 {"cx", FloatValue(info.camera.cx)}, {"cy", FloatValue(info.camera.cy)}};
  j["depth_scale"] = info.depth_scale;
  j["integrate_ms_median"] = RoundTo(integrate_t.median, 3);
  j["integrate_ms_p90"] = RoundTo(integrate_t.p90, 3);
  j["integrate_ms_mean"] = RoundTo(integrate_t.mean, 3);
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
  j["map"] = OrNull(o.map_path);
  j["stats"] = OrNull(o.stats_path);
  j["peak_rss_mb"] = PeakRssMb();
  if (!o.stats_path.empty()) {
    if (Status s = WriteJsonFile(j, o.stats_path); !s.ok()) {
      return Fail(MessageNaming(s, o.stats_path));
    }
  }

  std::cerr << "fused " << integrated << " frames (" << j["frames_skipped"] << " skipped) in "
            << j["loop_s"] << " s: integrate median " << j["integrate_ms_median"]
            << " ms, load median " << j["load_ms_median"] << " ms, " << j["fps"] << " fps\n"
            << "map: " << volume.num_blocks() << " blocks, " << j["map_mb"] << " MiB, peak RSS "
            << j["peak_rss_mb"] << " MiB\n";
  if (!o.mesh_path.empty()) {
    std::cerr << "mesh: " << o.mesh_path << " (" << mesh.num_vertices() << " vertices, "
              << mesh.num_triangles() << " triangles, " << j["mesh_ms"] << " ms)\n";
  }
  if (!o.map_path.empty()) std::cerr << "map file: " << o.map_path << "\n";
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
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--trunc", o->trunc_m, "Truncation distance in metres")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(NonNegative())
      ->capture_default_str();
  sub->add_option("--intrinsics", o->intrinsics, "Override intrinsics: fx,fy,cx,cy");
  sub->add_option("--depth-scale", o->depth_scale, "Override depth units per metre")
      ->check(Positive());
  sub->add_option("--weighting", o->weighting, "Observation weight")
      ->check(CLI::IsMember({"constant", "depth"}))
      ->capture_default_str();
  sub->add_option("--kernel", o->kernel, "Integration kernel")
      ->check(CLI::IsMember({"auto", "scalar", "simd"}))
      ->capture_default_str();
  sub->add_option("--max-weight", o->max_weight, "Weight cap per voxel")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--mesh-min-weight", o->mesh_min_weight, "Meshing: ignore voxels below this")
      ->check(NonNegative())
      ->capture_default_str();
  sub->add_option("--mesh", o->mesh_path, "Write the mesh (.ply .obj .glb .stl)")
      ->check(MeshOutputValidator());
  sub->add_option("--map", o->map_path, "Write the map (.vpmap)")->check(OutputFileValidator());
  sub->add_option("--stats", o->stats_path, "Write the stats JSON")->check(OutputFileValidator());
  sub->add_flag("--track", o->track,
                "Estimate poses by frame-to-model ICP instead of using the dataset's");
  sub->add_option("--photometric-weight", o->photometric_weight,
                  "With --track: weight of the colour term (0: geometry only)")
      ->check(NonNegative())
      ->capture_default_str();
  sub->add_option("--trajectory", o->trajectory_path,
                  "Write the poses used (TUM format: t tx ty tz qx qy qz qw)")
      ->check(OutputFileValidator());
  sub->add_option("--frame-list", o->frame_list_path,
                  "Write the integrated frames (paths, poses, intrinsics) as JSON")
      ->check(OutputFileValidator());
  return {sub, [o] { return RunFuse(*o); }};
}

}  // namespace voxplan::cli
