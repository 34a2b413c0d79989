#include "io/dataset.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "io/file_util.h"
#include "io/image_io.h"
#include "io/text_file.h"
#include "io/tum_trajectory.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr double kTumMaxAssociationDt = 0.02;  // seconds, as in TUM's associate.py
constexpr double kNoTimestampRateHz = 30.0;    // datasets without timestamps were 30 Hz sensors

// Known cameras for datasets that ship no intrinsics file.
constexpr float kTumFr1[4] = {517.3f, 516.5f, 318.6f, 255.3f};
constexpr float kIclNuim[4] = {481.20f, -480.00f, 319.5f, 239.5f};  // y axis flipped
constexpr float kPrimeSense[4] = {525.f, 525.f, 319.5f, 239.5f};    // Open3D's default
constexpr float kSevenScenes[4] = {585.f, 585.f, 320.f, 240.f};

Result<Pose3d> PoseFromMatrix(const Eigen::Matrix4d& m) {
  VOXPLAN_RETURN_IF_ERROR(ValidatePoseMatrix(m));
  Pose3d pose;
  pose.matrix() = m;
  return pose;
}

// Rows of 4 numbers starting at lines[first]; errors name the first offending line.
Result<Pose3d> ParseMatrixRows(const TextFile& f, size_t first) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    if (first + size_t(r) >= f.lines.size())
      return CorruptData(f.path + ": unexpected end of file inside a 4x4 matrix");
    const TextLine& line = f.lines[first + size_t(r)];
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(f, line, 4, "one matrix row of 4 numbers"));
    double row[4];
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(f, line, 0, 4, row));
    for (int c = 0; c < 4; ++c) m(r, c) = row[c];
  }
  auto pose = PoseFromMatrix(m);
  if (!pose.ok()) return LineError(f.path, f.lines[first].number, pose.status().message());
  return pose;
}

std::string Rel(const std::string& root, const std::string& path) {
  std::error_code ec;
  const fs::path rel = fs::relative(path, root, ec);
  return ec || rel.empty() ? path : rel.string();
}

// ---------------------------------------------------------------------------------------------
// The one Dataset implementation: a list of frames, each a depth path, an optional colour path,
// a timestamp and an optional pose. Readers only build the list.

struct Entry {
  std::string depth_path;
  std::string color_path;  // empty: no colour
  double timestamp = 0.0;
  std::optional<Pose3d> T_W_C;
  std::string origin;  // "file:line" the entry came from, for error messages
};

class ListDataset final : public Dataset {
 public:
  ListDataset(DatasetInfo info, std::vector<Entry> entries)
      : info_(std::move(info)), entries_(std::move(entries)) {}

  const DatasetInfo& info() const override { return info_; }

  Result<Frame> Load(size_t i) const override {
    if (i >= entries_.size())
      return InvalidArgument(info_.root + ": frame " + std::to_string(i) + " out of range (" +
                             std::to_string(entries_.size()) + " frames)");
    const Entry& e = entries_[i];
    Frame frame;
    frame.index = i;
    frame.timestamp = e.timestamp;
    frame.T_W_C = e.T_W_C;
    frame.depth_path = e.depth_path;
    frame.color_path = e.color_path;
    auto depth = ReadDepthPng(e.depth_path, info_.depth_scale);
    if (!depth.ok()) return depth.status();
    frame.depth = std::move(depth).value();
    if (frame.depth.width != info_.camera.width || frame.depth.height != info_.camera.height)
      return CorruptData(e.depth_path + ": depth is " + std::to_string(frame.depth.width) + "x" +
                         std::to_string(frame.depth.height) + " but the sequence is " +
                         std::to_string(info_.camera.width) + "x" +
                         std::to_string(info_.camera.height));
    if (!e.color_path.empty()) {
      auto color = ReadColorImage(e.color_path);
      if (!color.ok()) return color.status();
      frame.color = std::move(color).value();
      if (frame.color.width != frame.depth.width || frame.color.height != frame.depth.height)
        return CorruptData(e.color_path + ": colour is " + std::to_string(frame.color.width) + "x" +
                           std::to_string(frame.color.height) + " but its depth " + e.depth_path +
                           " is " + std::to_string(frame.depth.width) + "x" +
                           std::to_string(frame.depth.height));
    }
    return frame;
  }

 private:
  DatasetInfo info_;
  std::vector<Entry> entries_;
};

// What a reader found, before options and common checks are applied.
struct Draft {
  DatasetFormat format = DatasetFormat::kAuto;
  std::string root;
  std::vector<Entry> entries;
  float intrinsics[4] = {0, 0, 0, 0};  // fx fy cx cy
  std::string intrinsics_source;
  std::string default_intrinsics_warning;  // added only if the caller gave no intrinsics
  double depth_scale = 0.0;
  int stated_width = 0, stated_height = 0;  // from the intrinsics file, when it states a size
  std::string pose_source = "none";
  std::vector<std::string> warnings;
  std::string empty_message;  // why there are no frames, when there are none
};

void SetIntrinsics(Draft& d, const float (&k)[4]) { std::copy(k, k + 4, d.intrinsics); }

Result<std::unique_ptr<Dataset>> Finish(Draft d, const DatasetOptions& options) {
  if (d.entries.empty())
    return CorruptData(d.empty_message.empty() ? d.root + ": no frames found" : d.empty_message);
  DatasetInfo info;
  info.format = d.format;
  info.root = d.root;
  info.num_frames = d.entries.size();
  info.pose_source = d.pose_source;
  info.warnings = std::move(d.warnings);

  info.depth_scale = options.depth_scale ? *options.depth_scale : d.depth_scale;
  if (!(info.depth_scale > 0.0) || !std::isfinite(info.depth_scale))
    return InvalidArgument(d.root + ": depth scale must be positive and finite, got " +
                           NumberText(info.depth_scale));
  if (options.intrinsics) {
    const PinholeCamera& k = *options.intrinsics;
    if (!(k.fx != 0.f && k.fy != 0.f && std::isfinite(k.fx) && std::isfinite(k.fy) &&
          std::isfinite(k.cx) && std::isfinite(k.cy)))
      return InvalidArgument("intrinsics flag: fx and fy must be non-zero and all values finite");
    info.camera = k;
    info.intrinsics_source = "flag";
  } else {
    info.camera.fx = d.intrinsics[0];
    info.camera.fy = d.intrinsics[1];
    info.camera.cx = d.intrinsics[2];
    info.camera.cy = d.intrinsics[3];
    info.intrinsics_source = d.intrinsics_source;
    if (!d.default_intrinsics_warning.empty())
      info.warnings.push_back(d.default_intrinsics_warning);
  }

  // Every listed file must exist; colour is all or nothing.
  info.has_color = std::any_of(d.entries.begin(), d.entries.end(),
                               [](const Entry& e) { return !e.color_path.empty(); });
  std::error_code ec;
  for (const Entry& e : d.entries) {
    const std::string from = e.origin.empty() ? "" : " (listed at " + e.origin + ")";
    if (!fs::is_regular_file(e.depth_path, ec))
      return NotFound(e.depth_path + ": depth image not found" + from);
    if (info.has_color && e.color_path.empty())
      return NotFound(e.depth_path + ": this frame has no colour image but others do" + from);
    if (!e.color_path.empty() && !fs::is_regular_file(e.color_path, ec))
      return NotFound(e.color_path + ": colour image not found" + from);
  }

  // The size comes from the first depth image's header; refuse the wrong kind of PNG early.
  const std::string& first = d.entries.front().depth_path;
  auto header = ReadPngHeader(first);
  if (!header.ok()) return header.status();
  if (header->bit_depth != 16 || header->channels != 1 || header->palette)
    return Unsupported(first + ": depth PNG must be 16-bit single-channel gray, found " +
                       std::to_string(header->bit_depth) + "-bit with " +
                       std::to_string(header->channels) + " channel(s)");
  info.camera.width = header->width;
  info.camera.height = header->height;
  if (d.stated_width > 0 && (d.stated_width != header->width || d.stated_height != header->height))
    return CorruptData(d.intrinsics_source + ": states an image size of " +
                       std::to_string(d.stated_width) + "x" + std::to_string(d.stated_height) +
                       " but " + first + " is " + std::to_string(header->width) + "x" +
                       std::to_string(header->height));
  return std::unique_ptr<Dataset>(new ListDataset(std::move(info), std::move(d.entries)));
}

// Picks the depth path of a pair: the one mentioning "depth" when exactly one does (TUM's
// associate.py writes rgb first, ICL-NUIM writes depth first); otherwise `default_first`.
bool DepthIsFirst(const std::string& a, const std::string& b, bool default_first) {
  const bool da = a.find("depth") != std::string::npos;
  const bool db = b.find("depth") != std::string::npos;
  if (da != db) return da;
  return default_first;
}

// ---------------------------------------------------------------------------------------------
// TUM RGB-D: rgb.txt, depth.txt, groundtruth.txt.

struct Stamped {
  double t = 0.0;
  std::string path;
  int line = 0;
};

Result<std::vector<Stamped>> ReadTumList(const std::string& path) {
  auto file = ReadTextFile(path);
  if (!file.ok()) return file.status();
  std::vector<Stamped> out;
  TimestampChecker checker;
  for (const TextLine& line : file->lines) {
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 2, "timestamp filename"));
    double t = 0.0;
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 1, &t));
    VOXPLAN_RETURN_IF_ERROR(checker.Check(*file, line, t));
    out.push_back({t, line.tokens[1], line.number});
  }
  if (out.empty()) return CorruptData(path + ": no entries");
  return out;
}

struct StampedPose {
  double t = 0.0;
  Eigen::Vector3d translation;
  Eigen::Quaterniond rotation;
};

// Lines `t tx ty tz qx qy qz qw` (io/tum_trajectory.h); near-unit quaternions renormalised
// with a warning.
Result<std::vector<StampedPose>> ReadTumPoses(const std::string& path,
                                              std::vector<std::string>& warnings) {
  Result<TumTrajectory> trajectory = ReadTumTrajectory(path, &warnings);
  if (!trajectory.ok()) return trajectory.status();
  std::vector<StampedPose> out;
  for (size_t i = 0; i < trajectory->T_W_C.size(); ++i) {
    const Pose3d& pose = trajectory->T_W_C[i];
    out.push_back(
        {trajectory->timestamps_s[i], pose.translation(), Eigen::Quaterniond(pose.linear())});
  }
  return out;
}

Pose3d ToPose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  Pose3d pose = Pose3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = t;
  return pose;
}

// Pose at time t between the two bracketing poses (lerp translation, slerp rotation); none when
// t is outside the trajectory.
std::optional<Pose3d> InterpolatePose(const std::vector<StampedPose>& poses, double t) {
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const StampedPose& p, double v) { return p.t < v; });
  if (it == poses.end()) return std::nullopt;
  if (it->t == t) return ToPose(it->translation, it->rotation);
  if (it == poses.begin()) return std::nullopt;
  const StampedPose& a = *(it - 1);
  const StampedPose& b = *it;
  const double alpha = (t - a.t) / (b.t - a.t);
  return ToPose((1.0 - alpha) * a.translation + alpha * b.translation,
                a.rotation.slerp(alpha, b.rotation));
}

Result<Draft> ReadTum(const fs::path& root) {
  Draft d;
  d.format = DatasetFormat::kTum;
  d.root = root.string();
  d.depth_scale = 5000.0;
  SetIntrinsics(d, kTumFr1);
  d.intrinsics_source = "default (TUM Freiburg 1)";
  d.default_intrinsics_warning =
      "TUM folders carry no intrinsics: using Freiburg 1 (fx 517.3 fy 516.5 cx 318.6 cy 255.3); "
      "pass intrinsics for Freiburg 2/3 sequences";

  // Optional camera.txt, one line "fx fy cx cy" (voxplan sim render writes it): overrides the
  // Freiburg 1 default.
  const std::string camera_txt = (root / "camera.txt").string();
  std::error_code camera_ec;
  if (fs::exists(camera_txt, camera_ec)) {
    auto file = ReadTextFile(camera_txt);
    if (!file.ok()) return file.status();
    if (file->lines.size() != 1)
      return CorruptData(camera_txt + ": expected one line 'fx fy cx cy', found " +
                         std::to_string(file->lines.size()));
    const TextLine& line = file->lines[0];
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 4, "fx fy cx cy"));
    double k[4];
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 4, k));
    for (double v : k)
      if (!std::isfinite(v)) return LineError(camera_txt, line.number, "intrinsics must be finite");
    if (k[0] == 0.0 || k[1] == 0.0)
      return LineError(camera_txt, line.number, "fx and fy must be non-zero");
    const float kf[4] = {float(k[0]), float(k[1]), float(k[2]), float(k[3])};
    SetIntrinsics(d, kf);
    d.intrinsics_source = camera_txt;
    d.default_intrinsics_warning.clear();
  }

  const std::string depth_txt = (root / "depth.txt").string();
  const std::string rgb_txt = (root / "rgb.txt").string();
  const std::string gt_txt = (root / "groundtruth.txt").string();
  auto depth = ReadTumList(depth_txt);
  if (!depth.ok()) return depth.status();
  std::error_code ec;
  std::vector<Stamped> rgb;
  const bool have_rgb = fs::exists(rgb_txt, ec);
  if (have_rgb) {
    auto list = ReadTumList(rgb_txt);
    if (!list.ok()) return list.status();
    rgb = std::move(list).value();
  } else {
    d.warnings.push_back(rgb_txt + ": not found; frames have no colour");
  }
  std::vector<StampedPose> gt;
  const bool have_gt = fs::exists(gt_txt, ec);
  if (have_gt) {
    auto poses = ReadTumPoses(gt_txt, d.warnings);
    if (!poses.ok()) return poses.status();
    gt = std::move(poses).value();
    d.pose_source = gt_txt;
  } else {
    d.warnings.push_back(gt_txt + ": not found; frames have no pose");
  }

  size_t no_rgb = 0, no_pose = 0;
  for (const Stamped& s : *depth) {
    const std::string where = depth_txt + ":" + std::to_string(s.line);
    Entry e;
    e.depth_path = (root / s.path).string();
    e.timestamp = s.t;
    e.origin = where;
    if (have_rgb) {
      auto it = std::lower_bound(rgb.begin(), rgb.end(), s.t,
                                 [](const Stamped& r, double v) { return r.t < v; });
      const Stamped* best = nullptr;
      if (it != rgb.end()) best = &*it;
      if (it != rgb.begin() && (!best || s.t - (it - 1)->t <= best->t - s.t)) best = &*(it - 1);
      if (!best || std::abs(best->t - s.t) > kTumMaxAssociationDt) {
        ++no_rgb;
        d.warnings.push_back(where + ": no rgb frame within 0.02 s of depth " + NumberText(s.t) +
                             "; frame dropped");
        continue;
      }
      e.color_path = (root / best->path).string();
    }
    if (have_gt) {
      e.T_W_C = InterpolatePose(gt, s.t);
      if (!e.T_W_C) {
        ++no_pose;
        d.warnings.push_back(where + ": depth " + NumberText(s.t) +
                             " has no bracketing ground-truth poses; frame dropped");
        continue;
      }
    }
    d.entries.push_back(std::move(e));
  }
  d.empty_message = depth_txt + ": no frame associates (" + std::to_string(depth->size()) +
                    " depth frames: " + std::to_string(no_rgb) + " with no frame of " + rgb_txt +
                    " within 0.02 s, " + std::to_string(no_pose) + " without bracketing poses in " +
                    gt_txt + ")";
  return d;
}

// ---------------------------------------------------------------------------------------------
// ICL-NUIM, TUM-compatible release: associations.txt + *.gt.freiburg, ids as timestamps.

Result<std::string> FindOne(const fs::path& dir, const std::string& suffix) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > suffix.size() && name.ends_with(suffix)) found.push_back(entry.path());
  }
  if (ec) return IoError(dir.string() + ": cannot list (" + ec.message() + ")");
  if (found.empty()) return NotFound(dir.string() + ": no *" + suffix + " file");
  std::sort(found.begin(), found.end());
  return found.front();
}

Result<Draft> ReadIclNuim(const fs::path& root) {
  Draft d;
  d.format = DatasetFormat::kIclNuim;
  d.root = root.string();
  d.depth_scale = 5000.0;
  SetIntrinsics(d, kIclNuim);
  d.intrinsics_source = "default (ICL-NUIM: fx 481.2 fy -480 cx 319.5 cy 239.5)";

  const std::string assoc_txt = (root / "associations.txt").string();
  auto assoc = ReadTextFile(assoc_txt);
  if (!assoc.ok()) return assoc.status();
  // Poses are optional: without a *.gt.freiburg file every frame is kept without one.
  std::map<double, Pose3d> poses;
  auto gt_path = FindOne(root, ".gt.freiburg");
  if (!gt_path.ok() && gt_path.status().code() != StatusCode::kNotFound) return gt_path.status();
  if (gt_path.ok()) {
    Result<TumTrajectory> gt = ReadTumTrajectory(*gt_path, &d.warnings, "id tx ty tz qx qy qz qw");
    if (!gt.ok()) return gt.status();
    d.pose_source = *gt_path;
    for (size_t i = 0; i < gt->T_W_C.size(); ++i) poses.emplace(gt->timestamps_s[i], gt->T_W_C[i]);
  } else {
    d.warnings.push_back(root.string() + ": no *.gt.freiburg file; frames have no pose");
  }

  // Frames without a pose (id 1 in traj0) are kept with T_W_C empty, so frame indices match
  // the dataset's ids; callers that need poses skip them.
  TimestampChecker checker;
  for (const TextLine& line : assoc->lines) {
    VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*assoc, line, 4, "id depth_path id rgb_path"));
    double t[2];
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*assoc, line, 0, 1, &t[0]));
    VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*assoc, line, 2, 1, &t[1]));
    const bool depth_first = DepthIsFirst(line.tokens[1], line.tokens[3], true);
    const double t_depth = depth_first ? t[0] : t[1];
    VOXPLAN_RETURN_IF_ERROR(checker.Check(*assoc, line, t_depth));
    Entry e;
    e.depth_path = (root / line.tokens[depth_first ? 1 : 3]).string();
    e.color_path = (root / line.tokens[depth_first ? 3 : 1]).string();
    e.timestamp = t_depth;
    e.origin = assoc_txt + ":" + std::to_string(line.number);
    auto it = poses.find(t_depth);
    if (it != poses.end()) {
      e.T_W_C = it->second;
    } else if (gt_path.ok()) {
      d.warnings.push_back(e.origin + ": frame " + NumberText(t_depth) + " has no pose in " +
                           *gt_path + "; kept with no pose");
    }
    d.entries.push_back(std::move(e));
  }
  d.empty_message = assoc_txt + ": no frames listed";
  return d;
}

// ---------------------------------------------------------------------------------------------
// JSON helpers (Redwood camera file, Replica cam_params.json).

Result<nlohmann::json> ReadJson(const std::string& path) {
  auto content = ReadFileToString(path);
  if (!content.ok()) return content.status();
  std::string_view text = *content;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const size_t byte = std::min<size_t>(e.byte, text.size());
    const int line = 1 + int(std::count(text.begin(), text.begin() + long(byte), '\n'));
    return LineError(path, line, std::string("invalid JSON: ") + e.what());
  }
}

Result<double> JsonNumber(const nlohmann::json& obj, const std::string& key,
                          const std::string& path) {
  if (!obj.is_object() || !obj.contains(key) || !obj[key].is_number())
    return CorruptData(path + ": missing or non-numeric '" + key + "'");
  const double v = obj[key].get<double>();
  if (!std::isfinite(v)) return CorruptData(path + ": '" + key + "' is not finite");
  return v;
}

// ---------------------------------------------------------------------------------------------
// Redwood / Open3D: color/ depth/ (+ rgbd.match), trajectory.log or odometry.log, camera json.

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

// ---------------------------------------------------------------------------------------------
// 7-Scenes and 3DMatch: frame-XXXXXX.{depth.png,color.jpg|color.png,pose.txt}, intrinsics in
// camera-intrinsics.txt (3x3) in the folder or, for 3DMatch, beside the seq-XX folders.

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

// Frame files of one folder, sorted by id.
Result<std::vector<std::pair<long, std::string>>> ListFrames(const fs::path& dir,
                                                             const std::string& prefix,
                                                             const std::string& suffix) {
  std::vector<std::pair<long, std::string>> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const long id = IdFromName(entry.path().filename().string(), prefix, suffix);
    if (id >= 0) out.emplace_back(id, entry.path().string());
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
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (IdFromName(entry.path().filename().string(), "frame-", ".depth.png") >= 0) return true;
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
  if (k[0] == 0.0 || k[4] == 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0)
    return LineError(path, file->lines[0].number, "not a pinhole matrix [fx 0 cx; 0 fy cy; 0 0 1]");
  d.intrinsics[0] = float(k[0]);
  d.intrinsics[1] = float(k[4]);
  d.intrinsics[2] = float(k[2]);
  d.intrinsics[3] = float(k[5]);
  d.intrinsics_source = path;
  return Status::Ok();
}

Status AddFrameFolder(const fs::path& dir, double time_offset, Draft& d, double* end_time) {
  auto depth = ListFrames(dir, "frame-", ".depth.png");
  if (!depth.ok()) return depth.status();
  std::error_code ec;
  size_t missing_poses = 0;
  for (const auto& [id, path] : *depth) {
    Entry e;
    e.depth_path = path;
    // The stem keeps the file's own zero padding.
    const std::string stem = path.substr(0, path.size() - std::string(".depth.png").size());
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
      auto pose = ParseMatrixRows(*file, 0);
      if (!pose.ok()) return pose.status();
      e.T_W_C = *pose;
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
    return NotFound(root.string() + ": no frame-XXXXXX.depth.png files (here or in seq-XX/)");

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

// ---------------------------------------------------------------------------------------------
// Replica, NICE-SLAM layout: cam_params.json, <scene>/results/{depth,frame}NNNNNN, traj.txt.

Result<Draft> ReadReplica(const fs::path& root) {
  Draft d;
  d.format = DatasetFormat::kReplica;
  d.root = root.string();
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
      for (const auto& s : scenes) names += " " + s.filename().string();
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
  d.stated_width = int(v[0]);
  d.stated_height = int(v[1]);
  d.intrinsics[0] = float(v[2]);
  d.intrinsics[1] = float(v[3]);
  d.intrinsics[2] = float(v[4]);
  d.intrinsics[3] = float(v[5]);
  d.depth_scale = v[6];
  d.intrinsics_source = params;

  const fs::path results = scene / "results";
  auto depth = ListFrames(results, "depth", ".png");
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
  d.empty_message = results.string() + ": no depthNNNNNN.png images";

  // traj.txt holds a pose for every frame of the full sequence; line k (0-based) is frame k.
  const std::string traj = (scene / "traj.txt").string();
  if (fs::exists(traj, ec)) {
    auto file = ReadTextFile(traj);
    if (!file.ok()) return file.status();
    std::vector<Pose3d> poses;
    poses.reserve(file->lines.size());
    for (const TextLine& line : file->lines) {
      VOXPLAN_RETURN_IF_ERROR(ExpectTokens(*file, line, 16, "16 numbers, a row-major 4x4"));
      double m[16];
      VOXPLAN_RETURN_IF_ERROR(ParseNumbers(*file, line, 0, 16, m));
      auto pose = PoseFromMatrix(Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m));
      if (!pose.ok()) return LineError(traj, line.number, pose.status().message());
      poses.push_back(*pose);
    }
    d.pose_source = traj;
    for (size_t i = 0; i < d.entries.size(); ++i) {
      const long id = (*depth)[i].first;
      if (size_t(id) < poses.size()) {
        d.entries[i].T_W_C = poses[size_t(id)];
      } else {
        d.warnings.push_back(traj + ": no pose for frame " + std::to_string(id) + " (" +
                             std::to_string(poses.size()) + " poses); kept with no pose");
      }
    }
  } else {
    d.warnings.push_back(traj + ": not found; frames have no pose");
  }
  return d;
}

// ---------------------------------------------------------------------------------------------

Result<DatasetFormat> DetectFormat(const fs::path& root) {
  std::error_code ec;
  const auto has = [&](const fs::path& p) { return fs::exists(p, ec); };
  if (has(root / "associations.txt") &&
      (FindOne(root, ".gt.freiburg").ok() || !has(root / "depth.txt")))
    return DatasetFormat::kIclNuim;
  if (has(root / "depth.txt") || has(root / "rgb.txt")) return DatasetFormat::kTum;
  if (has(root / "cam_params.json") ||
      (has(root.parent_path() / "cam_params.json") && fs::is_directory(root / "results", ec)))
    return DatasetFormat::kReplica;
  if (HasFrames(root))
    return has(root / "camera-intrinsics.txt") || !has(root.parent_path() / "camera-intrinsics.txt")
               ? DatasetFormat::kSevenScenes
               : DatasetFormat::kThreeDMatch;
  if (!SequenceFolders(root).empty())
    return has(root / "camera-intrinsics.txt") ? DatasetFormat::kThreeDMatch
                                               : DatasetFormat::kSevenScenes;
  if (fs::is_directory(root / "depth", ec)) return DatasetFormat::kRedwood;
  return Unsupported(root.string() +
                     ": cannot tell the dataset format (expected TUM depth.txt, ICL-NUIM "
                     "associations.txt + *.gt.freiburg, Redwood depth/, 7-Scenes/3DMatch "
                     "frame-XXXXXX.depth.png, or Replica cam_params.json)");
}

}  // namespace

const char* DatasetFormatName(DatasetFormat f) {
  switch (f) {
    case DatasetFormat::kAuto:
      return "auto";
    case DatasetFormat::kTum:
      return "tum";
    case DatasetFormat::kIclNuim:
      return "icl";
    case DatasetFormat::kRedwood:
      return "redwood";
    case DatasetFormat::kSevenScenes:
      return "7scenes";
    case DatasetFormat::kThreeDMatch:
      return "3dmatch";
    case DatasetFormat::kReplica:
      return "replica";
  }
  return "unknown";
}

Result<DatasetFormat> ParseDatasetFormat(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  static const std::pair<const char*, DatasetFormat> kNames[] = {
      {"auto", DatasetFormat::kAuto},
      {"tum", DatasetFormat::kTum},
      {"icl", DatasetFormat::kIclNuim},
      {"iclnuim", DatasetFormat::kIclNuim},
      {"icl-nuim", DatasetFormat::kIclNuim},
      {"redwood", DatasetFormat::kRedwood},
      {"open3d", DatasetFormat::kRedwood},
      {"7scenes", DatasetFormat::kSevenScenes},
      {"7-scenes", DatasetFormat::kSevenScenes},
      {"3dmatch", DatasetFormat::kThreeDMatch},
      {"replica", DatasetFormat::kReplica}};
  for (const auto& [key, format] : kNames)
    if (n == key) return format;
  return InvalidArgument("unknown dataset format '" + name +
                         "' (expected auto, tum, icl, redwood, 7scenes, 3dmatch or replica)");
}

Result<std::unique_ptr<Dataset>> OpenDataset(const std::string& path,
                                             const DatasetOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(path + ": dataset folder not found");
  if (!fs::is_directory(path, ec)) return InvalidArgument(path + ": not a folder");
  // Trailing slashes would make parent_path() the folder itself.
  fs::path root = fs::path(path).lexically_normal();
  if (root.filename().empty()) root = root.parent_path();

  DatasetFormat format = options.format;
  if (format == DatasetFormat::kAuto) {
    auto detected = DetectFormat(root);
    if (!detected.ok()) return detected.status();
    format = *detected;
  }
  Result<Draft> draft = Status(StatusCode::kInternal, "unreachable");
  switch (format) {
    case DatasetFormat::kTum:
      draft = ReadTum(root);
      break;
    case DatasetFormat::kIclNuim:
      draft = ReadIclNuim(root);
      break;
    case DatasetFormat::kRedwood:
      draft = ReadRedwood(root);
      break;
    case DatasetFormat::kSevenScenes:
    case DatasetFormat::kThreeDMatch:
      draft = ReadFrameFolders(root, format);
      break;
    case DatasetFormat::kReplica:
      draft = ReadReplica(root);
      break;
    case DatasetFormat::kAuto:
      break;
  }
  if (!draft.ok()) return draft.status();
  return Finish(std::move(draft).value(), options);
}

}  // namespace voxplan
