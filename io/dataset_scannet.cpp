// ScanNet: one .sens file holds the whole scan (io/sens_file.h). Frames are decoded from it on
// Load; poses ScanNet marks lost (-inf) leave their frame without a pose, counted; colour is
// brought into the depth camera as the header's intrinsics and extrinsics say.
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "io/color_registration.h"
#include "io/dataset_internal.h"
#include "io/sens_file.h"

namespace voxplan::dataset {
namespace {

PinholeCamera CameraOf(const Eigen::Matrix4f& k, int width, int height) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = k(0, 0);
  c.fy = k(1, 1);
  c.cx = k(0, 2);
  c.cy = k(1, 2);
  return c;
}

class SensDataset final : public Dataset {
 public:
  SensDataset(DatasetInfo info, std::vector<Entry> entries, SensIndex index)
      : info_(std::move(info)), entries_(std::move(entries)), index_(std::move(index)) {
    const SensHeader& h = index_.header;
    color_camera_ = CameraOf(h.color_intrinsic, h.color_width, h.color_height);
    // Extrinsics map each camera into a common frame: colour <- common <- depth.
    T_color_depth_.matrix() =
        (h.color_extrinsic.cast<double>().inverse() * h.depth_extrinsic.cast<double>());
  }

  const DatasetInfo& info() const override { return info_; }
  std::vector<std::string> InputFiles() const override { return {index_.path}; }

  Result<Frame> Load(size_t i) const override {
    Result<Frame> listed = FrameFromEntry(info_, entries_, i);
    if (!listed.ok()) return listed.status();
    Frame frame = std::move(listed).value();
    Result<DepthImage> depth = ReadSensDepth(index_, i, info_.depth_scale);
    if (!depth.ok()) return depth.status();
    frame.depth = std::move(depth).value();
    if (info_.has_color) {
      Result<ColorImage> color = ReadSensColor(index_, i);
      if (!color.ok()) return color.status();
      // The colour camera keeps the file's intrinsics even when --intrinsics overrides depth's.
      frame.color =
          RegisterColorToDepth(*color, color_camera_, frame.depth, info_.camera, T_color_depth_);
    }
    return frame;
  }

 private:
  DatasetInfo info_;
  std::vector<Entry> entries_;
  SensIndex index_;
  PinholeCamera color_camera_;
  Pose3d T_color_depth_ = Pose3d::Identity();
};

}  // namespace

Result<std::unique_ptr<Dataset>> OpenScanNet(const fs::path& sens_file,
                                             const DatasetOptions& options) {
  const std::string path = sens_file.string();
  Result<SensIndex> index = ReadSensIndex(path);
  if (!index.ok()) return index.status();
  const SensHeader& h = index->header;

  Draft d;
  d.format = DatasetFormat::kScanNet;
  d.root = path;
  d.depth_scale = double(h.depth_shift);
  const float k[4] = {h.depth_intrinsic(0, 0), h.depth_intrinsic(1, 1), h.depth_intrinsic(0, 2),
                      h.depth_intrinsic(1, 2)};
  SetIntrinsics(d, k);
  d.intrinsics_source = path + ": depth intrinsics";
  d.pose_source = path;
  // ScanNet aligns every scan and its camera poses to a frame with z up and the floor in the xy
  // plane (Dai et al., CVPR 2017; the axisAlignment matrices then only turn about z).
  d.stated_up = WorldUp::kPlusZ;
  d.up_convention = "ScanNet convention (scans are aligned z-up)";

  // Colour is all or nothing: a file whose header has a colour size must carry it every frame.
  const bool has_color = h.color_width > 0 && index->frames.front().color_bytes > 0;
  // Timestamps are microseconds; a file whose depth timestamps do not increase is timed at 30 Hz.
  bool timed = true;
  for (size_t i = 0; i < index->frames.size(); ++i) {
    const SensFrameRecord& f = index->frames[i];
    if (has_color != (f.color_bytes > 0))
      return CorruptData(SensFrameName(*index, i) +
                         (has_color ? ": has no colour image" : ": has a colour image") +
                         " but frame 0 " + (has_color ? "has one" : "has none"));
    if (f.depth_timestamp_us == 0 ||
        (i > 0 && f.depth_timestamp_us <= index->frames[i - 1].depth_timestamp_us))
      timed = false;
  }
  if (!timed)
    d.warnings.push_back(path + ": depth timestamps are missing or do not increase; frames are " +
                         "timed at 30 Hz");

  for (size_t i = 0; i < index->frames.size(); ++i) {
    const SensFrameRecord& f = index->frames[i];
    Entry e;
    e.depth_path = SensFrameName(*index, i);
    if (has_color) e.color_path = e.depth_path;
    e.timestamp = timed ? double(f.depth_timestamp_us) * 1e-6 : double(i) / kNoTimestampRateHz;
    e.origin = e.depth_path;
    SetMatrixPose(f.camera_to_world.cast<double>(), e.origin, e, d);
    d.entries.push_back(std::move(e));
  }
  Result<DatasetInfo> finished = FinishInfo(d, options);
  if (!finished.ok()) return finished.status();
  DatasetInfo info = std::move(finished).value();
  info.camera.width = h.depth_width;
  info.camera.height = h.depth_height;
  return std::unique_ptr<Dataset>(
      new SensDataset(std::move(info), std::move(d.entries), std::move(index).value()));
}

}  // namespace voxplan::dataset
