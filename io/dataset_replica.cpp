// Replica in the NICE-SLAM layout: cam_params.json, <scene>/results/{depth,frame}NNNNNN and
// traj.txt (one row-major 4x4 pose per line, line k is frame k).
#include <Eigen/Core>
#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/dataset_internal.h"
#include "io/text_file.h"

namespace voxplan::dataset {

Result<Draft> ReadReplica(const fs::path& root) {
  Draft d;
  d.format = DatasetFormat::kReplica;
  d.root = root.string();
  // The poses are in the frame of Replica's meshes, which are z-up (shared data README).
  d.stated_up = WorldUp::kPlusZ;
  d.up_convention = "Replica convention (its meshes and poses are z-up)";
  std::error_code ec;

  fs::path scene;
  std::string params;
  if (fs::is_directory(root / "results", ec)) {  // pointed at the scene folder
    scene = root;
    params = fs::exists(root / "cam_params.json", ec)
                 ? (root / "cam_params.json").string()
                 : (root.parent_path() / "cam_params.json").string();
  } else {
    params = (root / "cam_params.json").string();
    std::vector<fs::path> scenes;
    for (const auto& entry : fs::directory_iterator(root, ec))
      if (entry.is_directory(ec) && fs::is_directory(entry.path() / "results", ec))
        scenes.push_back(entry.path());
    std::sort(scenes.begin(), scenes.end());
    if (scenes.empty())
      return NotFound(root.string() + ": no scene folder with results/ (e.g. office0/results)");
    if (scenes.size() > 1) {
      std::string names;
      for (const auto& s : scenes) {
        names += ' ';
        names += s.filename().string();
      }
      return InvalidArgument(root.string() + ": several Replica scenes (" + names.substr(1) +
                             "); open one of them");
    }
    scene = scenes.front();
  }

  auto json = ReadJson(params);
  if (!json.ok()) return json.status();
  if (!json->is_object() || !json->contains("camera") || !(*json)["camera"].is_object())
    return CorruptData(params + ": expected an object 'camera' with w h fx fy cx cy scale");
  const nlohmann::json& cam = (*json)["camera"];
  double v[7];
  const char* keys[7] = {"w", "h", "fx", "fy", "cx", "cy", "scale"};
  for (int i = 0; i < 7; ++i) {
    auto x = JsonNumber(cam, keys[i], params);
    if (!x.ok()) return x.status();
    v[i] = *x;
  }
  auto width = StatedImageSide(v[0], params, "w");
  if (!width.ok()) return width.status();
  auto height = StatedImageSide(v[1], params, "h");
  if (!height.ok()) return height.status();
  d.stated_width = *width;
  d.stated_height = *height;
  d.intrinsics[0] = float(v[2]);
  d.intrinsics[1] = float(v[3]);
  d.intrinsics[2] = float(v[4]);
  d.intrinsics[3] = float(v[5]);
  d.depth_scale = v[6];
  d.intrinsics_source = params;
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(v[2], 1.0, params, LineOf(params, "\"fx\"")));
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(1.0, v[3], params, LineOf(params, "\"fy\"")));

  const fs::path results = scene / "results";
  auto depth = ListFrames(results, "depth", DepthSuffixes(""));
  if (!depth.ok()) return depth.status();
  for (const auto& [id, path] : *depth) {
    Entry e;
    e.depth_path = path;
    const std::string digits = fs::path(path).stem().string().substr(5);
    for (const char* ext : {".jpg", ".png"}) {
      const fs::path color = results / ("frame" + digits + ext);
      if (fs::exists(color, ec)) e.color_path = color.string();
    }
    e.timestamp = double(id) / kNoTimestampRateHz;
    d.entries.push_back(std::move(e));
  }
  d.empty_message = results.string() + ": no depthNNNNNN.png (.tif, .tiff, .exr) images";

  // traj.txt holds a pose for every frame of the full sequence; line k (0-based) is frame k.
  const std::string traj = (scene / "traj.txt").string();
  if (fs::exists(traj, ec)) {
    auto file = ReadTextFile(traj);
    if (!file.ok()) return file.status();
    std::vector<std::pair<Eigen::Matrix4d, int>> poses;  // matrix, line
    poses.reserve(file->lines.size());
    for (const TextLine& line : file->lines) {
      VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 16, "16 numbers, a row-major 4x4"));
      double m[16];
      VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 16, m));
      poses.push_back(
          {Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m), line.number});
    }
    d.pose_source = traj;
    size_t matched = 0;
    for (size_t i = 0; i < d.entries.size(); ++i) {
      const long id = (*depth)[i].first;
      if (size_t(id) < poses.size()) {
        const auto& [matrix, number] = poses[size_t(id)];
        SetMatrixPose(matrix, traj + ":" + std::to_string(number), d.entries[i], d);
        ++matched;
      } else {
        d.warnings.push_back(traj + ": no pose for frame " + std::to_string(id) + " (" +
                             std::to_string(poses.size()) + " poses); kept with no pose");
      }
    }
    WarnPoseCount(traj, poses.size(), d.entries.size(), matched, d);
  } else {
    d.warnings.push_back(traj + ": not found; frames have no pose");
  }
  return d;
}

}  // namespace voxplan::dataset
