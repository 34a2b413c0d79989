// Redwood / Open3D: color/ and depth/ (+ rgbd.match), trajectory.log or odometry.log, and a
// camera JSON holding a column-major intrinsic matrix.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/dataset_internal.h"
#include "io/file_util.h"
#include "io/text_file.h"

namespace voxplan::dataset {
namespace {

std::string Rel(const std::string& root, const std::string& path) {
  std::error_code ec;
  const fs::path rel = fs::relative(path, root, ec);
  return ec || rel.empty() ? path : rel.string();
}

Result<std::vector<std::string>> ListFiles(const fs::path& dir,
                                           const std::vector<std::string>& extensions) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return out;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end())
      out.push_back(entry.path().string());
  }
  if (ec) return IoError(dir.string() + ": cannot list (" + ec.message() + ")");
  std::sort(out.begin(), out.end());
  return out;
}

Status ReadRedwoodCamera(const std::string& path, Draft& d) {
  auto json = ReadJson(path);
  if (!json.ok()) return json.status();
  const nlohmann::json& j = *json;
  if (!j.is_object() || !j.contains("intrinsic_matrix") || !j["intrinsic_matrix"].is_array() ||
      j["intrinsic_matrix"].size() != 9)
    return CorruptData(path + ": expected 'intrinsic_matrix' with 9 numbers (column-major)");
  double k[9];
  for (size_t i = 0; i < 9; ++i) {
    const auto& v = j["intrinsic_matrix"][i];
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      return CorruptData(path + ": intrinsic_matrix[" + std::to_string(i) + "] is not a number");
    k[i] = v.get<double>();
  }
  // Column-major: [fx 0 0, 0 fy 0, cx cy 1].
  if (k[0] == 0.0 || k[4] == 0.0 || k[8] != 1.0)
    return CorruptData(path + ": intrinsic_matrix is not a pinhole matrix (column-major)");
  d.intrinsics[0] = float(k[0]);
  d.intrinsics[1] = float(k[4]);
  d.intrinsics[2] = float(k[6]);
  d.intrinsics[3] = float(k[7]);
  d.intrinsics_source = path;
  if (j.contains("width") || j.contains("height")) {
    auto w = JsonNumber(j, "width", path);
    if (!w.ok()) return w.status();
    auto h = JsonNumber(j, "height", path);
    if (!h.ok()) return h.status();
    d.stated_width = int(*w);
    d.stated_height = int(*h);
  }
  return Status::Ok();
}

// Redwood .log: blocks of a `i j n` line and four matrix rows; the first id is the frame index.
Result<std::map<long, Pose3d>> ReadRedwoodLog(const std::string& path) {
  auto file = ReadTextFile(path);
  if (!file.ok()) return file.status();
  std::map<long, Pose3d> poses;
  long prev = -1;
  for (size_t i = 0; i < file->lines.size(); i += 5) {
    const TextLine& meta = file->lines[i];
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, meta, 3, "frame_id frame_id count"));
    double ids[3];
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, meta, 0, 3, ids));
    if (!(ids[0] >= 0.0) || ids[0] != std::floor(ids[0]) || ids[0] > 1e9)
      return LineError(path, meta.number, "frame id " + meta.tokens[0] + " is not an index");
    const long id = long(ids[0]);
    if (id == prev) return LineError(path, meta.number, "duplicate frame id " + meta.tokens[0]);
    if (id < prev)
      return LineError(path, meta.number, "frame id " + meta.tokens[0] + " out of order");
    prev = id;
    auto pose = ParseMatrixRows(*file, i + 1);
    if (!pose.ok()) return pose.status();
    poses.emplace(id, *pose);
  }
  if (poses.empty()) return CorruptData(path + ": no poses");
  return poses;
}

}  // namespace

Result<Draft> ReadRedwood(const fs::path& root) {
  Draft d;
  d.format = DatasetFormat::kRedwood;
  d.root = root.string();
  d.depth_scale = 1000.0;
  SetIntrinsics(d, kPrimeSense);
  d.intrinsics_source = "default (PrimeSense: fx 525 fy 525 cx 319.5 cy 239.5)";

  std::error_code ec;
  auto jsons = ListFiles(root, {".json"});
  if (!jsons.ok()) return jsons.status();
  std::string camera_json;
  for (const std::string& j : *jsons) {  // the first one holding an intrinsic matrix
    auto content = ReadFileToString(j);
    if (content.ok() && content->find("intrinsic_matrix") != std::string::npos) {
      camera_json = j;
      break;
    }
  }
  if (!camera_json.empty()) {
    VOXPLAN_RETURN_IF_ERROR(ReadRedwoodCamera(camera_json, d));
  } else {
    d.default_intrinsics_warning = root.string() +
                                   ": no camera json with 'intrinsic_matrix'; using PrimeSense "
                                   "defaults (fx 525 fy 525 cx 319.5 cy 239.5)";
  }

  const std::string match = (root / "rgbd.match").string();
  if (fs::exists(match, ec)) {
    auto file = ReadTextFile(match);
    if (!file.ok()) return file.status();
    for (const TextLine& line : file->lines) {
      VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 2, "depth_path color_path"));
      const bool depth_first = DepthIsFirst(line.tokens[0], line.tokens[1], true);
      Entry e;
      e.depth_path = (root / line.tokens[depth_first ? 0 : 1]).string();
      e.color_path = (root / line.tokens[depth_first ? 1 : 0]).string();
      e.origin = match + ":" + std::to_string(line.number);
      d.entries.push_back(std::move(e));
    }
    d.empty_message = match + ": no frames listed";
  } else {
    if (!fs::is_directory(root / "depth", ec))
      return NotFound((root / "depth").string() + ": depth folder not found");
    auto depth = ListFiles(root / "depth", {".png"});
    if (!depth.ok()) return depth.status();
    auto color = ListFiles(root / "color", {".jpg", ".jpeg", ".png"});
    if (!color.ok()) return color.status();
    if (!color->empty() && color->size() != depth->size())
      return CorruptData((root / "color").string() + ": " + std::to_string(color->size()) +
                         " images but depth/ has " + std::to_string(depth->size()) +
                         "; add an rgbd.match file to pair them");
    for (size_t i = 0; i < depth->size(); ++i) {
      Entry e;
      e.depth_path = (*depth)[i];
      if (!color->empty()) e.color_path = (*color)[i];
      d.entries.push_back(std::move(e));
    }
    d.empty_message = (root / "depth").string() + ": no PNG images";
  }
  for (size_t i = 0; i < d.entries.size(); ++i)
    d.entries[i].timestamp = double(i) / kNoTimestampRateHz;

  std::string log = (root / "trajectory.log").string();
  if (!fs::exists(log, ec)) log = (root / "odometry.log").string();
  if (fs::exists(log, ec)) {
    auto poses = ReadRedwoodLog(log);
    if (!poses.ok()) return poses.status();
    d.pose_source = log;
    for (size_t i = 0; i < d.entries.size(); ++i) {
      auto it = poses->find(long(i));
      if (it != poses->end()) {
        d.entries[i].T_W_C = it->second;
      } else {
        d.warnings.push_back(log + ": no pose for frame " + std::to_string(i) + " (" +
                             Rel(d.root, d.entries[i].depth_path) + ")");
      }
    }
    if (poses->size() > d.entries.size())
      d.warnings.push_back(log + ": " + std::to_string(poses->size()) + " poses for " +
                           std::to_string(d.entries.size()) + " frames; extra poses ignored");
  } else {
    d.warnings.push_back(root.string() +
                         ": no trajectory.log or odometry.log; frames have no pose");
  }
  return d;
}

}  // namespace voxplan::dataset
