#pragma once
// RGB-D dataset readers. The format is detected from the folder's files; intrinsics and depth
// scale come from the dataset's own files unless overridden. Every error names the file (and
// line) it came from.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/status.h"

namespace voxplan {

enum class DatasetFormat { kAuto, kTum, kIclNuim, kRedwood, kSevenScenes, kThreeDMatch, kReplica };

const char* DatasetFormatName(DatasetFormat f);  // "tum", "icl", "redwood", "7scenes", ...
Result<DatasetFormat> ParseDatasetFormat(const std::string& name);

struct DatasetOptions {
  DatasetFormat format = DatasetFormat::kAuto;
  std::optional<PinholeCamera> intrinsics;  // overrides fx fy cx cy (size comes from the images)
  std::optional<double> depth_scale;        // depth units per metre
  // Timestamped ground truth (TUM): a frame is not interpolated between two poses further apart
  // than this (seconds); it gets no pose, PoseRejection::kGroundTruthGap.
  double max_pose_gap_s = 0.1;
};

struct DatasetInfo {
  DatasetFormat format = DatasetFormat::kAuto;
  std::string root;
  PinholeCamera camera;      // width/height from the first depth image
  double depth_scale = 0.0;  // units per metre
  size_t num_frames = 0;
  bool has_color = false;
  std::string intrinsics_source;      // the file they came from, "flag" or "default (...)"
  std::string pose_source;            // the file poses came from, or "none"
  std::vector<std::string> warnings;  // one line each, e.g. frames dropped for lack of poses
};

// Why a frame has no pose although its dataset lists one for it (or around it).
enum class PoseRejection {
  kNone,
  kBadValues,       // the listed pose is not a rigid transform (NaN, inf, not a rotation)
  kGroundTruthGap,  // between two ground-truth poses further apart than max_pose_gap_s
};

struct Frame {
  size_t index = 0;        // 0-based position in the sequence
  double timestamp = 0.0;  // seconds (frame id or index / 30 Hz where the dataset has none)
  DepthImage depth;        // metres, 0 = invalid
  ColorImage color;        // empty when the dataset has no colour
  std::optional<Pose3d> T_W_C;
  PoseRejection pose_rejected = PoseRejection::kNone;  // set only when T_W_C is empty
  std::string pose_rejected_why;                       // "file:line: reason"
  std::string depth_path;
  std::string color_path;  // empty when the dataset has no colour
};

class Dataset {
 public:
  virtual ~Dataset() = default;
  virtual const DatasetInfo& info() const = 0;
  // Loads frame i (0 <= i < num_frames): decodes depth (and colour), checks sizes and bit depth.
  virtual Result<Frame> Load(size_t i) const = 0;
  // Every file it reads: each frame's images, the pose and intrinsics files and the lists at
  // the top of its folder (every file there but meshes, maps and images), so that a command can
  // refuse an output that would overwrite one. Empty for datasets without files.
  virtual std::vector<std::string> InputFiles() const { return {}; }
};

Result<std::unique_ptr<Dataset>> OpenDataset(const std::string& path,
                                             const DatasetOptions& options = {});

}  // namespace voxplan
