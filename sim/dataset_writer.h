#pragma once
// Rendering a simulated RGB-D dataset along a trajectory, in the TUM RGB-D layout that
// io/dataset.h OpenDataset reads back:
//   rgb/NNNNNN.png      8-bit RGB
//   depth/NNNNNN.png    16-bit, depth_scale units per metre (5000 like TUM), 0 = no return
//   labels/NNNNNN.png   16-bit instance ids (World::triangle_instance), 0 = none
//   rgb.txt depth.txt labels.txt   "timestamp path" lines
//   groundtruth.txt     "t tx ty tz qx qy qz qw", camera-to-world, OpenCV axes
//   camera.txt          "fx fy cx cy"
// Timestamps are written with 6 decimals in every list, so each depth frame associates exactly
// with its colour image and ground-truth pose.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/status.h"
#include "io/tum_trajectory.h"
#include "sim/raycaster.h"
#include "sim/sensor_noise.h"

namespace voxplan {

struct SimDatasetOptions {
  PinholeCamera camera;
  float max_range_m =
      10.0f;  // farther hits give no return (16-bit depth at scale 5000 ends at 13.1 m)
  bool noise = true;
  KinectNoiseParams noise_params;  // frame i of the trajectory draws noise for frame index i
  double depth_scale = 5000.0;
  bool write_color = true;
  bool write_labels = true;

  Status Validate() const;
};

struct SimDatasetSummary {
  size_t frames = 0;
  std::vector<double> render_ms, noise_ms, write_ms;  // per frame
  double valid_depth_fraction = 0.0;                  // over all frames, after noise
  std::vector<std::string> paths;                     // the list files written
};

// Renders every pose of `trajectory` into `out_dir` (which must exist). Refuses timestamps that
// do not increase, non-finite poses and label ids above 65535, naming the trajectory's source.
// `progress(done)` is called after each frame.
Result<SimDatasetSummary> RenderSimDataset(const MeshRaycaster& raycaster,
                                           const TumTrajectory& trajectory,
                                           const SimDatasetOptions& options,
                                           const std::string& out_dir,
                                           const std::function<void(size_t)>& progress = {});

}  // namespace voxplan
