// TUM RGB-D (rgb.txt, depth.txt, groundtruth.txt, associated by timestamp) and ICL-NUIM's
// TUM-compatible release (associations.txt + *.gt.freiburg): both read TUM pose files.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/dataset_internal.h"
#include "io/text_file.h"
#include "io/tum_trajectory.h"

namespace voxplan::dataset {
namespace {

// TUM's lists and ground truth.
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

}  // namespace

// ---------------------------------------------------------------------------------------------
// Association in time, shared with the ROS bag reader (io/dataset_internal.h).

Pose3d ToPose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  Pose3d pose = Pose3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = t;
  return pose;
}

std::optional<Pose3d> InterpolatePose(const std::vector<StampedPose>& poses, double t,
                                      double max_gap, double* gap_from, double* gap_to) {
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const StampedPose& p, double v) { return p.t < v; });
  if (it == poses.end()) return std::nullopt;
  if (it->t == t) return ToPose(it->translation, it->rotation);
  if (it == poses.begin()) return std::nullopt;
  const StampedPose& a = *(it - 1);
  const StampedPose& b = *it;
  if (b.t - a.t > max_gap + 1e-9) {  // a 10 Hz trajectory is not refused for rounding
    *gap_from = a.t;
    *gap_to = b.t;
    return std::nullopt;
  }
  const double alpha = (t - a.t) / (b.t - a.t);
  return ToPose((1.0 - alpha) * a.translation + alpha * b.translation,
                a.rotation.slerp(alpha, b.rotation));
}

std::optional<size_t> NearestStamp(const std::vector<double>& sorted_t, double t, double max_dt) {
  auto it = std::lower_bound(sorted_t.begin(), sorted_t.end(), t);
  std::optional<size_t> best;
  if (it != sorted_t.end()) best = size_t(it - sorted_t.begin());
  if (it != sorted_t.begin() && (!best || t - *(it - 1) <= sorted_t[*best] - t))
    best = size_t(it - sorted_t.begin()) - 1;
  if (!best || std::abs(sorted_t[*best] - t) > max_dt) return std::nullopt;
  return best;
}

// ---------------------------------------------------------------------------------------------
// TUM RGB-D: rgb.txt, depth.txt, groundtruth.txt.

Result<Draft> ReadTum(const fs::path& root, double max_pose_gap_s) {
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
    // A negative fy is a y-flipped camera (ICL-NUIM's convention), which `voxplan sim render
    // --fy` writes here; zero, or a negative fx, is no camera.
    VOXPLAN_RETURN_IF_ERROR(CheckFocalLengths(k[0], std::abs(k[1]), camera_txt, line.number));
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

  std::vector<double> rgb_t;
  for (const Stamped& r : rgb) rgb_t.push_back(r.t);
  size_t no_rgb = 0, no_pose = 0, in_gap = 0;
  std::string first_gap;
  for (const Stamped& s : *depth) {
    const std::string where = depth_txt + ":" + std::to_string(s.line);
    Entry e;
    e.depth_path = (root / s.path).string();
    e.timestamp = s.t;
    e.origin = where;
    if (have_rgb) {
      const std::optional<size_t> best = NearestStamp(rgb_t, s.t, kTumMaxAssociationDt);
      if (!best) {
        ++no_rgb;
        d.warnings.push_back(where + ": no rgb frame within 0.02 s of depth " + NumberText(s.t) +
                             "; frame dropped");
        continue;
      }
      e.color_path = (root / rgb[*best].path).string();
    }
    if (have_gt) {
      double gap_from = 0.0, gap_to = 0.0;
      e.T_W_C = InterpolatePose(gt, s.t, max_pose_gap_s, &gap_from, &gap_to);
      if (!e.T_W_C && gap_to > gap_from) {
        // Kept without a pose, so that fusion counts it as skipped for the gap.
        ++in_gap;
        e.pose_rejected = PoseRejection::kGroundTruthGap;
        e.pose_rejected_why =
            where + ": depth " + NumberText(s.t) + " lies in a " + NumberText(gap_to - gap_from) +
            " s gap of " + gt_txt + " (" + NumberText(gap_from) + " to " + NumberText(gap_to) +
            "), longer than the " + NumberText(max_pose_gap_s) + " s allowed for interpolation";
        if (in_gap == 1) first_gap = e.pose_rejected_why;
      } else if (!e.T_W_C) {
        ++no_pose;
        d.warnings.push_back(where + ": depth " + NumberText(s.t) +
                             " has no bracketing ground-truth poses; frame dropped");
        continue;
      }
    }
    d.entries.push_back(std::move(e));
  }
  if (in_gap > 0)
    d.warnings.push_back(std::to_string(in_gap) + " depth frames have no pose: they lie in gaps " +
                         "of the ground truth (first: " + first_gap + ")");
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
  // Its scenes are modelled y-up; the y-flipped camera (fy < 0) has +y up in its upright images.
  d.stated_up = WorldUp::kPlusY;
  d.up_convention = "ICL-NUIM convention (its world is y-up)";

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
  if (gt_path.ok()) {
    const size_t matched = size_t(std::count_if(
        d.entries.begin(), d.entries.end(), [](const Entry& e) { return e.T_W_C.has_value(); }));
    WarnPoseCount(*gt_path, poses.size(), d.entries.size(), matched, d);
  }
  d.empty_message = assoc_txt + ": no frames listed";
  return d;
}

}  // namespace voxplan::dataset
