#pragma once
// Colour brought into the depth camera, for datasets whose colour camera is not the depth
// camera (ScanNet's 1296x968 colour beside 640x480 depth, RealSense colour streams): each depth
// pixel's point is projected into the colour image and sampled there.
#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"

namespace voxplan {

// Colour at every pixel of `depth_camera`: the pixel's point (at its depth; at unit depth where
// the depth is invalid, which is exact when the cameras share a centre) moved by T_color_depth
// into the colour camera, projected and sampled bilinearly. Pixels that land outside the colour
// image, or behind it, are black. Equal cameras and an identity transform copy the image.
ColorImage RegisterColorToDepth(const ColorImage& color, const PinholeCamera& color_camera,
                                const DepthImage& depth, const PinholeCamera& depth_camera,
                                const Pose3d& T_color_depth);

// Whether RegisterColorToDepth would only copy: same size, same intrinsics, identity transform.
bool SameCamera(const PinholeCamera& color_camera, const PinholeCamera& depth_camera,
                const Pose3d& T_color_depth);

}  // namespace voxplan
