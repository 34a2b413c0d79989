#include "sim/dataset_writer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/parallel.h"
#include "core/stopwatch.h"
#include "io/file_util.h"
#include "io/image_io.h"

namespace voxplan {

namespace {

namespace fs = std::filesystem;

std::string FrameName(size_t i) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu.png", i);
  return name;
}

std::string Stamp(double t) {
  char s[64];
  std::snprintf(s, sizeof(s), "%.6f", t);
  return s;
}

Status WriteLabelPng16(const std::string& path, const LabelImage& labels) {
  std::vector<uint16_t> samples(labels.data.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    if (labels.data[i] > 0xffffu)
      return InvalidArgument(path + ": instance id " + std::to_string(labels.data[i]) +
                             " does not fit a 16-bit label image");
    samples[i] = uint16_t(labels.data[i]);
  }
  return WritePngRaw(path, labels.width, labels.height, 1, 16, samples.data());
}

}  // namespace

Status SimDatasetOptions::Validate() const {
  if (!camera.Valid()) return InvalidArgument("SimDatasetOptions: invalid camera");
  if (!(depth_scale > 0.0)) return InvalidArgument("SimDatasetOptions: depth_scale must be > 0");
  if (!(max_range_m > 0.f) || double(max_range_m) * depth_scale > 65535.0)
    return InvalidArgument("SimDatasetOptions: max_range_m must be in (0, " +
                           std::to_string(65535.0 / depth_scale) + "] for 16-bit depth");
  if (noise) return noise_params.Validate();
  return Status::Ok();
}

Result<SimDatasetSummary> RenderSimDataset(const MeshRaycaster& raycaster,
                                           const TumTrajectory& trajectory,
                                           const SimDatasetOptions& options,
                                           const std::string& out_dir,
                                           const std::function<void(size_t)>& progress) {
  VOXPLAN_RETURN_IF_ERROR(options.Validate());
  const std::string source = trajectory.source.empty() ? "trajectory" : trajectory.source;
  if (trajectory.T_W_C.empty() || trajectory.T_W_C.size() != trajectory.timestamps_s.size())
    return InvalidArgument(source + ": no poses, or timestamps and poses differ in number");
  for (size_t i = 0; i < trajectory.T_W_C.size(); ++i) {
    const std::string where = source + ": pose " + std::to_string(i + 1);
    if (!std::isfinite(trajectory.timestamps_s[i]) || !trajectory.T_W_C[i].matrix().allFinite())
      return InvalidArgument(where + " is not finite");
    // Timestamps are written with 6 decimals: they must stay distinct and increasing there.
    if (i > 0 && !(trajectory.timestamps_s[i] >= trajectory.timestamps_s[i - 1] + 1e-6))
      return InvalidArgument(where + ": timestamp " + Stamp(trajectory.timestamps_s[i]) +
                             " does not increase (previous " +
                             Stamp(trajectory.timestamps_s[i - 1]) + ")");
  }
  std::error_code ec;
  const fs::path root(out_dir);
  if (!fs::is_directory(root, ec)) return NotFound(out_dir + ": output folder does not exist");
  for (const char* sub : {"rgb", "depth", "labels"}) {
    if ((std::string(sub) == "rgb" && !options.write_color) ||
        (std::string(sub) == "labels" && !options.write_labels))
      continue;
    fs::create_directories(root / sub, ec);
    if (ec) return IoError((root / sub).string() + ": cannot create folder: " + ec.message());
  }

  RenderParams render;
  render.max_range_m = options.max_range_m;
  render.color = options.write_color;
  render.labels = options.write_labels;
  render.normals = options.noise && options.noise_params.grazing_dropout;
  SimDatasetSummary summary;
  std::string rgb_txt = "# color images\n# timestamp filename\n";
  std::string depth_txt = "# depth maps (" + std::to_string(options.depth_scale) +
                          " units per metre)\n# timestamp filename\n";
  std::string labels_txt = "# instance label images (16-bit ids, 0 = none)\n# timestamp filename\n";
  size_t valid = 0, total = 0;
  for (size_t i = 0; i < trajectory.T_W_C.size(); ++i) {
    Stopwatch clock;
    const Pose3f T_W_C = trajectory.T_W_C[i].cast<float>();
    RenderOutput out = raycaster.Render(options.camera, T_W_C, render);
    summary.render_ms.push_back(clock.ElapsedMs());

    clock.Restart();
    if (options.noise) {
      auto noisy =
          ApplyKinectNoise(out.depth, out.normals_C, options.camera, options.noise_params, i);
      if (!noisy.ok()) return noisy.status();
      out.depth = std::move(noisy).value();
    }
    for (float z : out.depth.data) valid += z > 0.f;
    total += out.depth.data.size();
    summary.noise_ms.push_back(clock.ElapsedMs());

    // The three images of a frame are encoded in parallel (PNG compression dominates).
    clock.Restart();
    const std::string name = FrameName(i);
    Status status[3];
    ParallelFor(3, 1, [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) {
        if (k == 0)
          status[0] =
              WriteDepthPng16((root / "depth" / name).string(), out.depth, options.depth_scale);
        else if (k == 1 && options.write_color)
          status[1] = WriteColorPng((root / "rgb" / name).string(), out.color);
        else if (k == 2 && options.write_labels)
          status[2] = WriteLabelPng16((root / "labels" / name).string(), out.labels);
      }
    });
    for (const Status& s : status) VOXPLAN_RETURN_IF_ERROR(s);
    summary.write_ms.push_back(clock.ElapsedMs());

    const std::string t = Stamp(trajectory.timestamps_s[i]);
    depth_txt += t + " depth/" + name + "\n";
    rgb_txt += t + " rgb/" + name + "\n";
    labels_txt += t + " labels/" + name + "\n";
    ++summary.frames;
    if (progress) progress(i + 1);
  }

  // Ground truth with the same 6-decimal timestamps as the lists.
  std::vector<double> stamps;
  for (double t : trajectory.timestamps_s) stamps.push_back(std::stod(Stamp(t)));
  const std::string gt = (root / "groundtruth.txt").string();
  VOXPLAN_RETURN_IF_ERROR(WriteTumTrajectory(gt, stamps, trajectory.T_W_C));
  char camera[160];
  std::snprintf(camera, sizeof(camera), "# fx fy cx cy\n%.9g %.9g %.9g %.9g\n", options.camera.fx,
                options.camera.fy, options.camera.cx, options.camera.cy);
  const std::string camera_path = (root / "camera.txt").string();
  const std::string depth_path = (root / "depth.txt").string();
  VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(camera_path, camera));
  VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(depth_path, depth_txt));
  summary.paths = {depth_path};
  if (options.write_color) {
    const std::string p = (root / "rgb.txt").string();
    VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(p, rgb_txt));
    summary.paths.push_back(p);
  }
  if (options.write_labels) {
    const std::string p = (root / "labels.txt").string();
    VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(p, labels_txt));
    summary.paths.push_back(p);
  }
  summary.paths.push_back(gt);
  summary.paths.push_back(camera_path);
  summary.valid_depth_fraction = total ? double(valid) / double(total) : 0.0;
  return summary;
}

}  // namespace voxplan
