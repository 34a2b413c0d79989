// The format-neutral part of the dataset readers: format names, detection, OpenDataset's
// dispatch to a reader, the finishing step (overrides, file checks, image size) that turns a
// Draft into the one Dataset implementation, and the parsing helpers several readers share.
#include "io/dataset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "core/bounds.h"
#include "io/dataset_internal.h"
#include "io/depth_image.h"
#include "io/file_util.h"
#include "io/image_io.h"
#include "io/text_file.h"

namespace voxplan::dataset {

void SetMatrixPose(const Eigen::Matrix4d& m, const std::string& where, Entry& e, Draft& d) {
  if (Status s = ValidatePoseMatrix(m); !s.ok()) {
    e.T_W_C.reset();
    e.pose_rejected = PoseRejection::kBadValues;
    e.pose_rejected_why = where + ": " + s.message();
    if (d.bad_poses++ == 0) d.first_bad_pose = e.pose_rejected_why;
    return;
  }
  Pose3d pose;
  pose.matrix() = m;
  e.T_W_C = pose;
}

Result<Eigen::Matrix4d> ParseMatrixRows(const TextFile& f, size_t first) {
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
  return m;
}

Status CheckFocalLengths(double fx, double fy, const std::string& file, int line) {
  for (const auto& [name, v] : {std::pair{"fx", fx}, std::pair{"fy", fy}}) {
    const std::string why =
        std::string(name) + " " + NumberText(v) + " must be positive and finite";
    if (!(v > 0.0) || !std::isfinite(v))
      return line > 0 ? LineError(file, line, why) : CorruptData(file + ": " + why);
  }
  return Status::Ok();
}

Result<int> StatedImageSide(double v, const std::string& file, const char* key) {
  // Checked before the cast: int() of a double out of range is undefined behaviour.
  if (!(v >= 1.0 && v <= double(bounds::kImageSideMax) && v == std::floor(v)))
    return CorruptData(file + ": " + key + " " + NumberText(v) + " must be a whole number of " +
                       "pixels in [1, " + std::to_string(bounds::kImageSideMax) + "]");
  return int(v);
}

int LineOf(const std::string& path, const std::string& text) {
  auto content = ReadFileToString(path);
  if (!content.ok()) return 0;
  const size_t at = content->find(text);
  if (at == std::string::npos) return 0;
  return 1 + int(std::count(content->begin(), content->begin() + long(at), '\n'));
}

void WarnPoseCount(const std::string& pose_file, size_t poses, size_t frames, size_t matched,
                   Draft& d) {
  if (poses == frames && matched == frames) return;
  std::string w =
      pose_file + ": " + std::to_string(poses) + " poses for " + std::to_string(frames) + " frames";
  if (matched < frames) w += "; " + std::to_string(frames - matched) + " frames have no pose";
  if (poses > matched) w += "; " + std::to_string(poses - matched) + " poses match no frame";
  d.warnings.push_back(w);
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
  } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double (1e309)
    return InvalidArgument(path + ": invalid JSON: " + e.what());
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

Result<Frame> FrameFromEntry(const DatasetInfo& info, const std::vector<Entry>& entries, size_t i) {
  if (i >= entries.size())
    return InvalidArgument(info.root + ": frame " + std::to_string(i) + " out of range (" +
                           std::to_string(entries.size()) + " frames)");
  const Entry& e = entries[i];
  Frame frame;
  frame.index = i;
  frame.timestamp = e.timestamp;
  frame.T_W_C = e.T_W_C;
  frame.pose_rejected = e.pose_rejected;
  frame.pose_rejected_why = e.pose_rejected_why;
  frame.depth_path = e.depth_path;
  frame.color_path = e.color_path;
  return frame;
}

namespace {

std::string UnitsText(bool metres) { return metres ? "metres" : "units of 1 / depth scale"; }

// ---------------------------------------------------------------------------------------------
// The one Dataset implementation: a list of frames, each a depth path, an optional colour path,
// a timestamp and an optional pose. Readers only build the list.

class ListDataset final : public Dataset {
 public:
  ListDataset(DatasetInfo info, std::vector<Entry> entries)
      : info_(std::move(info)), entries_(std::move(entries)) {}

  const DatasetInfo& info() const override { return info_; }
  std::vector<std::string> InputFiles() const override;

  Result<Frame> Load(size_t i) const override {
    Result<Frame> listed = FrameFromEntry(info_, entries_, i);
    if (!listed.ok()) return listed.status();
    Frame frame = std::move(listed).value();
    const Entry& e = entries_[i];
    DepthFileHeader header;
    auto depth = ReadDepthImage(e.depth_path, info_.depth_scale, &header);
    if (!depth.ok()) return depth.status();
    if (header.metres != info_.depth_metres)
      return CorruptData(e.depth_path + ": holds " + header.Encoding() + " depth (" +
                         UnitsText(header.metres) + ") but the sequence's first frame holds " +
                         info_.depth_encoding + " depth (" + UnitsText(info_.depth_metres) +
                         "); a sequence cannot mix them");
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

// Association lists, trajectories and camera files sit at the top of the folder; voxplan's own
// outputs (meshes, maps, images) may sit there too without being read.
bool IsTopLevelInput(const fs::path& file) {
  static const char* const kNotRead[] = {".ply", ".obj",   ".glb", ".gltf", ".stl",
                                         ".dae", ".vpmap", ".png", ".jpg",  ".jpeg",
                                         ".tif", ".tiff",  ".exr"};
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return std::none_of(std::begin(kNotRead), std::end(kNotRead),
                      [&](const char* e) { return ext == e; });
}

std::vector<std::string> ListDataset::InputFiles() const {
  std::vector<std::string> files;
  for (const Entry& e : entries_) {
    files.push_back(e.depth_path);
    if (!e.color_path.empty()) files.push_back(e.color_path);
  }
  std::error_code ec;
  for (const std::string& f : {info_.pose_source, info_.intrinsics_source})
    if (fs::is_regular_file(f, ec)) files.push_back(f);
  for (fs::directory_iterator it(info_.root, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && IsTopLevelInput(it->path()))
      files.push_back(it->path().string());
  return files;
}

}  // namespace

Result<DatasetInfo> FinishInfo(Draft& d, const DatasetOptions& options) {
  if (d.entries.empty())
    return CorruptData(d.empty_message.empty() ? d.root + ": no frames found" : d.empty_message);
  DatasetInfo info;
  info.format = d.format;
  info.root = d.root;
  info.num_frames = d.entries.size();
  info.pose_source = d.pose_source;
  info.frames_bad_pose = d.bad_poses;
  info.warnings = std::move(d.warnings);
  if (d.bad_poses > 0)
    info.warnings.push_back(
        std::to_string(d.bad_poses) + (d.bad_poses == 1 ? " pose is" : " poses are") +
        " not a rigid transform, those frames have no pose (first: " + d.first_bad_pose + ")");

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
  info.has_color = std::any_of(d.entries.begin(), d.entries.end(),
                               [](const Entry& e) { return !e.color_path.empty(); });
  if (d.stated_up != WorldUp::kUnknown) {
    info.up = d.stated_up;
    info.up_source = d.up_convention;
  } else {
    WorldUpEstimator votes(info.camera.fy);
    for (const Entry& e : d.entries)
      if (e.T_W_C) votes.Add(e.T_W_C->linear());
    const WorldUpEstimator::Estimate estimate = votes.Result();
    info.up = estimate.up;
    info.up_source = estimate.Describe();
  }
  return info;
}

namespace {

Result<std::unique_ptr<Dataset>> Finish(Draft d, const DatasetOptions& options) {
  Result<DatasetInfo> finished = FinishInfo(d, options);
  if (!finished.ok()) return finished.status();
  DatasetInfo info = std::move(finished).value();

  // Every listed file must exist; colour is all or nothing.
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

  // One type of depth file (by name): PNG, TIFF or EXR. The size and the units come from the
  // first one's header, which also refuses the wrong kind of file early.
  const std::string& first = d.entries.front().depth_path;
  const DepthFileType type = DepthFileTypeOf(first);
  for (const Entry& e : d.entries)
    if (DepthFileTypeOf(e.depth_path) != type)
      return Unsupported(e.depth_path + ": " + DepthFileTypeName(DepthFileTypeOf(e.depth_path)) +
                         " depth in a sequence of " + DepthFileTypeName(type) +
                         " depth images (the first: " + first + ")");
  auto header = ReadDepthHeader(first);
  if (!header.ok()) return header.status();
  info.depth_encoding = header->Encoding();
  info.depth_metres = header->metres;
  if (header->metres && options.depth_scale)
    info.warnings.push_back("depth scale " + NumberText(*options.depth_scale) + " given, but " +
                            first + " holds " + info.depth_encoding +
                            " depth in metres: the scale applies only to 16-bit depth images");
  info.camera.width = header->width;
  info.camera.height = header->height;
  if (d.stated_width > 0 && (d.stated_width != header->width || d.stated_height != header->height))
    return CorruptData(d.intrinsics_source + ": states an image size of " +
                       std::to_string(d.stated_width) + "x" + std::to_string(d.stated_height) +
                       " but " + first + " is " + std::to_string(header->width) + "x" +
                       std::to_string(header->height));
  return std::unique_ptr<Dataset>(new ListDataset(std::move(info), std::move(d.entries)));
}

// ---------------------------------------------------------------------------------------------
// Format detection, from the files present.

// ROS 2 bags (SQLite .db3 or MCAP, in a folder with metadata.yaml) have no C++ reader in
// Debian 12; the refusal says how to get a ROS 1 bag instead.
bool IsRos2BagFile(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".db3" || ext == ".mcap";
}

Status RefuseRos2Bag(const std::string& what) {
  return Unsupported(what +
                     ": a ROS 2 bag, which voxplan cannot read (Debian 12 has no C++ reader for "
                     "it); convert it to a ROS 1 .bag, e.g. `rosbags-convert --src <bag folder> "
                     "--dst out.bag` (pip install rosbags) or with the ROS 2 bag tools, and pass "
                     "the .bag");
}

// A folder `ros2 bag record` wrote: metadata.yaml naming rosbag2, or .db3 / .mcap files.
bool IsRos2BagFolder(const fs::path& root) {
  std::error_code ec;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec))
    if (IsRos2BagFile(it->path().string())) return true;
  const fs::path metadata = root / "metadata.yaml";
  if (!fs::is_regular_file(metadata, ec)) return false;
  Result<std::string> text = ReadFileToString(metadata.string());
  return text.ok() && text->find("rosbag2_bagfile_information") != std::string::npos;
}

Result<DatasetFormat> DetectFormat(const fs::path& root) {
  std::error_code ec;
  const auto has = [&](const fs::path& p) { return fs::exists(p, ec); };
  if (IsRos2BagFolder(root)) return RefuseRos2Bag(root.string());
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
  if (FindOne(root, ".sens").ok()) return DatasetFormat::kScanNet;
  if (FindOne(root, ".bag").ok()) return DatasetFormat::kRosBag;
  return Unsupported(root.string() +
                     ": cannot tell the dataset format (expected TUM depth.txt, ICL-NUIM "
                     "associations.txt + *.gt.freiburg, Redwood depth/, 7-Scenes/3DMatch "
                     "frame-XXXXXX.depth.png, Replica cam_params.json, a ScanNet .sens file or a "
                     "ROS .bag file)");
}

// The format of a dataset that is one file, from its extension.
Result<DatasetFormat> DetectFileFormat(const fs::path& file) {
  const std::string ext = LowerExtension(file.string());
  if (ext == ".sens") return DatasetFormat::kScanNet;
  if (ext == ".bag") return DatasetFormat::kRosBag;
  if (IsRos2BagFile(file.string())) return RefuseRos2Bag(file.string());
  return Unsupported(file.string() +
                     ": not a dataset file (expected a dataset folder, a ScanNet "
                     ".sens file or a ROS 1 .bag file)");
}

// The one `ext` file of a folder (ScanNet's scene0000_00/scene0000_00.sens, a folder with a bag).
Result<fs::path> OneFileWithExtension(const fs::path& root, const std::string& ext) {
  std::vector<std::string> found;
  std::error_code ec;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec))
    if (LowerExtension(it->path().string()) == ext) found.push_back(it->path().string());
  if (ec) return IoError(root.string() + ": cannot list (" + ec.message() + ")");
  if (found.empty()) return NotFound(root.string() + ": no " + ext + " file");
  std::sort(found.begin(), found.end());
  if (found.size() > 1)
    return InvalidArgument(root.string() + ": holds " + std::to_string(found.size()) + " " + ext +
                           " files (" + found[0] + ", " + found[1] +
                           ", ...); name the one to read");
  return fs::path(found.front());
}

// The readers of datasets that are one file.
Result<std::unique_ptr<Dataset>> OpenFileDataset(const fs::path& file, DatasetFormat format,
                                                 const DatasetOptions& options) {
  if (format == DatasetFormat::kRosBag) return OpenRosBag(file, options);
  return OpenScanNet(file, options);
}

}  // namespace
}  // namespace voxplan::dataset

namespace voxplan {

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
    case DatasetFormat::kScanNet:
      return "scannet";
    case DatasetFormat::kRosBag:
      return "rosbag";
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
      {"replica", DatasetFormat::kReplica},
      {"scannet", DatasetFormat::kScanNet},
      {"sens", DatasetFormat::kScanNet},
      {"rosbag", DatasetFormat::kRosBag},
      {"bag", DatasetFormat::kRosBag}};
  for (const auto& [key, format] : kNames)
    if (n == key) return format;
  return InvalidArgument(
      "unknown dataset format '" + name +
      "' (expected auto, tum, icl, redwood, 7scenes, 3dmatch, replica, scannet or rosbag)");
}

Result<std::unique_ptr<Dataset>> OpenDataset(const std::string& path,
                                             const DatasetOptions& options) {
  using namespace dataset;  // fs, DetectFormat, the readers, Finish
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(path + ": dataset folder not found");
  if (!(options.max_pose_gap_s > 0.0) || !std::isfinite(options.max_pose_gap_s))
    return InvalidArgument("max pose gap must be positive and finite, got " +
                           NumberText(options.max_pose_gap_s) + " s");
  // Trailing slashes would make parent_path() the folder itself.
  fs::path root = fs::path(path).lexically_normal();
  if (root.filename().empty()) root = root.parent_path();

  if (!fs::is_directory(path, ec)) {
    if (!fs::is_regular_file(path, ec))
      return InvalidArgument(path + ": neither a folder nor a regular file");
    auto detected = DetectFileFormat(root);
    if (!detected.ok()) return detected.status();
    if (options.format != DatasetFormat::kAuto && options.format != *detected)
      return InvalidArgument(path + ": a " + DatasetFormatName(*detected) + " file, not " +
                             DatasetFormatName(options.format) + " (that format is a folder)");
    return OpenFileDataset(root, *detected, options);
  }

  DatasetFormat format = options.format;
  if (format == DatasetFormat::kAuto) {
    auto detected = DetectFormat(root);
    if (!detected.ok()) return detected.status();
    format = *detected;
  }
  if (format == DatasetFormat::kScanNet || format == DatasetFormat::kRosBag) {
    Result<fs::path> file =
        OneFileWithExtension(root, format == DatasetFormat::kScanNet ? ".sens" : ".bag");
    if (!file.ok()) return file.status();
    return OpenFileDataset(*file, format, options);
  }
  Result<Draft> draft = Status(StatusCode::kInternal, "unreachable");
  switch (format) {
    case DatasetFormat::kTum:
      draft = ReadTum(root, options.max_pose_gap_s);
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
    case DatasetFormat::kScanNet:  // opened above
    case DatasetFormat::kRosBag:
    case DatasetFormat::kAuto:
      break;
  }
  if (!draft.ok()) return draft.status();
  return Finish(std::move(draft).value(), options);
}

bool IsDatasetFile(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".sens" || ext == ".bag" || dataset::IsRos2BagFile(path);
}

}  // namespace voxplan
