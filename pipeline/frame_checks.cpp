#include "pipeline/frame_checks.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/index.h"

namespace voxplan {

std::string PoseProblem(const Pose3d& T_W_C, double max_translation_m, const VolumeParams& volume,
                        double max_depth_m) {
  const Eigen::Matrix4d& m = T_W_C.matrix();
  if (!m.allFinite()) return "pose has NaN or infinite values";
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double ortho_err = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho_err > 1e-3 || r.determinant() < 0.0) return "pose rotation is not orthonormal";
  const Eigen::Vector3d t = T_W_C.translation();
  std::ostringstream why;
  if (t.norm() > max_translation_m) {
    why << "pose translation " << t.norm() << " m is beyond the " << max_translation_m
        << " m allowed";
    return why.str();
  }
  // Blocks beyond the index range cannot be stored: keep the whole view inside it.
  const double range_m = double(kMaxBlockCoord) * double(kBlockSide) * double(volume.voxel_size_m);
  const double reach_m = max_depth_m + double(volume.trunc_m);
  if (t.cwiseAbs().maxCoeff() + reach_m >= range_m) {
    why << "camera at " << t.cwiseAbs().maxCoeff() << " m sees outside the volume's block index "
        << "range (+-" << range_m << " m at " << volume.voxel_size_m << " m voxels)";
    return why.str();
  }
  return "";
}

std::optional<std::string> DepthScaleCheck::Add(const DepthImage& depth,
                                                const std::string& depth_path) {
  if (judged_ || frames_ >= kFrames) return std::nullopt;
  if (frames_++ == 0) first_path_ = depth_path;
  // Every 7th valid pixel is plenty for a median and keeps the samples small.
  size_t n = 0;
  for (float z : depth.data)
    if (z > 0.f && std::isfinite(z) && n++ % 7 == 0) samples_.push_back(z);
  if (frames_ < kFrames) return std::nullopt;
  return Judge();
}

std::optional<std::string> DepthScaleCheck::Finish() {
  if (judged_ || frames_ == 0) return std::nullopt;
  return Judge();
}

std::optional<std::string> DepthScaleCheck::Judge() {
  judged_ = true;
  if (samples_.empty()) return std::nullopt;
  auto mid = samples_.begin() + long(samples_.size() / 2);
  std::nth_element(samples_.begin(), mid, samples_.end());
  median_m_ = double(*mid);
  std::vector<float>().swap(samples_);
  if (median_m_ >= kMinMedianM && median_m_ <= kMaxMedianM) return std::nullopt;
  std::ostringstream w;
  w << dataset_ << ": the median valid depth of the first " << frames_ << " frame(s) (from "
    << first_path_ << ") is " << median_m_ << " m, outside " << kMinMedianM << " to " << kMaxMedianM
    << " m";
  if (depth_scale_ > 0.0) {
    w << ", with depth scale " << depth_scale_ << " units per metre";
    // The common scales (metres, millimetres, TUM/ICL's 5000, ...): the one putting the median
    // nearest 2 m, a typical indoor distance.
    const double raw = median_m_ * depth_scale_;
    double best_error = 1e300;
    for (double s : {1000.0, 5000.0, 1.0, 100.0, 10000.0}) {
      const double z = raw / s, error = std::abs(std::log(z / 2.0));
      if (z >= kMinMedianM && z <= kMaxMedianM && error < best_error)
        best_error = error, suggested_scale_ = s;
    }
    if (suggested_scale_ > 0.0)
      w << "; the likely scale is " << suggested_scale_ << " (median " << raw / suggested_scale_
        << " m)";
  }
  return w.str() + "; check the depth scale";
}

}  // namespace voxplan
