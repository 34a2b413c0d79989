// voxplan render: map or mesh -> shaded PNG views (a pose, a dataset's frames, or a turntable
// around the centre), about the map's recorded up axis unless --up says otherwise.
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <tuple>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "apps/voxplan/signals.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "io/dataset.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/sharded_map.h"
#include "io/world_up.h"
#include "sim/mesh_scene.h"
#include "viewer_offscreen/render_views.h"
#include "viewer_offscreen/shading.h"
#include "viewer_offscreen/view_files.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct RenderOptions {
  std::string input;
  std::string pose;  // "tx ty tz qx qy qz qw", T_W_C
  int orbit = 0;     // 0: one view (the first orbit view) unless --pose
  std::string mode = "shaded";
  std::string size = "640x480";
  double fov_deg = 60.0;
  std::string out_dir;
  double min_weight = 0.5;
  std::string up = "auto";    // the scene's up axis; auto: the map's recorded one, else z
  std::string intrinsics;     // "fx,fy,cx,cy" of the views' camera (size from --size)
  DatasetInput dataset;       // --dataset: views at its frames' poses, with its camera
  double orbit_radius_m = 0;  // 0: framed (RenderViews)
  double orbit_height_m = 0;
  bool orbit_height_set = false;
  double near_m = 0.0;          // maps: rays start this far out (cuts away near walls); 0: 0.01 m
  std::string kernel = "auto";  // maps: "scalar" marches the scalar reference (same images)
  int threads = 0;
  std::string dollhouse = "auto";  // auto: on for orbits
};

Result<Pose3f> ParsePose(const std::string& text) {
  double v[7];
  std::istringstream in(text);
  for (double& x : v) {
    if (!(in >> x))
      return InvalidArgument("--pose wants 7 numbers 'tx ty tz qx qy qz qw': " + text);
  }
  std::string extra;
  if (in >> extra) return InvalidArgument("--pose wants 7 numbers 'tx ty tz qx qy qz qw': " + text);
  Result<Pose3d> pose =
      PoseFromTranslationQuaternion(Eigen::Vector3d(v[0], v[1], v[2]), v[3], v[4], v[5], v[6]);
  if (!pose.ok()) return InvalidArgument("--pose: " + pose.status().message());
  return Pose3f(pose->cast<float>());
}

nlohmann::json Json(const Eigen::Vector3f& v) {
  return {RoundTo(v.x(), 6), RoundTo(v.y(), 6), RoundTo(v.z(), 6)};
}

// The up axis of the views: --up, else (auto) the map's recorded one, else +z. `source` says
// which: "--up", "map", or "default" (which a --dataset's own up axis then replaces).
Eigen::Vector3f ViewsUp(const RenderOptions& o, std::string* source) {
  if (o.up != "auto") {
    *source = "--up";
    return WorldUpOrZ(*ParseWorldUp(o.up));  // checked by the validator
  }
  *source = "default";
  if (!IsMapPath(o.input)) return Eigen::Vector3f::UnitZ();
  if (IsShardedMapFile(o.input)) {  // a sharded map's manifest records it (io/sharded_map.h)
    const Result<ShardManifest> manifest = ReadShardManifest(o.input);
    if (!manifest.ok() || manifest->up == WorldUp::kUnknown) return Eigen::Vector3f::UnitZ();
    *source = "map";
    return WorldUpOrZ(manifest->up);
  }
  // A header that does not read leaves the up at +z; loading the map reports the problem.
  const Result<MapHeader> header = ReadMapHeader(o.input);
  if (!header.ok() || header->up == WorldUp::kUnknown) return Eigen::Vector3f::UnitZ();
  *source = "map";
  return WorldUpOrZ(header->up);
}

// --dataset: the poses of the selected frames that have one, their indices, the camera, the
// world's up axis and the dataset's files (no output may be one).
struct DatasetViews {
  std::vector<Pose3f> poses;
  std::vector<size_t> frames;
  PinholeCamera camera;
  WorldUp up = WorldUp::kUnknown;
  std::vector<std::string> files;
};
int LoadDatasetViews(const DatasetInput& in, DatasetViews* views) {
  OpenedDataset opened;
  if (int code = OpenDatasetInput(in, {}, &opened); code != kExitOk) return code;
  views->files = opened.dataset->InputFiles();
  views->camera = opened.dataset->info().camera;
  views->up = opened.dataset->info().up;
  for (size_t i : opened.indices) {
    Result<Frame> frame = opened.dataset->Load(i);
    if (!frame.ok()) return Fail(MessageNaming(frame.status(), in.dataset));
    if (!frame->T_W_C) continue;  // ICL-NUIM's first frame, a gap in the ground truth
    views->poses.push_back(Pose3f(frame->T_W_C->cast<float>()));
    views->frames.push_back(i);
  }
  if (views->poses.empty())
    return Fail("none of the " + std::to_string(opened.indices.size()) +
                " selected frames has a pose: " + in.dataset);
  return kExitOk;
}

int RunRender(const RenderOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.input, ec)) return Fail("input file not found: " + o.input);
  RenderViewsParams params;
  std::tie(params.width, params.height) = *ParseImageSize(o.size);  // checked by the validator
  params.mode = *ParseShadeMode(o.mode);
  params.fov_deg = float(o.fov_deg);
  if (o.orbit_radius_m > 0.0) params.orbit_radius_m = float(o.orbit_radius_m);
  if (o.orbit_height_set) params.orbit_height_m = float(o.orbit_height_m);
  std::string up_source;
  params.up_W = ViewsUp(o, &up_source);
  if (!o.pose.empty()) params.T_W_C = *ParsePose(o.pose);  // checked by the validator
  params.orbit_views = o.orbit;
  if (!o.intrinsics.empty()) {
    Result<PinholeCamera> camera = ParseIntrinsics(o.intrinsics);
    if (!camera.ok()) return Fail("--intrinsics: " + camera.status().message(), kExitUsage);
    camera->width = params.width;
    camera->height = params.height;
    if (Status s = bounds::CheckIntrinsics(*camera); !s.ok())
      return Fail("--intrinsics: " + s.message(), kExitUsage);
    params.camera = *camera;
  }
  const bool at_dataset = !o.dataset.dataset.empty();
  ThreadLimit thread_limit(o.threads);
  // The files it will write: none may be the input (nor, with --dataset, one of its files).
  const auto view_files = [&](size_t n) {
    std::vector<PathUse> outputs;
    for (size_t k = 0; k < n; ++k)
      outputs.push_back({"--out", (fs::path(o.out_dir) / ViewFileName(k)).string()});
    return outputs;
  };
  DatasetViews dataset_views;
  if (at_dataset) {
    if (int code = LoadDatasetViews(o.dataset, &dataset_views); code != kExitOk) return code;
    params.poses = dataset_views.poses;
    params.camera = dataset_views.camera;
    // A map that records no up axis (version 1) is in the dataset's world: take its up.
    if (up_source == "default" && dataset_views.up != WorldUp::kUnknown) {
      params.up_W = WorldUpOrZ(dataset_views.up);
      up_source = "dataset";
    }
  }
  const size_t num_views = at_dataset     ? params.poses.size()
                           : params.T_W_C ? 1
                                          : size_t(std::max(o.orbit, 1));
  std::vector<PathUse> inputs = {{"the input", o.input}};
  AddInputs(inputs, "the dataset", dataset_views.files);
  if (int code = RefusePathCollisions(view_files(num_views), inputs); code != kExitOk) return code;

  const Stopwatch load_clock;
  MapSceneParams map_params;
  map_params.min_weight = float(o.min_weight);
  map_params.near_m = float(o.near_m);
  map_params.simd = o.kernel != "scalar";
  DollhouseParams dollhouse;
  dollhouse.enabled =
      o.dollhouse == "on" || (o.dollhouse == "auto" && !params.T_W_C && params.poses.empty());
  dollhouse.up_W = params.up_W;
  params.choose_side = dollhouse.enabled;
  Result<std::unique_ptr<SurfaceScene>> loaded = LoadSurfaceScene(o.input, map_params, dollhouse);
  if (!loaded.ok()) return Fail(MessageNaming(loaded.status(), o.input));
  const double load_ms = load_clock.ElapsedMs();

  const Stopwatch render_clock;
  const StopPolling polling;  // a signal ends the rendering after the current view
  params.stop_requested = StopRequestedFn();
  Result<RenderedViews> views = RenderViews(**loaded, params);
  if (!views.ok() && views.status().code() == StatusCode::kCancelled)
    return Interrupted(views.status().message() + "; nothing written");
  if (!views.ok()) return Fail("shading failed: " + views.status().message());
  const double render_ms = render_clock.ElapsedMs();
  // A y-down camera whose top looks down: likely a pose of a y-flipped dataset (ICL-NUIM's).
  if (params.T_W_C && views->camera.fy > 0.0f &&
      -params.T_W_C->linear().col(1).dot(params.up_W.normalized()) < -0.5f)
    Warn("the view is upside down about the up axis (" + up_source +
         "); a pose of a y-flipped camera (ICL-NUIM's)? Give its --intrinsics (negative fy) or "
         "render at --dataset");

  // Only now touch the disk: every image is in memory.
  const Stopwatch write_clock;
  OutputTransaction transaction;  // every view lands, or none
  transaction.WatchFolder(o.out_dir);
  Result<std::vector<std::string>> written =
      WriteViewFiles(o.out_dir, views->images, WriteColorPng);
  if (!written.ok()) return Fail(written.status().message());
  if (int code = CommitOutputs(transaction); code != kExitOk) return code;
  const double write_ms = write_clock.ElapsedMs();

  for (const std::string& path : *written) std::cerr << "wrote " << path << "\n";
  std::cerr << "render: " << written->size() << " " << ShadeModeName(params.mode) << " view(s) of "
            << o.input << " at " << views->camera.width << "x" << views->camera.height << " in "
            << RoundTo(render_ms, 1) << " ms\n";
  nlohmann::json j;
  j["command"] = "render";
  j["input"] = o.input;
  j["input_kind"] = IsMapPath(o.input) ? "map" : "mesh";
  j["mode"] = ShadeModeName(params.mode);
  j["width"] = views->camera.width;
  j["height"] = views->camera.height;
  j["fov_deg"] = o.fov_deg;
  j["camera"] = CameraJson(views->camera);  // as rendered (UprightCamera)
  j["rows_flipped"] = views->rows_flipped;
  j["up"] = Json(params.up_W);
  j["up_source"] = up_source;
  if (at_dataset) {
    j["dataset"] = o.dataset.dataset;
    j["dataset_frames"] = dataset_views.frames;
  }
  j["views"] = written->size();
  j["out"] = o.out_dir;
  j["files"] = *written;
  j["bounds_min"] = Json(views->bounds_W.min());
  j["bounds_max"] = Json(views->bounds_W.max());
  j["centre"] = Json(views->framing.centre_W);
  if (o.pose.empty() && !at_dataset) {
    j["orbit_radius_m"] = RoundTo(views->framing.radius_m, 6);
    j["orbit_height_m"] = RoundTo(views->framing.height_m, 6);
    // What the orbit was framed on: a map's surface (its zero crossings) or the bounds (a mesh).
    j["framed_on"] = views->surface_framed ? "surface" : "bounds";
  }
  j["hit_fraction"] = RoundTo(views->hit_fraction, 6);
  j["dollhouse"] = params.choose_side;
  j["threads"] = MaxThreads();
  j["load_ms"] = RoundTo(load_ms, 3);
  j["render_ms"] = RoundTo(render_ms, 3);
  j["write_ms"] = RoundTo(write_ms, 3);
  PrintJsonLine(j);
  return kExitOk;
}

// Refuses what `parse` (ParseImageSize, ParsePose) refuses, with its message.
template <class T>
CLI::Validator ParsedBy(Result<T> (*parse)(const std::string&), const std::string& description) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        Result<T> parsed = parse(text);
        return parsed.ok() ? std::string() : parsed.status().message();
      },
      description);
}

CLI::Validator InputValidator() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        if (IsMapPath(path) || IsSupportedMeshExtension(path)) return {};
        return "unsupported input (use a .vpmap map or a .ply, .obj, .glb or .stl mesh): " + path;
      },
      "MAP|MESH");
}

CLI::Validator OutputDirValidator() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        std::error_code ec;
        if (path.empty()) return "empty output folder";
        if (fs::exists(path, ec)) {
          return fs::is_directory(path, ec) ? std::string()
                                            : "output path exists and is not a folder: " + path;
        }
        // It will be created: the nearest existing ancestor must be a writable folder.
        fs::path ancestor = fs::absolute(path, ec).parent_path();
        while (!ancestor.empty() && !fs::exists(ancestor, ec) && ancestor != ancestor.parent_path())
          ancestor = ancestor.parent_path();
        if (!fs::is_directory(ancestor, ec) || ::access(ancestor.c_str(), W_OK) != 0)
          return "cannot create output folder " + path + " (" + ancestor.string() +
                 " is not a writable folder)";
        return {};
      },
      "DIR");
}

}  // namespace

Command AddRenderCommand(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* sub = app.add_subcommand("render", "Render a map or mesh to PNG images");
  sub->add_option("input", o->input, "Map (.vpmap) or mesh (.ply .obj .glb .stl)")
      ->required()
      ->check(InputValidator());
  CLI::Option* pose =
      sub->add_option("--pose", o->pose, "Camera-to-world pose \"tx ty tz qx qy qz qw\"")
          ->check(ParsedBy(&ParsePose, "\"tx ty tz qx qy qz qw\""));
  CLI::Option* orbit =
      sub->add_option("--orbit", o->orbit, "Turntable of N views around the centre")
          ->check(IntInRange(1, 3600));
  pose->excludes(orbit);
  CLI::Option* dataset =
      sub->add_option("--dataset", o->dataset.dataset,
                      "Render at this dataset's frames' poses with its camera and image size "
                      "(folder, .sens or .bag)");
  dataset->excludes(pose)->excludes(orbit);
  sub->add_option("--format", o->dataset.format, "With --dataset: its format")
      ->check(CLI::IsMember(
          {"auto", "tum", "icl", "redwood", "7scenes", "3dmatch", "replica", "scannet", "rosbag"}))
      ->capture_default_str()
      ->needs(dataset);
  AddTopicsOption(sub, o->dataset.topics);
  sub->add_option("--frames", o->dataset.frames, "With --dataset: frames to render (0: all)")
      ->check(FrameCount())
      ->capture_default_str()
      ->needs(dataset);
  sub->add_option("--start", o->dataset.start, "With --dataset: first frame (0-based)")
      ->check(IntInRange(0, bounds::kFramesMax))
      ->capture_default_str()
      ->needs(dataset);
  sub->add_option("--stride", o->dataset.stride, "With --dataset: every K-th frame")
      ->check(Stride())
      ->capture_default_str()
      ->needs(dataset);
  CLI::Option* intrinsics =
      sub->add_option("--intrinsics", o->intrinsics,
                      "Camera fx,fy,cx,cy of the views (a dataset's, fy may be negative), at "
                      "--size; default: from --fov-deg");
  intrinsics->excludes(dataset);
  sub->add_option("--mode", o->mode, "Shading")
      ->check(CLI::IsMember({"shaded", "normals", "colour", "color", "depth"}))
      ->capture_default_str();
  sub->add_option("--size", o->size, "Image size WxH (with --dataset: the dataset's)")
      ->check(ParsedBy(&ParseImageSize, "WxH"))
      ->capture_default_str()
      ->excludes(dataset);
  sub->add_option("--fov-deg", o->fov_deg, "Horizontal field of view (degrees)")
      ->check(InRange(1.0, 179.0, "degrees"))
      ->capture_default_str()
      ->excludes(dataset)
      ->excludes(intrinsics);
  sub->add_option("--out,-o", o->out_dir, "Output folder (created if missing)")
      ->required()
      ->check(OutputDirValidator());
  sub->add_option("--min-weight", o->min_weight, "Maps: voxels with less weight are unobserved")
      ->check(InRange(0.0, kMaxWeight))
      ->capture_default_str();
  sub->add_option("--up", o->up,
                  "Up axis of the scene, for orbits and upright pictures: auto (the map's "
                  "recorded one, else the --dataset's, else z), x, y, z, -x, -y, -z")
      ->check(CLI::IsMember({"auto", "x", "y", "z", "+x", "+y", "+z", "-x", "-y", "-z"}))
      ->capture_default_str();
  sub->add_option("--orbit-radius", o->orbit_radius_m,
                  "Orbit: distance from the centre across the up axis (m; default: framed on a "
                  "map's surface, a mesh's bounds)")
      ->check(InRange(1e-3, 1e4, "m"));
  sub->add_option_function<double>(
         "--orbit-height",
         [o](double h) {
           o->orbit_height_m = h;
           o->orbit_height_set = true;
         },
         "Orbit: height above the centre along the up axis (m; default: framed on a map's "
         "surface, a mesh's bounds)")
      ->check(InRange(-1e4, 1e4, "m"));
  sub->add_option("--near", o->near_m,
                  "Maps: start rays this far from the camera (m), to cut away near walls")
      ->check(InRange(0.0, 1e4, "m"));
  sub->add_option("--kernel", o->kernel, "Maps: ray-casting march (scalar: the reference)")
      ->check(CLI::IsMember({"auto", "scalar"}))
      ->capture_default_str();
  sub->add_option("--dollhouse", o->dollhouse,
                  "Cut away what hides the rooms (meshes: back faces, and a roof with all above "
                  "60% of the height; maps pass back faces always) and orbit from the side that "
                  "sees more; auto: for orbits")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  return {sub, [o] { return RunRender(*o); }};
}

}  // namespace voxplan::cli
