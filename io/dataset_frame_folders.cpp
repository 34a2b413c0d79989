// 7-Scenes and 3DMatch: frame-XXXXXX.{depth.png,color.jpg|color.png,pose.txt}, intrinsics in
// camera-intrinsics.txt (3x3) in the folder or, for 3DMatch, beside the seq-XX folders.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "io/dataset_internal.h"
#include "io/text_file.h"

namespace voxplan::dataset {
namespace {

// The number in `prefix<digits>suffix`, or -1.
long IdFromName(const std::string& name, const std::string& prefix, const std::string& suffix) {
  if (name.size() <= prefix.size() + suffix.size() || !name.starts_with(prefix) ||
      !name.ends_with(suffix))
    return -1;
  const std::string digits =
      name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return -1;
  return std::stol(digits);
}

}  // namespace

std::vector<std::string> DepthSuffixes(const std::string& stem) {
  return {stem + ".png", stem + ".tif", stem + ".tiff", stem + ".exr"};
}

// Frame files of one folder, sorted by id.
Result<std::vector<std::pair<long, std::string>>> ListFrames(
    const fs::path& dir, const std::string& prefix, const std::vector<std::string>& suffixes) {
  std::vector<std::pair<long, std::string>> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    for (const std::string& suffix : suffixes) {
      const long id = IdFromName(entry.path().filename().string(), prefix, suffix);
      if (id >= 0) out.emplace_back(id, entry.path().string());
    }
  }
  if (ec) return IoError(dir.string() + ": cannot list (" + ec.message() + ")");
  std::sort(out.begin(), out.end());
  for (size_t i = 1; i < out.size(); ++i)
    if (out[i].first == out[i - 1].first)
      return CorruptData(out[i].second + ": duplicate frame id " + std::to_string(out[i].first) +
                         " (also " + out[i - 1].second + ")");
  return out;
}

bool HasFrames(const fs::path& dir) {
  std::error_code ec;
  const std::vector<std::string> suffixes = DepthSuffixes(".depth");
  for (const auto& entry : fs::directory_iterator(dir, ec))
    for (const std::string& suffix : suffixes)
      if (IdFromName(entry.path().filename().string(), "frame-", suffix) >= 0) return true;
  return false;
}

std::vector<fs::path> SequenceFolders(const fs::path& root) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(root, ec))
    if (entry.is_directory(ec) && entry.path().filename().string().starts_with("seq") &&
        HasFrames(entry.path()))
      out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

Status ReadCameraIntrinsicsTxt(const std::string& path, Draft& d) {
  auto file = ReadTextFile(path);
  if (!file.ok()) return file.status();
  if (file->lines.size() != 3)
    return CorruptData(path + ": expected a 3x3 matrix (3 lines), found " +
                       std::to_string(file->lines.size()) + " lines");
  double k[9];
  for (size_t r = 0; r < 3; ++r) {
    const TextLine& line = file->lines[r];
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 3, "one matrix row of 3 numbers"));
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 3, k + 3 * r));
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(k[3 * r + size_t(c)]))
        return LineError(path, line.number, "non-finite value");
  }
  if (k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0)
    return LineError(path, file->lines[2].number, "not a pinhole matrix [fx 0 cx; 0 fy cy; 0 0 1]");
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(k[0], 1.0, path, file->lines[0].number));
  VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(1.0, k[4], path, file->lines[1].number));
  d.intrinsics[0] = float(k[0]);
  d.intrinsics[1] = float(k[4]);
  d.intrinsics[2] = float(k[2]);
  d.intrinsics[3] = float(k[5]);
  d.intrinsics_source = path;
  return Status::Ok();
}

Status AddFrameFolder(const fs::path& dir, double time_offset, Draft& d, double* end_time) {
  auto depth = ListFrames(dir, "frame-", DepthSuffixes(".depth"));
  if (!depth.ok()) return depth.status();
  std::error_code ec;
  size_t missing_poses = 0;
  for (const auto& [id, path] : *depth) {
    Entry e;
    e.depth_path = path;
    // The stem keeps the file's own zero padding.
    const std::string stem = path.substr(0, path.rfind(".depth."));
    for (const char* ext : {".color.png", ".color.jpg"})
      if (fs::exists(stem + ext, ec)) e.color_path = stem + ext;
    e.timestamp = time_offset + double(id) / kNoTimestampRateHz;
    const std::string pose_path = stem + ".pose.txt";
    if (fs::exists(pose_path, ec)) {
      auto file = ReadTextFile(pose_path);
      if (!file.ok()) return file.status();
      if (file->lines.size() != 4)
        return CorruptData(pose_path + ": expected a 4x4 matrix (4 lines), found " +
                           std::to_string(file->lines.size()));
      auto matrix = ParseMatrixRows(*file, 0);
      if (!matrix.ok()) return matrix.status();
      SetMatrixPose(*matrix, pose_path + ":" + std::to_string(file->lines[0].number), e, d);
    } else {
      ++missing_poses;
      d.warnings.push_back(pose_path + ": not found; frame kept with no pose");
    }
    *end_time = e.timestamp;
    d.entries.push_back(std::move(e));
  }
  if (missing_poses < depth->size()) d.pose_source = dir.string() + "/frame-*.pose.txt";
  return Status::Ok();
}

}  // namespace

Result<Draft> ReadFrameFolders(const fs::path& root, DatasetFormat format) {
  Draft d;
  d.format = format;
  d.root = root.string();
  d.depth_scale = 1000.0;
  std::error_code ec;

  std::vector<fs::path> folders;
  std::string intrinsics;
  if (HasFrames(root)) {
    folders.push_back(root);
    // 3DMatch keeps camera-intrinsics.txt beside seq-XX/; accept pointing at the sequence.
    if (fs::exists(root / "camera-intrinsics.txt", ec))
      intrinsics = (root / "camera-intrinsics.txt").string();
    else if (fs::exists(root.parent_path() / "camera-intrinsics.txt", ec))
      intrinsics = (root.parent_path() / "camera-intrinsics.txt").string();
  } else {
    folders = SequenceFolders(root);
    if (fs::exists(root / "camera-intrinsics.txt", ec))
      intrinsics = (root / "camera-intrinsics.txt").string();
  }
  if (folders.empty())
    return NotFound(root.string() +
                    ": no frame-XXXXXX.depth.png (.tif, .tiff, .exr) files (here or in seq-XX/)");

  if (!intrinsics.empty()) {
    VOXPLAN_RETURN_IF_ERROR(ReadCameraIntrinsicsTxt(intrinsics, d));
  } else {
    SetIntrinsics(d, kSevenScenes);
    d.intrinsics_source = "default (7-Scenes Kinect: fx 585 fy 585 cx 320 cy 240)";
    d.default_intrinsics_warning = root.string() +
                                   ": no camera-intrinsics.txt; using the 7-Scenes Kinect "
                                   "defaults (fx 585 fy 585 cx 320 cy 240)";
  }
  // Sequences are concatenated; each starts one frame period after the previous one ends.
  double offset = 0.0;
  for (const fs::path& folder : folders) {
    double end_time = offset;
    VOXPLAN_RETURN_IF_ERROR(AddFrameFolder(folder, offset, d, &end_time));
    offset = end_time + 1.0 / kNoTimestampRateHz;
  }
  if (folders.size() > 1) d.pose_source = root.string() + "/seq*/frame-*.pose.txt";
  return d;
}

}  // namespace voxplan::dataset
