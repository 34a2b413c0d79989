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
  if (k[8] != 1.0)
    return CorruptData(path + ": intrinsic_matrix is not a pinhole matrix (column-major)");
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(k[0], k[4], path, LineOf(path, "intrinsic_matrix")));
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
    auto width = StatedImageSide(*w, path, "width");
    if (!width.ok()) return width.status();
    auto height = StatedImageSide(*h, path, "height");
    if (!height.ok()) return height.status();
    d.stated_width = *width;
    d.stated_height = *height;
  }
  return Status::Ok();
}

// The frame number in a file name: the last run of digits of its stem ("00012.png",
// "depth_12.png": 12), or -1. Poses are associated by it, never by list position, so that a
// missing file or unpadded names ("10.png" sorting before "2.png") cannot shift them.
long FrameNumber(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (begin == end || end - begin > 9) return -1;
  return std::stol(stem.substr(begin, end - begin));
}

// Files sorted by frame number; a file without one, or two with the same, is refused.
Result<std::vector<std::pair<long, std::string>>> Numbered(const std::vector<std::string>& files) {
  std::vector<std::pair<long, std::string>> out;
  for (const std::string& f : files) {
    const long id = FrameNumber(f);
    if (id < 0)
      return CorruptData(f + ": no frame number in the file name (poses are matched by it)");
    out.emplace_back(id, f);
  }
  std::sort(out.begin(), out.end());
  for (size_t i = 1; i < out.size(); ++i)
    if (out[i].first == out[i - 1].first)
      return CorruptData(out[i].second + ": duplicate frame number " +
                         std::to_string(out[i].first) + " (also " + out[i - 1].second + ")");
  return out;
}

// Frames as rgbd.match pairs them, in its order; returns their frame numbers.
Result<std::vector<long>> ListMatched(const fs::path& root, const std::string& match, Draft& d) {
  auto file = ReadTextFile(match);
  if (!file.ok()) return file.status();
  std::vector<long> ids;
  std::map<long, int> seen;  // frame number -> line
  for (const TextLine& line : file->lines) {
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 2, "depth_path color_path"));
    const bool depth_first = DepthIsFirst(line.tokens[0], line.tokens[1], true);
    Entry e;
    e.depth_path = (root / line.tokens[depth_first ? 0 : 1]).string();
    e.color_path = (root / line.tokens[depth_first ? 1 : 0]).string();
    e.origin = match + ":" + std::to_string(line.number);
    const long id = FrameNumber(e.depth_path);
    if (id < 0)
      return LineError(
          match, line.number,
          "no frame number in " + line.tokens[depth_first ? 0 : 1] + " (poses are matched by it)");
    if (auto [it, fresh] = seen.emplace(id, line.number); !fresh)
      return LineError(match, line.number,
                       "frame number " + std::to_string(id) + " already listed at line " +
                           std::to_string(it->second));
    ids.push_back(id);
    d.entries.push_back(std::move(e));
  }
  d.empty_message = match + ": no frames listed";
  return ids;
}

// Frames of depth/ (and color/, paired by frame number), sorted by number.
Result<std::vector<long>> ListFolders(const fs::path& root, Draft& d) {
  std::error_code ec;
  if (!fs::is_directory(root / "depth", ec))
    return NotFound((root / "depth").string() + ": depth folder not found");
  auto depth_files = ListFiles(root / "depth", {".png", ".tif", ".tiff", ".exr"});
  if (!depth_files.ok()) return depth_files.status();
  auto color_files = ListFiles(root / "color", {".jpg", ".jpeg", ".png"});
  if (!color_files.ok()) return color_files.status();
  auto depth = Numbered(*depth_files);
  if (!depth.ok()) return depth.status();
  auto color = Numbered(*color_files);
  if (!color.ok()) return color.status();
  const std::map<long, std::string> color_by_id(color->begin(), color->end());
  std::vector<long> ids;
  size_t paired = 0;
  for (const auto& [id, path] : *depth) {
    Entry e;
    e.depth_path = path;
    if (auto it = color_by_id.find(id); it != color_by_id.end()) {
      e.color_path = it->second;
      ++paired;
    } else if (!color_by_id.empty()) {
      return NotFound(path + ": no colour image with frame number " + std::to_string(id) + " in " +
                      (root / "color").string() + "; add an rgbd.match file to pair them");
    }
    ids.push_back(id);
    d.entries.push_back(std::move(e));
  }
  if (paired < color->size())
    d.warnings.push_back((root / "color").string() + ": " + std::to_string(color->size() - paired) +
                         " of " + std::to_string(color->size()) +
                         " colour images have no depth image of the same number; unused");
  d.empty_message = (root / "depth").string() + ": no depth images (.png, .tif, .tiff, .exr)";
  return ids;
}

// Missing frame numbers between the first and the last frame: how many, and the first.
void WarnNumberingGaps(const fs::path& root, const std::vector<long>& ids, Draft& d) {
  if (ids.size() < 2) return;
  std::vector<long> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  long missing = 0, first_missing = -1;
  for (size_t i = 1; i < sorted.size(); ++i) {
    const long gap = sorted[i] - sorted[i - 1] - 1;
    if (gap > 0 && first_missing < 0) first_missing = sorted[i - 1] + 1;
    missing += gap;
  }
  if (missing > 0)
    d.warnings.push_back(root.string() + ": " + std::to_string(missing) +
                         " frame numbers missing between " + std::to_string(sorted.front()) +
                         " and " + std::to_string(sorted.back()) +
                         " (first: " + std::to_string(first_missing) +
                         "); poses follow the numbers in the file names");
}

struct LoggedPose {
  Eigen::Matrix4d matrix;
  int line = 0;
};

// Redwood .log: blocks of a `i j n` line and four matrix rows; the first id is the frame number.
Result<std::map<long, LoggedPose>> ReadRedwoodLog(const std::string& path) {
  auto file = ReadTextFile(path);
  if (!file.ok()) return file.status();
  std::map<long, LoggedPose> poses;
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
    auto matrix = ParseMatrixRows(*file, i + 1);
    if (!matrix.ok()) return matrix.status();
    poses.emplace(id, LoggedPose{*matrix, i + 1 < file->lines.size() ? file->lines[i + 1].number
                                                                     : meta.number});
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
  auto ids = fs::exists(match, ec) ? ListMatched(root, match, d) : ListFolders(root, d);
  if (!ids.ok()) return ids.status();
  WarnNumberingGaps(root, *ids, d);
  for (size_t i = 0; i < d.entries.size(); ++i)
    d.entries[i].timestamp = double((*ids)[i]) / kNoTimestampRateHz;

  std::string log = (root / "trajectory.log").string();
  if (!fs::exists(log, ec)) log = (root / "odometry.log").string();
  if (!fs::exists(log, ec)) {
    d.warnings.push_back(root.string() +
                         ": no trajectory.log or odometry.log; frames have no pose");
    return d;
  }
  auto poses = ReadRedwoodLog(log);
  if (!poses.ok()) return poses.status();
  d.pose_source = log;
  size_t matched = 0;
  for (size_t i = 0; i < d.entries.size(); ++i) {
    auto it = poses->find((*ids)[i]);
    if (it == poses->end()) {
      if (i - matched < 5)  // name the first few; WarnPoseCount counts them all
        d.warnings.push_back(log + ": no pose for frame " + std::to_string((*ids)[i]) + " (" +
                             Rel(d.root, d.entries[i].depth_path) + ")");
      continue;
    }
    SetMatrixPose(it->second.matrix, log + ":" + std::to_string(it->second.line), d.entries[i], d);
    ++matched;
  }
  WarnPoseCount(log, poses->size(), d.entries.size(), matched, d);
  return d;
}

}  // namespace voxplan::dataset
