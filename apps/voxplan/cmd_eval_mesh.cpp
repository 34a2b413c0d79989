// voxplan eval mesh: accuracy and completeness of a reconstruction against ground truth,
// optionally on the surface a set of camera poses could observe.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "apps/voxplan/cli_common.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "eval/eval_mesh.h"
#include "eval/visibility.h"
#include "io/dataset.h"
#include "io/mesh_io.h"
#include "io/tum_trajectory.h"
#include "sim/raycaster.h"

namespace voxplan::cli {

namespace {

struct EvalMeshOptions {
  std::string reconstruction;
  std::string ground_truth;
  double threshold_m = 0.05;
  double samples_per_m2 = 10000.0;
  uint64_t seed = 1;
  std::string gt_up = "z";
  double gt_scale = 1.0;
  int threads = 0;
  // Completeness on the observable surface: the camera poses (a dataset folder or a TUM file),
  // which of them to use, the camera of a TUM file, and the depth range that was fused.
  std::string observable_from;
  int observable_stride = 1;
  std::string intrinsics;        // fx,fy,cx,cy; default: the dataset's, or sim render's default
  std::string size = "640x480";  // image size for a TUM file (a dataset's images give theirs)
  double min_depth_m = 0.1;      // fuse's defaults
  double max_depth_m = 3.0;
};

// The poses and camera completeness is restricted to. A dataset folder gives its own camera and
// ground-truth poses (frames without a pose are skipped); a TUM trajectory file needs the camera
// sim render used, from --intrinsics and --size (sim render's defaults when not given).
struct ObservableViews {
  PinholeCamera camera;
  std::vector<Pose3d> T_W_C;  // every stride-th pose
  size_t poses_total = 0;
};

Result<ObservableViews> ReadObservableViews(const EvalMeshOptions& o) {
  std::error_code ec;
  ObservableViews views;
  std::optional<PinholeCamera> intrinsics;
  if (!o.intrinsics.empty()) {
    Result<PinholeCamera> k = ParseIntrinsics(o.intrinsics);
    if (!k.ok()) return k.status();
    intrinsics = *k;
  }
  if (std::filesystem::is_directory(o.observable_from, ec)) {
    DatasetOptions dataset_options;
    dataset_options.intrinsics = intrinsics;
    Result<std::unique_ptr<Dataset>> dataset = OpenDataset(o.observable_from, dataset_options);
    if (!dataset.ok()) return dataset.status();  // its messages name the file
    const DatasetInfo& info = (*dataset)->info();
    views.camera = info.camera;
    VOXPLAN_RETURN_IF_ERROR(bounds::CheckIntrinsics(views.camera).Naming(o.observable_from));
    views.poses_total = info.num_frames;
    // Loading decodes the images too; only the kept frames are loaded.
    for (size_t i = 0; i < info.num_frames; i += size_t(o.observable_stride)) {
      Result<Frame> frame = (*dataset)->Load(i);
      if (!frame.ok()) return frame.status();
      if (frame->T_W_C) views.T_W_C.push_back(*frame->T_W_C);
    }
    if (views.T_W_C.empty())
      return InvalidArgument(o.observable_from + ": the dataset has no ground-truth poses");
    return views;
  }
  if (!std::filesystem::is_regular_file(o.observable_from, ec))
    return NotFound("--observable-from: no dataset folder or trajectory file at " +
                    o.observable_from);
  const Result<std::pair<int, int>> size = ParseImageSize(o.size);
  if (!size.ok()) return size.status();
  const auto [width, height] = *size;
  // sim render's defaults: fx = fy = 525, principal point at the image centre.
  views.camera = intrinsics.value_or(
      PinholeCamera{0, 0, 525.f, 525.f, 0.5f * float(width - 1), 0.5f * float(height - 1)});
  views.camera.width = width;
  views.camera.height = height;
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckIntrinsics(views.camera));
  Result<TumTrajectory> trajectory = ReadTumTrajectory(o.observable_from);
  if (!trajectory.ok()) return trajectory.status();  // path:line: ...
  views.poses_total = trajectory->T_W_C.size();
  for (size_t i = 0; i < trajectory->T_W_C.size(); i += size_t(o.observable_stride))
    views.T_W_C.push_back(trajectory->T_W_C[i]);
  return views;
}

int RunEvalMesh(const EvalMeshOptions& o) {
  std::error_code ec;
  for (const std::string& path : {o.reconstruction, o.ground_truth}) {
    if (!std::filesystem::is_regular_file(path, ec)) return Fail("mesh file not found: " + path);
  }
  if (!(o.max_depth_m > o.min_depth_m))
    return Fail("--max-depth must be greater than --min-depth", kExitUsage);
  std::optional<ObservableViews> views;
  if (!o.observable_from.empty()) {  // small inputs: checked before the meshes are read
    Result<ObservableViews> read = ReadObservableViews(o);
    if (!read.ok()) {
      // Bad paths, sizes and poses are the caller's; only a failing read is not.
      const bool usage = read.status().code() != StatusCode::kIoError;
      return Fail(read.status().message(), usage ? kExitUsage : kExitFailure);
    }
    views = std::move(*read);
  }
  ThreadLimit thread_limit(o.threads);
  Result<Mesh> reconstruction = ReadMesh(o.reconstruction);
  if (!reconstruction.ok()) return Fail(MessageNaming(reconstruction.status(), o.reconstruction));
  MeshReadOptions gt_options;
  gt_options.up = o.gt_up == "y" ? UpAxis::kY : UpAxis::kZ;
  gt_options.scale = float(o.gt_scale);
  Result<Mesh> ground_truth = ReadMesh(o.ground_truth, gt_options);
  if (!ground_truth.ok()) return Fail(MessageNaming(ground_truth.status(), o.ground_truth));

  MeshEvalParams params;
  params.threshold_m = float(o.threshold_m);
  params.samples_per_m2 = float(o.samples_per_m2);
  params.seed = o.seed;
  const Stopwatch clock;
  std::unique_ptr<MeshRaycaster> raycaster;  // the filter renders with it: it lives as long
  if (views) {
    // The ground truth as the sensor saw it, within the depth range that was fused.
    Result<std::unique_ptr<MeshRaycaster>> created = MeshRaycaster::Create(*ground_truth);
    if (!created.ok()) return Fail(MessageNaming(created.status(), o.ground_truth));
    raycaster = std::move(*created);
    VisibilityParams visibility;
    visibility.min_depth_m = float(o.min_depth_m);
    visibility.max_depth_m = float(o.max_depth_m);
    Result<PointSetFilter> observable =
        ObservableSurfaceFilter(*raycaster, views->camera, views->T_W_C, visibility);
    if (!observable.ok()) return Fail(MessageNaming(observable.status(), o.observable_from));
    params.ground_truth_filter = *observable;
  }
  Result<MeshEvalResult> result = EvaluateMesh(*reconstruction, *ground_truth, params);
  if (!result.ok()) return Fail("evaluation failed: " + result.status().message());
  const MeshEvalResult& r = *result;
  const double observable_fraction =
      double(r.ground_truth_samples) / double(r.ground_truth_samples_all);

  std::cerr << "accuracy: mean " << r.accuracy_mean_m * 1000 << " mm, RMS "
            << r.accuracy_rms_m * 1000 << " mm, median " << r.accuracy_median_m * 1000 << " mm ("
            << r.reconstruction_samples << " samples)\n";
  if (views)
    std::cerr << "completeness: " << r.completeness * 100 << " % of the observable surface ("
              << RoundTo(observable_fraction * 100, 1) << " % of the ground truth, seen from "
              << views->T_W_C.size() << " poses at " << o.min_depth_m << "-" << o.max_depth_m
              << " m), " << r.completeness_all * 100 << " % of the whole ground truth, within "
              << o.threshold_m << " m\n";
  else
    std::cerr << "completeness: " << r.completeness * 100 << " % within " << o.threshold_m << " m ("
              << r.ground_truth_samples << " samples)\n";
  nlohmann::json j;
  j["command"] = "eval mesh";
  j["reconstruction"] = o.reconstruction;
  j["ground_truth"] = o.ground_truth;
  j["accuracy_mean_m"] = r.accuracy_mean_m;
  j["accuracy_rms_m"] = r.accuracy_rms_m;
  j["accuracy_median_m"] = r.accuracy_median_m;
  // completeness: of the observable surface with --observable-from, else of the whole ground
  // truth; completeness_full: always of the whole ground truth.
  j["completeness"] = r.completeness;
  j["completeness_percent"] = RoundTo(100.0 * r.completeness, 3);
  j["completeness_full"] = r.completeness_all;
  j["completeness_full_percent"] = RoundTo(100.0 * r.completeness_all, 3);
  j["observable_fraction"] = observable_fraction;
  j["observable_area_m2"] = observable_fraction * r.ground_truth_area_m2;
  if (views) {
    j["observable_from"] = o.observable_from;
    j["observable_poses"] = views->T_W_C.size();
    j["observable_poses_total"] = views->poses_total;
    j["observable_stride"] = o.observable_stride;
    j["camera"] = CameraJson(views->camera);
    j["min_depth_m"] = o.min_depth_m;
    j["max_depth_m"] = o.max_depth_m;
  } else {
    j["observable_from"] = nullptr;
  }
  j["threshold_m"] = o.threshold_m;
  j["samples_per_m2"] = o.samples_per_m2;
  j["seed"] = o.seed;
  j["reconstruction_samples"] = r.reconstruction_samples;
  j["ground_truth_samples"] = r.ground_truth_samples;
  j["ground_truth_samples_full"] = r.ground_truth_samples_all;
  j["reconstruction_area_m2"] = r.reconstruction_area_m2;
  j["ground_truth_area_m2"] = r.ground_truth_area_m2;
  j["eval_ms"] = RoundTo(clock.ElapsedMs(), 3);
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddEvalMeshCommand(CLI::App& eval) {
  auto o = std::make_shared<EvalMeshOptions>();
  CLI::App* sub = eval.add_subcommand("mesh", "Accuracy and completeness of a mesh");
  sub->add_option("reconstruction", o->reconstruction, "Reconstructed mesh")->required();
  sub->add_option("ground-truth", o->ground_truth, "Ground-truth mesh")->required();
  sub->add_option("--threshold", o->threshold_m, "Completeness distance threshold (m)")
      ->check(InRange(1e-4, 10.0, "m"))
      ->capture_default_str();
  sub->add_option("--samples-per-m2", o->samples_per_m2, "Surface samples per square metre")
      ->check(InRange(1.0, 1e6))
      ->capture_default_str();
  sub->add_option("--seed", o->seed, "Sampling seed")->capture_default_str();
  sub->add_option("--gt-up", o->gt_up, "Up axis of the ground-truth file (y rotates to Z-up)")
      ->check(CLI::IsMember({"y", "z"}))
      ->capture_default_str();
  sub->add_option("--gt-scale", o->gt_scale, "Scale applied to the ground truth")
      ->check(InRange(1e-6, 1e6))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  sub->add_option("--observable-from", o->observable_from,
                  "Score completeness on the surface these poses could see: a dataset folder "
                  "(its camera and ground-truth poses) or a TUM trajectory file");
  sub->add_option("--observable-stride", o->observable_stride,
                  "With --observable-from: use every N-th pose")
      ->check(CLI::Range(1, 1 << 30))
      ->capture_default_str();
  sub->add_option("--intrinsics", o->intrinsics,
                  "With --observable-from: camera fx,fy,cx,cy (default: the dataset's; for a "
                  "trajectory file sim render's 525,525,centre)");
  sub->add_option("--size", o->size,
                  "With --observable-from a trajectory file: image size WIDTHxHEIGHT")
      ->capture_default_str();
  sub->add_option("--min-depth", o->min_depth_m,
                  "With --observable-from: nearest depth that was fused (m), as given to fuse")
      ->check(InRange(0.0, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  sub->add_option("--max-depth", o->max_depth_m,
                  "With --observable-from: farthest depth that was fused (m), as given to fuse")
      ->check(InRange(0.0, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  return {sub, [o] { return RunEvalMesh(*o); }};
}

}  // namespace voxplan::cli
