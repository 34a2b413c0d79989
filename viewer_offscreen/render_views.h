#pragma once
// Shaded views of a SurfaceScene: from given poses (one, or a dataset's frames) or a turntable
// framed on its surface (or bounds), all kept in memory so a caller writes files only once every
// view has rendered. Pictures are upright for a y-flipped camera too (UprightCamera).
#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <vector>

#include "core/image.h"
#include "core/pose.h"
#include "core/status.h"
#include "viewer_offscreen/orbit.h"
#include "viewer_offscreen/shading.h"
#include "viewer_offscreen/surface_scene.h"

namespace voxplan {

struct RenderViewsParams {
  int width = 640;
  int height = 480;
  float fov_deg = 60.0f;  // horizontal
  // The views' camera, e.g. a dataset's (its size too; fy may be negative); unset: width x
  // height pixels with the horizontal fov_deg.
  std::optional<PinholeCamera> camera;
  ShadeMode mode = ShadeMode::kShaded;
  // One view from here (its depth colour range from the image); unset: an orbit.
  std::optional<Pose3f> T_W_C;
  // One view from each of these (a dataset's frames), each with its own depth colour range;
  // when not empty, instead of T_W_C and the orbit.
  std::vector<Pose3f> poses;
  int orbit_views = 1;                              // 0 renders one view too
  Eigen::Vector3f up_W = Eigen::Vector3f::UnitZ();  // the orbit's axis; upright pictures' up
  // An orbit is framed on the scene's surface samples (FrameSurface: what is drawn fills the
  // views) where it gives some (a map), else on its bounds (FrameBox: the whole box in view).
  std::optional<float> orbit_radius_m;  // across the up axis; unset: framed
  std::optional<float> orbit_height_m;  // along the up axis; unset: framed
  float orbit_elevation_deg = 35.0f;    // of the framing
  // A framed orbit (no orbit height given) goes below the centre, framed from there, when a small
  // preview of its views sees over 1.5 times the surface from there as from above: a room fused
  // from inside shows its inside from the side its floor (or ceiling) faces.
  bool choose_side = false;

  // Image size within core/bounds.h's, field of view in [1, 179] degrees, 0 to 3600 orbit
  // views, finite orbit numbers and pose; InvalidArgument naming the value otherwise.
  Status Validate() const;
  // Polled before every view: true ends the rendering there with a kCancelled status.
  std::function<bool()> stop_requested;
};

struct RenderedViews {
  Eigen::AlignedBox3f bounds_W;  // the scene's Bounds()
  OrbitFraming framing;          // the orbit (its centre is reported with a pose too)
  bool surface_framed = false;   // the orbit was framed on the scene's surface samples
  std::vector<Pose3f> T_W_C;     // one per image
  std::vector<ColorImage> images;
  PinholeCamera camera;       // what they were rendered with (UprightCamera's)
  bool rows_flipped = false;  // a y-flipped camera rendered with |fy| (UprightCamera)
  double hit_fraction = 0.0;  // mean over the views of the share of pixels on a surface
  bool from_below = false;    // choose_side put the orbit below the centre
};

// The camera that renders `camera`'s views from `T_W_C` upright, up along `up_W`. A camera with a
// negative fy (a y-flipped one, ICL-NUIM's) lists its rows bottom-up: its pictures stay as they
// are when their top rows look up on average over the views (a render at such a dataset's poses
// is then its frames, pixel for pixel), and otherwise (an orbit's poses, built for OpenCV's
// y-down image; a y-flipped dataset of an upright world) it becomes the camera with |fy| and
// the principal point mirrored (cy -> height - 1 - cy), whose image is the y-flipped one with its
// rows flipped. That is one ray cast per view rather than a flip of the shaded picture, so depth,
// vertices, normals, colour and the shading's unprojection stay on one pixel grid. A camera with
// fy > 0 is returned as it is. *flipped, when given, says whether it changed.
PinholeCamera UprightCamera(const PinholeCamera& camera, const std::vector<Pose3f>& T_W_C,
                            const Eigen::Vector3f& up_W, bool* flipped = nullptr);

// Renders and shades every view; fails when the params are invalid, when shading refuses an
// image or on a stop request.
Result<RenderedViews> RenderViews(const SurfaceScene& scene, const RenderViewsParams& params);

}  // namespace voxplan
