#pragma once
// RGB-D dataset readers. The format is detected from the folder's files (or, for the formats
// that are one file, its extension); intrinsics and depth scale come from the dataset's own files
// unless overridden. Every error names the file (and line, or frame) it came from.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/status.h"
#include "io/world_up.h"

namespace voxplan {

enum class DatasetFormat {
  kAuto,
  kTum,
  kIclNuim,
  kRedwood,
  kSevenScenes,
  kThreeDMatch,
  kReplica,
  kScanNet,  // one ScanNet .sens file (io/sens_file.h)
  kRosBag,   // one ROS 1 .bag file (io/rosbag_file.h)
};

const char* DatasetFormatName(DatasetFormat f);  // "tum", "icl", "redwood", "7scenes", ...
Result<DatasetFormat> ParseDatasetFormat(const std::string& name);

// Which topics of a ROS bag to read; empty ones are found by their message types.
struct RosBagTopics {
  std::string depth;       // sensor_msgs/Image, 16UC1 / mono16 (mm) or 32FC1 (m)
  std::string color;       // sensor_msgs/Image (rgb8, bgr8, rgba8, bgra8, mono8) or CompressedImage
  std::string info;        // sensor_msgs/CameraInfo of the depth camera
  std::string color_info;  // sensor_msgs/CameraInfo of the colour camera
  std::string pose;        // geometry_msgs/PoseStamped, or /tf (tf2_msgs/TFMessage)
  std::string frame;       // with TF: the camera frame (default: the depth images' frame_id)
};
// "depth=/camera/depth/image,color=/camera/rgb/image_color,info=...,pose=/tf" -> topics;
// unknown keys, empty values and repeated keys are refused.
Result<RosBagTopics> ParseRosBagTopics(const std::string& text);

struct DatasetOptions {
  DatasetFormat format = DatasetFormat::kAuto;
  std::optional<PinholeCamera> intrinsics;  // overrides fx fy cx cy (size comes from the images)
  std::optional<double> depth_scale;        // depth units per metre
  // Timestamped ground truth (TUM): a frame is not interpolated between two poses further apart
  // than this (seconds); it gets no pose, PoseRejection::kGroundTruthGap.
  double max_pose_gap_s = 0.1;
  RosBagTopics topics;  // ROS bags only
};

struct DatasetInfo {
  DatasetFormat format = DatasetFormat::kAuto;
  std::string root;
  PinholeCamera camera;      // width/height from the first depth image
  double depth_scale = 0.0;  // units per metre (of 16-bit depth; float depth files are metres)
  // Datasets of depth image files: what the first one holds (io/depth_image.h), "16-bit PNG",
  // "16-bit TIFF", "32-bit float TIFF", "32-bit float EXR", ...; empty for the formats in one
  // file. depth_metres: float depth in metres, the depth scale does not apply (every frame of
  // the sequence must then hold float depth).
  std::string depth_encoding;
  bool depth_metres = false;
  size_t num_frames = 0;
  bool has_color = false;
  std::string intrinsics_source;      // the file they came from, "flag" or "default (...)"
  std::string pose_source;            // the file poses came from, or "none"
  size_t frames_bad_pose = 0;         // listed poses that are not rigid (-inf), kept without one
  std::vector<std::string> warnings;  // one line each, e.g. frames dropped for lack of poses
  std::string streams;  // ROS bags: the topics read, "depth /camera/depth/image (32FC1), ..."
  // The world's up axis: the format's convention where it states one (ICL-NUIM +y, Replica and
  // ScanNet +z, ROS bags +z by REP 103), else estimated from the listed poses
  // (WorldUpEstimator: TUM, 7-Scenes, 3DMatch, Redwood); unknown when they do not tell.
  WorldUp up = WorldUp::kUnknown;
  std::string up_source;  // "ICL-NUIM convention ...", "estimated from 400 poses (...)", ...
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
  // Loads frame i (0 <= i < num_frames): decodes depth (and colour), checks sizes and bit depth
  // (and that its depth is in the units of the first frame's: all 16-bit or all float).
  // Called from several threads at once, for different frames (FuseDataset decodes ahead).
  virtual Result<Frame> Load(size_t i) const = 0;
  // Every file it reads: each frame's images, the pose and intrinsics files and the lists at
  // the top of its folder (every file there but meshes, maps and images), so that a command can
  // refuse an output that would overwrite one. Empty for datasets without files.
  virtual std::vector<std::string> InputFiles() const { return {}; }
};

// `path` is a dataset folder, or a file holding a whole sequence (ScanNet .sens, ROS 1 .bag); a
// folder holding exactly one such file (ScanNet's scene folders) reads that file. ROS 2 bags
// (.db3, .mcap, or their folder) are refused with how to convert them to a ROS 1 bag.
Result<std::unique_ptr<Dataset>> OpenDataset(const std::string& path,
                                             const DatasetOptions& options = {});

// Whether `path` names a file OpenDataset takes as a dataset, by its extension (.sens, .bag; and
// ROS 2's .db3 and .mcap, which it refuses saying how to convert them), so that a command taking
// a dataset or another file can tell them apart.
bool IsDatasetFile(const std::string& path);

}  // namespace voxplan
