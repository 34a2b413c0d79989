#pragma once
// Which parts of a ground-truth surface a camera trajectory could have observed: a filter for
// MeshEvalParams::ground_truth_filter, so completeness is scored on the observable surface
// (box bottoms, the floor under furniture, walls behind it and rooms never looked at drop out).
#include <Eigen/Core>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"
#include "core/status.h"
#include "eval/eval_mesh.h"
#include "sim/raycaster.h"

namespace voxplan {

struct VisibilityParams {
  // The sensor's depth range, as given to fusion: points outside it count as unseen.
  float min_depth_m = 0.1f;
  float max_depth_m = 10.0f;
  // How far a point may lie off the rendered ground-truth depth and still be the visible surface.
  float depth_tolerance_m = 0.015f;
  // Use every pose_stride-th pose: consecutive frames see nearly the same, and each kept pose
  // costs a render per call of the filter.
  int pose_stride = 1;
};

// A world-frame point is observable when, for at least one kept pose T_W_C, it lies in front of
// the camera within [min_depth_m, max_depth_m], projects inside the image, and its depth lies
// within depth_tolerance_m of the span of the ground-truth depths rendered at the 2x2 pixel
// centres around its projection (a sub-pixel test, so surfaces seen at grazing angles are not
// lost to depth steps between pixels, while points behind an occluder are). The filter renders
// the ground truth with `raycaster` at the kept poses each time it is called, a few at a time,
// so its memory does not grow with the trajectory; `raycaster` must outlive it. Refuses an
// invalid camera, no poses, a non-finite kept pose, pose_stride < 1, and a bad depth range or
// tolerance.
Result<PointSetFilter> ObservableSurfaceFilter(const MeshRaycaster& raycaster,
                                               const PinholeCamera& camera,
                                               const std::vector<Pose3d>& T_W_C,
                                               const VisibilityParams& params = {});

}  // namespace voxplan
