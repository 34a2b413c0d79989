#pragma once
// The frame list `voxplan fuse --frame-list` and `voxplan bench` write and
// bench/open3d_fusion.py reads: the integrated frames (image paths, row-major camera-to-world)
// with the camera and the fusion parameters, so that another pipeline runs on identical input.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/status.h"

namespace voxplan {

struct FrameListEntry {
  std::string depth_path, color_path;
  Eigen::Matrix4d T_W_C = Eigen::Matrix4d::Identity();
};

struct FrameListParams {
  PinholeCamera camera;
  double depth_scale = 0.0;  // units per metre
  double voxel_size_m = 0.0, trunc_m = 0.0, min_depth_m = 0.0, max_depth_m = 0.0;
};

// The list as JSON text; indent < 0: one line, else pretty with that indent. Ends in a newline.
std::string FrameListJson(const FrameListParams& params, const std::vector<FrameListEntry>& frames,
                          int indent);
// Pretty JSON, temporary file then rename.
Status WriteFrameList(const std::string& path, const FrameListParams& params,
                      const std::vector<FrameListEntry>& frames);

}  // namespace voxplan
