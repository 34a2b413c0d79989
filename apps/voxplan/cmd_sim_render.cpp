// voxplan sim render: render a TUM trajectory through a scene into an RGB-D dataset (TUM layout:
// colour, 16-bit depth, 16-bit instance labels, ground truth, camera.txt) that `voxplan fuse`
// reads back, with Kinect-like depth noise.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "io/file_util.h"
#include "io/tum_trajectory.h"
#include "sim/dataset_writer.h"
#include "sim/raycaster.h"
#include "sim/scene_loader.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct SimRenderOptions {
  std::string scene;
  std::string trajectory;
  std::string out_dir;
  SceneFrameOptions frame;
  std::string size = "640x480";
  double fx = 525.0, fy = 0.0, cx = -1.0, cy = -1.0;  // fy 0: fx; cx, cy < 0: image centre
  std::string noise = "on";
  uint64_t seed = 0;
  double max_range = 10.0;
  bool no_color = false, no_labels = false;
  int threads = 0;
};

// id, class, model of every instance: what the label images' ids mean.
Status WriteInstanceClasses(const World& world, const std::string& path) {
  std::string text = "id\tclass\tmodel\n";
  for (const Instance& inst : world.instances)
    text += std::to_string(inst.id) + "\t" + inst.class_name + "\t" + inst.model + "\n";
  return WriteFileAtomically(path, text);
}

int RunSimRender(const SimRenderOptions& o) {
  // Usage checks, before any work.
  const Result<std::pair<int, int>> size = ParseImageSize(o.size);
  if (!size.ok()) return Fail(size.status().message(), kExitUsage);
  const auto [width, height] = *size;
  if (o.noise != "on" && o.noise != "off")
    return Fail("--noise must be on or off, got '" + o.noise + "'", kExitUsage);
  std::error_code ec;
  if (!fs::is_regular_file(o.scene, ec))
    return Fail("scene file not found: " + o.scene, kExitUsage);
  if (!fs::is_regular_file(o.trajectory, ec))
    return Fail("trajectory file not found: " + o.trajectory, kExitUsage);
  const fs::path out(o.out_dir);
  if (!fs::is_directory(out, ec)) {
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (fs::exists(out, ec)) return Fail("--out " + o.out_dir + " is not a folder", kExitUsage);
    if (!fs::is_directory(parent, ec))
      return Fail("output folder's parent does not exist: " + parent.string(), kExitUsage);
  }
  std::vector<PathUse> outputs;
  for (const char* name :
       {"groundtruth.txt", "camera.txt", "depth.txt", "rgb.txt", "labels.txt", "instances.tsv"})
    outputs.push_back({"--out", (out / name).string()});
  if (int code =
          RefusePathCollisions(outputs, {{"--scene", o.scene}, {"--trajectory", o.trajectory}});
      code != kExitOk)
    return code;
  SimDatasetOptions options;
  options.camera.width = width;
  options.camera.height = height;
  options.camera.fx = float(o.fx);
  options.camera.fy = float(o.fy != 0.0 ? o.fy : o.fx);
  options.camera.cx = float(o.cx >= 0.0 ? o.cx : 0.5 * (width - 1));
  options.camera.cy = float(o.cy >= 0.0 ? o.cy : 0.5 * (height - 1));
  if (Status s = bounds::CheckIntrinsics(options.camera); !s.ok())
    return Fail("--fx/--fy/--cx/--cy: " + s.message(), kExitUsage);
  options.max_range_m = float(o.max_range);
  options.noise = o.noise == "on";
  options.noise_params.seed = o.seed;
  options.write_color = !o.no_color;
  options.write_labels = !o.no_labels;
  if (Status s = options.Validate(); !s.ok()) return Fail(s.message(), kExitUsage);
  // The trajectory is small: read and check it (NaN poses, bad lines) before loading the scene.
  Result<TumTrajectory> trajectory = ReadTumTrajectory(o.trajectory);
  if (!trajectory.ok()) return Fail(MessageNaming(trajectory.status(), o.trajectory), kExitUsage);

  ThreadLimit limit(o.threads);
  const Stopwatch clock;
  Result<World> world = LoadWorld(o.scene, SceneLoad(o.frame));
  if (!world.ok()) {
    const bool usage = world.status().code() == StatusCode::kInvalidArgument;
    return Fail(MessageNaming(world.status(), o.scene), usage ? kExitUsage : kExitFailure);
  }
  auto raycaster = MeshRaycaster::Create(*world);
  if (!raycaster.ok()) return Fail(MessageNaming(raycaster.status(), o.scene));
  const double load_ms = clock.ElapsedMs();
  std::cerr << "sim render: " << world->name << ": " << world->mesh.num_triangles()
            << " triangles, " << world->instances.size() << " instances, "
            << trajectory->T_W_C.size() << " poses -> " << o.out_dir << "\n";

  if (!fs::is_directory(out, ec) && !fs::create_directory(out, ec))
    return Fail("cannot create output folder " + o.out_dir + ": " + ec.message());
  Progress progress("sim render", trajectory->T_W_C.size());
  Result<SimDatasetSummary> summary = RenderSimDataset(**raycaster, *trajectory, options, o.out_dir,
                                                       [&](size_t done) { progress.Update(done); });
  progress.Finish();
  if (!summary.ok()) return Fail(summary.status().message());
  std::vector<std::string> paths = summary->paths;
  const std::string classes = (out / "instances.tsv").string();
  if (Status s = WriteInstanceClasses(*world, classes); !s.ok()) return Fail(s.message());
  paths.push_back(classes);

  std::vector<double> frame_ms;
  for (size_t i = 0; i < summary->frames; ++i)
    frame_ms.push_back(summary->render_ms[i] + summary->noise_ms[i] + summary->write_ms[i]);
  nlohmann::json j;
  j["command"] = "sim render";
  j["scene"] = o.scene;
  j["trajectory"] = o.trajectory;
  j["out"] = o.out_dir;
  j["frames"] = summary->frames;
  j["camera"] = CameraJson(options.camera);
  j["noise"] = options.noise;
  j["seed"] = o.seed;
  j["valid_depth_fraction"] = RoundTo(summary->valid_depth_fraction, 4);
  j["ms_per_frame_median"] = RoundTo(Summarize(frame_ms).median, 2);
  j["render_ms_median"] = RoundTo(Summarize(summary->render_ms).median, 2);
  j["noise_ms_median"] = RoundTo(Summarize(summary->noise_ms).median, 2);
  j["write_ms_median"] = RoundTo(Summarize(summary->write_ms).median, 2);
  j["load_ms"] = RoundTo(load_ms, 1);
  j["threads"] = MaxThreads();
  j["paths"] = paths;
  std::cerr << "sim render: " << summary->frames << " frames, median "
            << RoundTo(Summarize(frame_ms).median, 1) << " ms per frame (render "
            << RoundTo(Summarize(summary->render_ms).median, 1) << " ms), "
            << RoundTo(100.0 * summary->valid_depth_fraction, 1) << "% valid depth\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddSimRenderCommand(CLI::App& sim) {
  auto o = std::make_shared<SimRenderOptions>();
  CLI::App* sub = sim.add_subcommand(
      "render", "Render a TUM trajectory through a scene into an RGB-D dataset (TUM layout)");
  sub->add_option("--scene", o->scene, "Scene file (.ply .glb .obj .dae), Z-up metres by default")
      ->required();
  sub->add_option("--trajectory", o->trajectory,
                  "TUM trajectory 't tx ty tz qx qy qz qw', camera-to-world, OpenCV axes")
      ->required();
  sub->add_option("--out,-o", o->out_dir, "Output folder (created if its parent exists)")
      ->required();
  AddSceneFrameOptions(sub, o->frame);
  sub->add_option("--size", o->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  sub->add_option("--fx", o->fx, "Focal length, pixels")
      ->check(InRange(1e-3, 1e7))
      ->capture_default_str();
  sub->add_option("--fy", o->fy, "Focal length y, pixels (default: fx)")->check(InRange(-1e7, 1e7));
  sub->add_option("--cx", o->cx, "Principal point x (default: image centre)")
      ->check(InRange(-1e7, 1e7));
  sub->add_option("--cy", o->cy, "Principal point y (default: image centre)")
      ->check(InRange(-1e7, 1e7));
  sub->add_option("--noise", o->noise, "Kinect-like depth noise: on or off")->capture_default_str();
  sub->add_option("--seed", o->seed, "Noise seed (same seed, same images)")->capture_default_str();
  sub->add_option("--max-range", o->max_range, "Farthest depth returned, metres")
      ->check(InRange(0.01, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  sub->add_flag("--no-color", o->no_color, "Write no colour images");
  sub->add_flag("--no-labels", o->no_labels, "Write no label images");
  sub->add_option("--threads", o->threads, "Worker threads (0: all)")->check(ThreadCount());
  return {sub, [o] { return RunSimRender(*o); }};
}

}  // namespace voxplan::cli
