#pragma once
// What fuzz_sens, fuzz_rosbag and fuzz_ros_messages ask of a dataset file's reader: a refusal
// names the file; an opened dataset describes its images; each of its first frames loads with
// that size (colour, when there is any, brought into the depth camera) and a finite pose, or is
// refused naming the file. Anything else aborts, and libFuzzer keeps the input.
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>

#include "io/dataset.h"

namespace voxplan::fuzz {

inline void CheckNamesFile(const Status& status, const std::string& path) {
  if (status.ok() || status.message().find(path) == std::string::npos) std::abort();
}

inline void CheckDatasetFile(const Result<std::unique_ptr<Dataset>>& dataset,
                             const std::string& path, size_t frames_to_load = 3) {
  if (!dataset.ok()) return CheckNamesFile(dataset.status(), path);
  const DatasetInfo& info = (*dataset)->info();
  if (info.num_frames == 0 || info.camera.width <= 0 || info.camera.height <= 0) std::abort();
  if (!(info.depth_scale > 0.0)) std::abort();
  for (size_t i = 0; i < info.num_frames && i < frames_to_load; ++i) {
    const Result<Frame> frame = (*dataset)->Load(i);
    if (!frame.ok()) {
      CheckNamesFile(frame.status(), path);
      continue;
    }
    const DepthImage& depth = frame->depth;
    if (depth.width != info.camera.width || depth.height != info.camera.height ||
        depth.data.size() != size_t(depth.width) * size_t(depth.height))
      std::abort();
    for (float d : depth.data)
      if (!(d >= 0.f) || !std::isfinite(d)) std::abort();
    const ColorImage& color = frame->color;
    if (!color.data.empty() && (color.width != depth.width || color.height != depth.height))
      std::abort();
    if (info.has_color == color.data.empty()) std::abort();
    if (frame->T_W_C && !frame->T_W_C->matrix().allFinite()) std::abort();
  }
}

}  // namespace voxplan::fuzz
