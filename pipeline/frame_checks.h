#pragma once
// What fusion checks in a dataset's frames before trusting them: that a pose is a rigid
// transform in a sane range inside the volume's block index range (outside it, blocks are
// silently dropped), and that the depth scale puts the first frames' depth where RGB-D sensors
// see (a wrong one otherwise ends in an empty mesh without a hint).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/image.h"
#include "core/pose.h"
#include "core/volume.h"

namespace voxplan {

// Why the pose must not be integrated, or "" when it may: non-finite values, a rotation that
// is not orthonormal, a translation beyond `max_translation_m`, or a camera whose view
// (`max_depth_m` plus the truncation around it) leaves the block index range of `volume`.
std::string PoseProblem(const Pose3d& T_W_C, double max_translation_m, const VolumeParams& volume,
                        double max_depth_m);

// Median valid depth of the first frames with valid depth, judged against [0.2, 15] m.
class DepthScaleCheck {
 public:
  static constexpr int kFrames = 3;
  static constexpr double kMinMedianM = 0.2, kMaxMedianM = 15.0;
  // `depth_scale`: the units per metre in use (0: unknown, no scale is suggested then).
  DepthScaleCheck(std::string dataset, double depth_scale)
      : dataset_(std::move(dataset)), depth_scale_(depth_scale) {}
  // A frame with valid depth, until kFrames have been added. Returns the warning, once, when
  // the median is out of range after the kFrames-th frame.
  std::optional<std::string> Add(const DepthImage& depth, const std::string& depth_path);
  // After the last frame: the warning for fewer than kFrames frames, if not given yet.
  std::optional<std::string> Finish();
  double median_m() const { return median_m_; }                // 0 until judged
  double suggested_scale() const { return suggested_scale_; }  // 0: none (in range, unknown)

 private:
  std::optional<std::string> Judge();
  std::string dataset_, first_path_;
  double depth_scale_ = 0.0;
  int frames_ = 0;
  bool judged_ = false;
  std::vector<float> samples_;
  double median_m_ = 0.0, suggested_scale_ = 0.0;
};

}  // namespace voxplan
