#include "apps/voxplan/cli_common.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <sstream>

#include "core/bounds.h"
#include "explore/run_outputs.h"
#include "io/file_util.h"
#include "io/mesh_io.h"

namespace voxplan::cli {

namespace fs = std::filesystem;

void AddSceneFrameOptions(CLI::App* sub, SceneFrameOptions& frame) {
  sub->add_option("--up", frame.up, "Scene up axis: z or y (y rotates a Y-up file to Z-up)")
      ->check(CLI::IsMember({"z", "y", "Z", "Y"}))
      ->capture_default_str();
  sub->add_option("--scale", frame.scale, "Scene scale to metres")
      ->check(InRange(1e-6, 1e6))
      ->capture_default_str();
  sub->add_option("--floor-z", frame.floor_z,
                  "Height of the scene's floor (m, after --up and --scale), or auto: the lowest "
                  "large upward-facing surface; the world is moved down by it so its floor lies "
                  "at z = 0")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "auto") return {};
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) ||
                std::abs(v) > kMaxFloorZ_m)
              return "must be auto or a height in metres within +-" +
                     std::to_string(int(kMaxFloorZ_m)) + ", got " + text;
            return {};
          },
          "auto|M"))
      ->capture_default_str();
}

SceneLoadOptions SceneLoad(const SceneFrameOptions& frame) {
  SceneLoadOptions load;
  load.scale = float(frame.scale);
  load.up = (frame.up == "y" || frame.up == "Y") ? UpAxis::kY : UpAxis::kZ;
  // The option's validator has checked the text: "auto" or a bounded number.
  load.detect_floor = frame.floor_z == "auto";
  if (!load.detect_floor) load.floor_z_m = std::strtof(frame.floor_z.c_str(), nullptr);
  return load;
}

void AddSceneOptions(CLI::App* sub, SceneOptions* s, bool required) {
  CLI::Option* scene = sub->add_option(
      "--scene", s->scene, "Ground-truth world mesh; its instance table is <stem>_instances.tsv");
  if (required) scene->required();
  sub->add_option("--instances", s->instances, "Instance table of the world (default: beside it)");
  AddSceneFrameOptions(sub, s->frame);
}

Result<World> LoadScene(const SceneOptions& s) {
  std::error_code ec;
  if (!fs::is_regular_file(s.scene, ec)) return NotFound("scene file not found: " + s.scene);
  if (!s.instances.empty() && !fs::is_regular_file(s.instances, ec))
    return NotFound("instance table not found: " + s.instances);
  SceneLoadOptions load = SceneLoad(s.frame);
  load.instance_table = s.instances;
  Result<World> world = LoadWorld(s.scene, load);
  if (!world.ok()) return world.status().WithContext(s.scene);
  return world;
}

int CheckSceneIsRunWorld(const std::string& run_file, const World& world, bool any_world) {
  const Status s = CheckRunWorld(run_file, world);
  if (s.ok()) return kExitOk;
  if (s.code() == StatusCode::kNotFound) {
    Warn(s.message());
    return kExitOk;
  }
  if (s.code() == StatusCode::kInvalidArgument && any_world) {
    Warn(s.message() + "; scored anyway (--any-world)");
    return kExitOk;
  }
  return Fail(s.code() == StatusCode::kInvalidArgument
                  ? s.message() + "; --any-world scores it anyway"
                  : s.message());
}

void AddDatasetInputOptions(CLI::App* sub, DatasetInput& in, bool with_start) {
  sub->add_option("dataset", in.dataset, "Dataset folder (or ScanNet .sens, ROS .bag file)")
      ->required();
  sub->add_option("--format", in.format, "Dataset format")
      ->check(CLI::IsMember(
          {"auto", "tum", "icl", "redwood", "7scenes", "3dmatch", "replica", "scannet", "rosbag"}))
      ->capture_default_str();
  AddTopicsOption(sub, in.topics);
  sub->add_option("--min-depth", in.min_depth_m, "Ignore depth below this (m)")
      ->check(InRange(0.0, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  sub->add_option("--max-depth", in.max_depth_m, "Ignore depth beyond this (m)")
      ->check(InRange(0.0, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  sub->add_option("--frames", in.frames, "Frames to use (0: all)")
      ->check(FrameCount())
      ->capture_default_str();
  if (with_start) {
    sub->add_option("--start", in.start, "First frame (0-based)")
        ->check(IntInRange(0, bounds::kFramesMax))
        ->capture_default_str();
  }
  sub->add_option("--stride", in.stride, "Use every K-th frame")
      ->check(Stride())
      ->capture_default_str();
}

void AddTopicsOption(CLI::App* sub, std::string& topics) {
  sub->add_option("--topics", topics,
                  "ROS bags: topics to read instead of those found by type, "
                  "depth=T,color=T,info=T,color_info=T,pose=T (PoseStamped or /tf),frame=F");
}

int OpenDatasetInput(const DatasetInput& in, DatasetOptions options, OpenedDataset* out) {
  if (in.max_depth_m <= in.min_depth_m) {
    return Fail("--max-depth must be greater than --min-depth", kExitUsage);
  }
  Result<DatasetFormat> format = ParseDatasetFormat(in.format);
  if (!format.ok()) return Fail(format.status().message(), kExitUsage);
  options.format = *format;
  if (!in.topics.empty()) {
    Result<RosBagTopics> topics = ParseRosBagTopics(in.topics);
    if (!topics.ok()) return Fail(topics.status().message(), kExitUsage);
    options.topics = *topics;
  }
  std::error_code ec;
  if (!std::filesystem::exists(in.dataset, ec)) {
    return Fail("dataset folder not found: " + in.dataset);
  }
  if (!std::filesystem::is_directory(in.dataset, ec) && !IsDatasetFile(in.dataset)) {
    return Fail("dataset is not a folder (nor a .sens or .bag file): " + in.dataset);
  }
  Result<std::unique_ptr<Dataset>> opened = OpenDataset(in.dataset, options);
  if (!opened.ok()) return Fail(MessageNaming(opened.status(), in.dataset));
  const DatasetInfo& info = (*opened)->info();
  for (const std::string& w : info.warnings) Warn(w);
  if (Status s = bounds::CheckIntrinsics(info.camera); !s.ok()) {
    // Named by where the intrinsics came from: the flag or the dataset's camera file.
    const std::string& source =
        info.intrinsics_source.empty() ? in.dataset : info.intrinsics_source;
    return Fail((options.intrinsics ? std::string("--intrinsics") : source) + ": " + s.message(),
                kExitUsage);
  }
  out->indices.clear();
  for (size_t i = size_t(in.start); i < info.num_frames; i += size_t(in.stride)) {
    if (in.frames > 0 && out->indices.size() == size_t(in.frames)) break;
    out->indices.push_back(i);
  }
  if (out->indices.empty()) {
    return Fail("no frames selected: the dataset has " + std::to_string(info.num_frames) +
                    " frames" + (in.start > 0 ? " and --start is " + std::to_string(in.start) : ""),
                kExitUsage);
  }
  out->dataset = std::move(*opened);
  return kExitOk;
}

int RunParsed(const std::vector<Command>& commands) {
  for (const Command& command : commands) {
    if (command.app->parsed()) return command.run();
  }
  return Fail("no subcommand given", kExitUsage);
}

int Fail(const std::string& message, int exit_code) {
  std::cerr << "error: " << message << std::endl;
  return exit_code;
}

void Warn(const std::string& message) { std::cerr << "warning: " << message << std::endl; }

std::string MessageNaming(const Status& status, const std::string& path) {
  return status.Naming(path).message();
}

std::string CheckOutputFile(const std::string& path) {
  if (path.empty()) return "empty output path";
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) return "output path is a folder: " + path;
  // The libraries write a temporary file beside the target, so the folder must exist now;
  // refusing here keeps a long run from failing at the very end.
  const fs::path parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) {
    return "output folder does not exist: " + parent.string() + " (for " + path + ")";
  }
  return {};
}

CLI::Validator OutputFileValidator() {
  return CLI::Validator([](std::string& path) { return CheckOutputFile(path); }, "FILE");
}

CLI::Validator OutputWithExtensionValidator(const std::string& extension, const std::string& what) {
  return CLI::Validator(
      [extension, what](std::string& path) -> std::string {
        if (LowerExtension(path) != extension)
          return what + " must be a " + extension + " file: " + path;
        return CheckOutputFile(path);
      },
      "FILE");
}

CLI::Validator MeshOutputValidator() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        if (!IsSupportedMeshExtension(path)) {
          return "unsupported mesh extension (use .ply, .obj, .glb or .stl): " + path;
        }
        return CheckOutputFile(path);
      },
      "MESH");
}

namespace {

CLI::Validator NumberCheck(bool allow_zero) {
  return CLI::Validator(
      [allow_zero](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v))
          return "not a number: " + text;
        if (v < 0.0 || (!allow_zero && v == 0.0)) {
          return std::string("must be ") + (allow_zero ? "zero or more" : "positive") + ", got " +
                 text;
        }
        return {};
      },
      allow_zero ? "NONNEGATIVE" : "POSITIVE");
}

}  // namespace

CLI::Validator Positive() { return NumberCheck(false); }
CLI::Validator NonNegative() { return NumberCheck(true); }

Result<PinholeCamera> ParseIntrinsics(const std::string& text) {
  std::vector<float> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      size_t used = 0;
      const float v = std::stof(item, &used);
      if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      return InvalidArgument("--intrinsics: not a number: '" + item + "'");
    }
  }
  if (values.size() != 4) return InvalidArgument("--intrinsics wants fx,fy,cx,cy: " + text);
  if (values[0] == 0.f || values[1] == 0.f) {
    return InvalidArgument("--intrinsics: fx and fy must be non-zero: " + text);
  }
  PinholeCamera camera;
  camera.fx = values[0];
  camera.fy = values[1];
  camera.cx = values[2];
  camera.cy = values[3];
  return camera;
}

nlohmann::json CameraJson(const PinholeCamera& c) {
  return {{"width", c.width},           {"height", c.height},         {"fx", ShortestDouble(c.fx)},
          {"fy", ShortestDouble(c.fy)}, {"cx", ShortestDouble(c.cx)}, {"cy", ShortestDouble(c.cy)}};
}

Status WriteJsonFile(const nlohmann::json& json, const std::string& path) {
  const std::string text = json.dump(2) + "\n";
  return WriteFileAtomically(path, text);
}

void PrintJsonLine(const nlohmann::json& json) { std::cout << json.dump() << std::endl; }

void AddMapStats(nlohmann::json& j, const TsdfVolume& volume) {
  j["blocks"] = volume.num_blocks();
  j["voxels"] = volume.num_voxels();
  j["bytes_per_voxel"] = TsdfVolume::BytesPerVoxel();
  j["map_mb"] = Mib(volume.MemoryBytes());
}

void AddMeshStats(nlohmann::json& j, const Mesh& mesh, double mesh_ms) {
  j["mesh_vertices"] = mesh.num_vertices();
  j["mesh_triangles"] = mesh.num_triangles();
  j["mesh_ms"] = RoundTo(mesh_ms, 3);
}

}  // namespace voxplan::cli
