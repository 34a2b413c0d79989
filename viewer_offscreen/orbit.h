#pragma once
// Camera poses for offscreen views: look-at and turntable orbits in voxplan's Z-up world, with
// OpenCV camera axes (x right, y down, z forward).
#include <Eigen/Geometry>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"

namespace voxplan {

// n cameras on the circle of `radius_m` around `centre_W` in the plane normal to `up_W`,
// `height_m` above it along `up_W`, each looking at the centre with the image upright. With
// the Z-up default, view k sits at angle 2 pi k / n from +X, counter-clockwise seen from above.
std::vector<Pose3f> OrbitPoses(const Eigen::Vector3f& centre_W, float radius_m, float height_m,
                               int n, const Eigen::Vector3f& up_W = Eigen::Vector3f::UnitZ());

struct OrbitFraming {
  Eigen::Vector3f centre_W = Eigen::Vector3f::Zero();
  float radius_m = 1.0f;     // horizontal distance to the centre
  float height_m = 0.0f;     // above the centre
  float distance_m = 1.0f;   // camera to centre
  float bound_radius_m = 0;  // radius of the sphere around the box
};

// An orbit that keeps the whole box in view of `camera` (its bounding sphere fits the narrower
// field of view) from `elevation_deg` above the horizon.
OrbitFraming FrameBox(const Eigen::AlignedBox3f& box_W, const PinholeCamera& camera,
                      float elevation_deg = 35.0f);

// An orbit framed on the surface itself: `samples_W`, points spread over it by area (SurfaceScene's
// SurfaceSamples). Centred on the box between the `trim` and 1 - `trim` quantiles of the samples
// along each world axis; as near as keeps all but a `trim` share of the samples inside the image
// of `camera` (with FrameBox's margin, at least 5 cm in front) in every one of the n views
// OrbitPoses places about `up_W` at `elevation_deg`. So what is drawn fills the views however
// little of its box it covers (a partly seen room), and a few stray bits far out (noise: under a
// `trim` share of the surface) neither move nor shrink it. bound_radius_m: half the diagonal of
// that box. No samples: FrameBox of an empty box.
OrbitFraming FrameSurface(const std::vector<Eigen::Vector3f>& samples_W,
                          const PinholeCamera& camera, float elevation_deg, int n,
                          const Eigen::Vector3f& up_W = Eigen::Vector3f::UnitZ(),
                          float trim = 0.01f);

// A camera of width x height pixels with a horizontal field of view, square pixels, principal
// point at the image centre.
PinholeCamera CameraFromFov(int width, int height, float horizontal_fov_deg);

}  // namespace voxplan
