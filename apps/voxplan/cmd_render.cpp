// voxplan render: map or mesh -> shaded PNG views (a pose, or a turntable around the centre).
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "core/raycast.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "sim/raycaster.h"
#include "viewer_offscreen/orbit.h"
#include "viewer_offscreen/shading.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

constexpr int kMaxImageSide = 8192;
constexpr float kOrbitElevationDeg = 35.0f;

struct RenderOptions {
  std::string input;
  std::string pose;  // "tx ty tz qx qy qz qw", T_W_C
  int orbit = 0;     // 0: one view (the first orbit view) unless --pose
  std::string mode = "shaded";
  std::string size = "640x480";
  double fov_deg = 60.0;
  std::string out_dir;
  double min_weight = 0.5;
  std::string up = "z";       // the scene's up axis, for orbits (ICL-NUIM maps are Y-up)
  double orbit_radius_m = 0;  // 0: from the bounds
  double orbit_height_m = 0;
  bool orbit_height_set = false;
  double near_m = 0.0;          // maps: rays start this far out (cuts away near walls); 0: 0.01 m
  std::string kernel = "auto";  // maps: "scalar" marches the scalar reference (same images)
  int threads = 0;
};

Result<std::pair<int, int>> ParseSize(const std::string& text) {
  int width = 0, height = 0;
  char x = 0, extra = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || (x != 'x' && x != 'X') || (in >> extra)) {
    return InvalidArgument("--size wants WxH, e.g. 640x480: " + text);
  }
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide) {
    return InvalidArgument("--size: width and height must be 1.." + std::to_string(kMaxImageSide) +
                           ": " + text);
  }
  return std::pair(width, height);
}

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

bool IsMapPath(const std::string& path) { return fs::path(path).extension() == ".vpmap"; }

// What to render: a map (TSDF ray casting) or a mesh (Embree); both yield SurfaceImages.
class Scene {
 public:
  virtual ~Scene() = default;
  virtual Eigen::AlignedBox3f Bounds() const = 0;
  virtual SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const = 0;
};

class MapScene : public Scene {
 public:
  MapScene(TsdfVolume volume, float min_weight, float near_m, bool simd)
      : volume_(std::move(volume)) {
    params_.min_weight = min_weight;
    params_.simd = simd;
    params_.min_depth_m = near_m > 0.0f ? near_m : 0.01f;
    // From outside a room the walls' backs come first: look through them at the inside.
    params_.stop_at_back_faces = false;
    const float block_m = volume_.block_size_m();
    volume_.ForEachBlock([&](BlockIndex b, const TsdfBlock&) {
      const Eigen::Vector3f lo = BlockOrigin(b, block_m);
      bounds_.extend(lo);
      bounds_.extend(Eigen::Vector3f(lo + Eigen::Vector3f::Constant(block_m)));
    });
  }
  Eigen::AlignedBox3f Bounds() const override { return bounds_; }
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override {
    RaycastParams params = params_;
    // Far enough to reach every allocated block from this camera.
    float farthest_m = 0.0f;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3f corner =
          bounds_.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c));
      farthest_m = std::max(farthest_m, (corner - T_W_C.translation()).norm());
    }
    params.max_depth_m = std::max(farthest_m, params.min_depth_m + 0.1f);
    RaycastImages r = Raycast(volume_, camera, T_W_C, params);
    SurfaceImages s;
    s.depth = std::move(r.depth);
    s.vertex_W = std::move(r.vertex_W);
    s.normal_W = std::move(r.normal_W);
    // A map fused without colour stores black: shade it neutral grey instead.
    bool any_colour = false;
    for (size_t i = 0; i < s.depth.data.size() && !any_colour; ++i)
      any_colour = s.depth.data[i] > 0.0f && (r.color.data[i] & 0xffffffu) != 0;
    if (any_colour) s.color = std::move(r.color);
    return s;
  }

 private:
  TsdfVolume volume_;
  RaycastParams params_;
  Eigen::AlignedBox3f bounds_;
};

class MeshScene : public Scene {
 public:
  MeshScene(const Mesh& mesh, std::unique_ptr<MeshRaycaster> raycaster)
      : raycaster_(std::move(raycaster)), has_colour_(!mesh.colors.empty()) {
    for (const Eigen::Vector3f& p : mesh.positions) bounds_.extend(p);
  }
  Eigen::AlignedBox3f Bounds() const override { return bounds_; }
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override {
    RenderOutput r = raycaster_->Render(camera, T_W_C);
    SurfaceImages s;
    s.depth = std::move(r.depth);  // vertices and normals follow from depth in Shade
    if (has_colour_) s.color = std::move(r.color);
    return s;
  }

 private:
  std::unique_ptr<MeshRaycaster> raycaster_;
  bool has_colour_;
  Eigen::AlignedBox3f bounds_;
};

Result<std::unique_ptr<Scene>> LoadScene(const std::string& path, float min_weight, float near_m,
                                         bool simd) {
  if (IsMapPath(path)) {
    Result<TsdfVolume> volume = LoadMap(path);
    if (!volume.ok()) return volume.status();
    if (volume->num_blocks() == 0) return InvalidArgument("the map holds no blocks: " + path);
    return std::unique_ptr<Scene>(new MapScene(std::move(*volume), min_weight, near_m, simd));
  }
  Result<Mesh> mesh = ReadMesh(path);
  if (!mesh.ok()) return mesh.status();
  Result<std::unique_ptr<MeshRaycaster>> raycaster = MeshRaycaster::Create(*mesh);
  if (!raycaster.ok()) return raycaster.status();
  return std::unique_ptr<Scene>(new MeshScene(*mesh, std::move(*raycaster)));
}

nlohmann::json Json(const Eigen::Vector3f& v) {
  return {RoundTo(v.x(), 6), RoundTo(v.y(), 6), RoundTo(v.z(), 6)};
}

// Removes what this run wrote, so a failed run leaves nothing behind.
void CleanUp(const std::vector<std::string>& written, const fs::path& created_dir) {
  std::error_code ec;
  for (const std::string& path : written) fs::remove(path, ec);
  if (!created_dir.empty()) fs::remove_all(created_dir, ec);
}

int RunRender(const RenderOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.input, ec)) return Fail("input file not found: " + o.input);
  const auto [width, height] = *ParseSize(o.size);  // checked by the validator
  const ShadeMode mode = *ParseShadeMode(o.mode);
  ThreadLimit thread_limit(o.threads);

  const Stopwatch load_clock;
  Result<std::unique_ptr<Scene>> loaded =
      LoadScene(o.input, float(o.min_weight), float(o.near_m), o.kernel != "scalar");
  if (!loaded.ok()) return Fail(MessageNaming(loaded.status(), o.input));
  const Scene& scene = **loaded;
  const double load_ms = load_clock.ElapsedMs();

  const PinholeCamera camera = CameraFromFov(width, height, float(o.fov_deg));
  const Eigen::AlignedBox3f bounds = scene.Bounds();
  OrbitFraming framing = FrameBox(bounds, camera, kOrbitElevationDeg);
  if (o.orbit_radius_m > 0.0) framing.radius_m = float(o.orbit_radius_m);
  if (o.orbit_height_set) framing.height_m = float(o.orbit_height_m);
  framing.distance_m = std::hypot(framing.radius_m, framing.height_m);
  const Eigen::Vector3f up_W =
      o.up == "y" ? Eigen::Vector3f::UnitY() : Eigen::Vector3f(Eigen::Vector3f::UnitZ());
  std::vector<Pose3f> poses;
  ShadeParams shade;
  if (!o.pose.empty()) {
    poses.push_back(*ParsePose(o.pose));  // checked by the validator; depth range: per image
  } else {
    poses = OrbitPoses(framing.centre_W, framing.radius_m, framing.height_m, std::max(o.orbit, 1),
                       up_W);
    // One depth range for the whole turntable, so colours mean the same depth in every view.
    shade.depth_near_m = std::max(0.0f, framing.distance_m - framing.bound_radius_m);
    shade.depth_far_m = framing.distance_m + framing.bound_radius_m;
  }

  const Stopwatch render_clock;
  std::vector<ColorImage> images;
  double hit_fraction_sum = 0.0;
  for (const Pose3f& T_W_C : poses) {
    const SurfaceImages surface = scene.Render(camera, T_W_C);
    const size_t hits = size_t(std::count_if(surface.depth.data.begin(), surface.depth.data.end(),
                                             [](float z) { return z > 0.0f; }));
    hit_fraction_sum += double(hits) / double(surface.depth.data.size());
    Result<ColorImage> image = Shade(surface, camera, T_W_C, mode, shade);
    if (!image.ok()) return Fail("shading failed: " + image.status().message());
    images.push_back(std::move(*image));
  }
  const double render_ms = render_clock.ElapsedMs();

  // Only now touch the disk: every image is in memory.
  const fs::path dir(o.out_dir);
  fs::path created_dir;
  if (!fs::is_directory(dir, ec)) {
    // Remember the topmost folder this run creates, to remove it again on failure.
    fs::path top = dir;
    while (top.has_parent_path() && !top.parent_path().empty() &&
           !fs::exists(top.parent_path(), ec))
      top = top.parent_path();
    if (!fs::create_directories(dir, ec) || ec) {
      return Fail("cannot create output folder " + o.out_dir + ": " + ec.message());
    }
    created_dir = top;
  }
  const Stopwatch write_clock;
  std::vector<std::string> written;
  for (size_t k = 0; k < images.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "render_%03zu.png", k);
    const std::string path = (dir / name).string();
    if (Status s = WriteColorPng(path, images[k]); !s.ok()) {
      CleanUp(written, created_dir);
      return Fail(MessageNaming(s, path));
    }
    written.push_back(path);
  }
  const double write_ms = write_clock.ElapsedMs();

  for (const std::string& path : written) std::cerr << "wrote " << path << "\n";
  std::cerr << "render: " << written.size() << " " << ShadeModeName(mode) << " view(s) of "
            << o.input << " at " << width << "x" << height << " in " << RoundTo(render_ms, 1)
            << " ms\n";
  nlohmann::json j;
  j["command"] = "render";
  j["input"] = o.input;
  j["input_kind"] = IsMapPath(o.input) ? "map" : "mesh";
  j["mode"] = ShadeModeName(mode);
  j["width"] = width;
  j["height"] = height;
  j["fov_deg"] = o.fov_deg;
  j["views"] = written.size();
  j["out"] = o.out_dir;
  j["files"] = written;
  j["bounds_min"] = Json(bounds.min());
  j["bounds_max"] = Json(bounds.max());
  j["centre"] = Json(framing.centre_W);
  if (o.pose.empty()) {
    j["orbit_radius_m"] = RoundTo(framing.radius_m, 6);
    j["orbit_height_m"] = RoundTo(framing.height_m, 6);
  }
  j["hit_fraction"] = RoundTo(hit_fraction_sum / double(poses.size()), 6);
  j["threads"] = MaxThreads();
  j["load_ms"] = RoundTo(load_ms, 3);
  j["render_ms"] = RoundTo(render_ms, 3);
  j["write_ms"] = RoundTo(write_ms, 3);
  PrintJsonLine(j);
  return kExitOk;
}

CLI::Validator SizeValidator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        Result<std::pair<int, int>> size = ParseSize(text);
        return size.ok() ? std::string() : size.status().message();
      },
      "WxH");
}

CLI::Validator PoseValidator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        Result<Pose3f> pose = ParsePose(text);
        return pose.ok() ? std::string() : pose.status().message();
      },
      "\"tx ty tz qx qy qz qw\"");
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
          ->check(PoseValidator());
  CLI::Option* orbit =
      sub->add_option("--orbit", o->orbit, "Turntable of N views around the centre")
          ->check(CLI::Range(1, 3600));
  pose->excludes(orbit);
  sub->add_option("--mode", o->mode, "Shading")
      ->check(CLI::IsMember({"shaded", "normals", "colour", "color", "depth"}))
      ->capture_default_str();
  sub->add_option("--size", o->size, "Image size WxH")
      ->check(SizeValidator())
      ->capture_default_str();
  sub->add_option("--fov-deg", o->fov_deg, "Horizontal field of view (degrees)")
      ->check(CLI::Range(1.0, 179.0))
      ->capture_default_str();
  sub->add_option("--out,-o", o->out_dir, "Output folder (created if missing)")
      ->required()
      ->check(OutputDirValidator());
  sub->add_option("--min-weight", o->min_weight, "Maps: voxels with less weight are unobserved")
      ->check(NonNegative())
      ->capture_default_str();
  sub->add_option("--up", o->up, "Up axis of the scene, for orbits")
      ->check(CLI::IsMember({"y", "z"}))
      ->capture_default_str();
  sub->add_option("--orbit-radius", o->orbit_radius_m,
                  "Orbit: distance from the centre across the up axis (m; default from bounds)")
      ->check(Positive());
  sub->add_option_function<double>(
         "--orbit-height",
         [o](double h) {
           o->orbit_height_m = h;
           o->orbit_height_set = true;
         },
         "Orbit: height above the centre along the up axis (m; default from bounds)")
      ->check(CLI::Range(-1e6, 1e6));
  sub->add_option("--near", o->near_m,
                  "Maps: start rays this far from the camera (m), to cut away near walls")
      ->check(NonNegative());
  sub->add_option("--kernel", o->kernel, "Maps: ray-casting march (scalar: the reference)")
      ->check(CLI::IsMember({"auto", "scalar"}))
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(NonNegative())
      ->capture_default_str();
  return {sub, [o] { return RunRender(*o); }};
}

}  // namespace voxplan::cli
