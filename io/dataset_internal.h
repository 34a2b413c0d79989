#pragma once
// What io/dataset*.cpp share: the Draft a reader fills (frames found, intrinsics, warnings) and
// OpenDataset finishes into a Dataset, the known cameras, the readers, and the parsing helpers
// more than one reader uses. Internal to io/dataset*; io/dataset.h is the public face.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/pose.h"
#include "core/status.h"
#include "io/dataset.h"
#include "io/text_file.h"

namespace voxplan::dataset {

namespace fs = std::filesystem;

// Datasets without timestamps were 30 Hz sensors.
inline constexpr double kNoTimestampRateHz = 30.0;

// Known cameras for datasets that ship no intrinsics file.
inline constexpr float kTumFr1[4] = {517.3f, 516.5f, 318.6f, 255.3f};
inline constexpr float kIclNuim[4] = {481.20f, -480.00f, 319.5f, 239.5f};  // y axis flipped
inline constexpr float kPrimeSense[4] = {525.f, 525.f, 319.5f, 239.5f};    // Open3D's default
inline constexpr float kSevenScenes[4] = {585.f, 585.f, 320.f, 240.f};

// One frame as a reader lists it; the Dataset decodes it on Load.
struct Entry {
  std::string depth_path;
  std::string color_path;  // empty: no colour
  double timestamp = 0.0;
  std::optional<Pose3d> T_W_C;
  PoseRejection pose_rejected = PoseRejection::kNone;  // why T_W_C is empty, when listed
  std::string pose_rejected_why;
  std::string origin;  // "file:line" the entry came from, for error messages
};

// Frame i of a listing with what its entry says (index, time, pose or why it has none, file
// names) and no images yet, or the out-of-range error naming the dataset: each Dataset's Load
// then decodes the images its own way.
Result<Frame> FrameFromEntry(const DatasetInfo& info, const std::vector<Entry>& entries, size_t i);

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
  std::string empty_message;   // why there are no frames, when there are none
  size_t bad_poses = 0;        // listed poses rejected as kBadValues; Finish warns once
  std::string first_bad_pose;  // "file:line: reason" of the first
  // The world's up axis where the format states one, and the convention's name; otherwise
  // FinishInfo estimates it from the entries' poses.
  WorldUp stated_up = WorldUp::kUnknown;
  std::string up_convention;
};

inline void SetIntrinsics(Draft& d, const float (&k)[4]) { std::copy(k, k + 4, d.intrinsics); }

// The readers, one per format family; each returns a Draft for OpenDataset to finish.
Result<Draft> ReadTum(const fs::path& root, double max_pose_gap_s);  // io/dataset_tum.cpp
Result<Draft> ReadIclNuim(const fs::path& root);                     // io/dataset_tum.cpp
Result<Draft> ReadRedwood(const fs::path& root);                     // io/dataset_redwood.cpp
// 7-Scenes and 3DMatch; io/dataset_frame_folders.cpp.
Result<Draft> ReadFrameFolders(const fs::path& root, DatasetFormat format);
Result<Draft> ReadReplica(const fs::path& root);  // io/dataset_replica.cpp

// Readers of formats that hold a whole sequence in one file decode their frames from it, so they
// make their own Dataset (over FinishInfo) instead of a Draft of image files.
Result<std::unique_ptr<Dataset>> OpenScanNet(const fs::path& sens_file,
                                             const DatasetOptions& options);  // dataset_scannet.cpp
Result<std::unique_ptr<Dataset>> OpenRosBag(const fs::path& bag_file,
                                            const DatasetOptions& options);  // dataset_rosbag.cpp

// What finishing shares across every reader (io/dataset.cpp): the options applied (depth scale,
// intrinsics) and the warnings gathered, the bad poses counted. The image size is left to the
// caller, which knows where it comes from.
Result<DatasetInfo> FinishInfo(Draft& d, const DatasetOptions& options);

// Timestamp association as TUM's tools do it (io/dataset_tum.cpp), shared with the ROS bag
// reader. Images pair with the nearest image of the other stream within this (seconds, as in
// TUM's associate.py).
inline constexpr double kTumMaxAssociationDt = 0.02;
// The index of the stamp in `sorted_t` nearest to t (the earlier one on a tie), if within
// max_dt.
std::optional<size_t> NearestStamp(const std::vector<double>& sorted_t, double t, double max_dt);
struct StampedPose {
  double t = 0.0;
  Eigen::Vector3d translation;
  Eigen::Quaterniond rotation;
};
Pose3d ToPose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q);
// Pose at time t between the two bracketing poses (sorted by t; lerp translation, slerp
// rotation); none when t is outside the trajectory, or when the bracketing poses are more than
// `max_gap` apart (then *gap_from / *gap_to are set: the motion across a gap is unknown,
// interpolating it invents one).
std::optional<Pose3d> InterpolatePose(const std::vector<StampedPose>& poses, double t,
                                      double max_gap, double* gap_from, double* gap_to);

// Helpers more than one reader uses, in io/dataset.cpp.
// A pose read as a 4x4 matrix at `where` ("file:line"): a rigid one (ValidatePoseMatrix) becomes
// e.T_W_C; any other leaves the frame without a pose, rejected as kBadValues and counted in d,
// so that one bad pose (7-Scenes and 3DMatch write -inf where tracking was lost) costs a frame,
// not the dataset.
void SetMatrixPose(const Eigen::Matrix4d& m, const std::string& where, Entry& e, Draft& d);
// Rows of 4 numbers starting at lines[first]; errors name the first offending line.
Result<Eigen::Matrix4d> ParseMatrixRows(const TextFile& f, size_t first);
// Refuses focal lengths read from `file` that are not positive and finite, as file:line.
// (ICL-NUIM's negative fy is that format's built-in default; camera.txt passes |fy|.)
Status CheckFocalLengths(double fx, double fy, const std::string& file, int line);
// An image side stated in `file` (key `key`), refused unless a whole number in
// [1, bounds::kImageSideMax].
Result<int> StatedImageSide(double v, const std::string& file, const char* key);
// The 1-based line of the first occurrence of `text` in `path` (for JSON values), else 0.
int LineOf(const std::string& path, const std::string& text);
// Warns, naming both numbers, when a pose list holds a different number of poses than there
// are frames; `matched`: frames that got one of them.
void WarnPoseCount(const std::string& pose_file, size_t poses, size_t frames, size_t matched,
                   Draft& d);
// Picks the depth path of a pair: the one mentioning "depth" when exactly one does (TUM's
// associate.py writes rgb first, ICL-NUIM writes depth first); otherwise `default_first`.
bool DepthIsFirst(const std::string& a, const std::string& b, bool default_first);
// JSON (Redwood camera file, Replica cam_params.json); parse errors name the line.
Result<nlohmann::json> ReadJson(const std::string& path);
Result<double> JsonNumber(const nlohmann::json& obj, const std::string& key,
                          const std::string& path);

// The first (sorted) file in `dir` whose name ends in `suffix`; ICL-NUIM's *.gt.freiburg, also
// used by detection. In io/dataset_tum.cpp.
Result<std::string> FindOne(const fs::path& dir, const std::string& suffix);

// The frame-file listing of io/dataset_frame_folders.cpp, also used by Replica and detection.
// Files `prefix<id>suffix` of one folder, for any of `suffixes`, sorted by id; a duplicate id
// (also across suffixes: frame-000001.depth.png beside frame-000001.depth.exr) is an error.
Result<std::vector<std::pair<long, std::string>>> ListFrames(
    const fs::path& dir, const std::string& prefix, const std::vector<std::string>& suffixes);
// The depth file types a folder of frames may hold (io/depth_image.h): `stem` + ".png", ".tif",
// ".tiff", ".exr".
std::vector<std::string> DepthSuffixes(const std::string& stem);
bool HasFrames(const fs::path& dir);  // any frame-XXXXXX.depth.{png,tif,tiff,exr} in dir
std::vector<fs::path> SequenceFolders(const fs::path& root);  // seq*/ folders with frames, sorted

}  // namespace voxplan::dataset
