// RenderViews: poses (given or an orbit framed on the surface or the bounds), one depth range
// per turntable, render, count hits, shade.
#include "viewer_offscreen/render_views.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/bounds.h"
#include "core/camera.h"

namespace voxplan {

Status RenderViewsParams::Validate() const {
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize("render size", width, height));
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("field of view", fov_deg, 1.0, 179.0, "degrees"));
  // 0 renders one view, as 1 does (the CLI's default when neither --orbit nor --pose is given).
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("orbit views", orbit_views, 0, 3600));
  VOXPLAN_RETURN_IF_ERROR(
      bounds::CheckRange("orbit elevation", orbit_elevation_deg, -90.0, 90.0, "degrees"));
  if (orbit_radius_m)
    VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("orbit radius", *orbit_radius_m, 1e-3, 1e4, "m"));
  if (orbit_height_m)
    VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("orbit height", *orbit_height_m, -1e4, 1e4, "m"));
  if (!up_W.allFinite() || up_W.norm() < 1e-6f)
    return InvalidArgument("up axis must be a finite non-zero vector");
  if (T_W_C && !T_W_C->matrix().allFinite())
    return InvalidArgument("render pose has NaN or infinite values");
  for (size_t k = 0; k < poses.size(); ++k)
    if (!poses[k].matrix().allFinite())
      return InvalidArgument("render pose " + std::to_string(k) + " has NaN or infinite values");
  if (camera) VOXPLAN_RETURN_IF_ERROR(bounds::CheckIntrinsics(*camera));
  return Status::Ok();
}

namespace {

// `camera` at a tenth of its size (at least 16 x 12 pixels), for previews.
PinholeCamera SmallCamera(const PinholeCamera& camera) {
  PinholeCamera small = camera;
  small.width = std::max(16, camera.width / 10);
  small.height = std::max(12, camera.height / 10);
  const float sx = float(small.width) / float(camera.width),
              sy = float(small.height) / float(camera.height);
  small.fx *= sx, small.cx = (camera.cx + 0.5f) * sx - 0.5f;
  small.fy *= sy, small.cy = (camera.cy + 0.5f) * sy - 0.5f;
  return small;
}

// The mean share of pixels on a surface over an orbit's views, rendered at a tenth of the size.
double PreviewHits(const SurfaceScene& scene, const RenderViewsParams& params,
                   const PinholeCamera& camera, const OrbitFraming& framing) {
  const PinholeCamera small = SmallCamera(camera);
  const std::vector<Pose3f> poses = OrbitPoses(framing.centre_W, framing.radius_m, framing.height_m,
                                               std::max(params.orbit_views, 1), params.up_W);
  double sum = 0.0;
  for (const Pose3f& T_W_C : poses) {
    const SurfaceImages s = scene.Render(small, T_W_C);
    sum += double(std::count_if(s.depth.data.begin(), s.depth.data.end(),
                                [](float z) { return z > 0.0f; })) /
           double(std::max<size_t>(1, s.depth.data.size()));
  }
  return sum / double(poses.size());
}

}  // namespace

PinholeCamera UprightCamera(const PinholeCamera& camera, const std::vector<Pose3f>& T_W_C,
                            const Eigen::Vector3f& up_W, bool* flipped) {
  if (flipped) *flipped = false;
  if (!(camera.fy < 0.0f)) return camera;
  // Rows run along -y of the camera in the image's upward direction for fy > 0, along +y here.
  double top_along_up = 0.0;
  for (const Pose3f& pose : T_W_C) top_along_up += double(pose.linear().col(1).dot(up_W));
  if (top_along_up >= 0.0) return camera;
  PinholeCamera upright = camera;
  upright.fy = -camera.fy;
  upright.cy = float(camera.height - 1) - camera.cy;
  if (flipped) *flipped = true;
  return upright;
}

Result<RenderedViews> RenderViews(const SurfaceScene& scene, const RenderViewsParams& params) {
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  RenderedViews views;
  PinholeCamera camera =
      params.camera ? *params.camera : CameraFromFov(params.width, params.height, params.fov_deg);
  views.bounds_W = scene.Bounds();
  const bool orbit = !params.T_W_C && params.poses.empty();
  // An orbit frames the surface where the scene gives samples of it (a map), else its box.
  const std::vector<Eigen::Vector3f> samples =
      orbit ? scene.SurfaceSamples() : std::vector<Eigen::Vector3f>();
  views.surface_framed = !samples.empty();
  const auto frame = [&](float elevation_deg) {
    OrbitFraming f = samples.empty() ? FrameBox(views.bounds_W, camera, elevation_deg)
                                     : FrameSurface(samples, camera, elevation_deg,
                                                    std::max(params.orbit_views, 1), params.up_W);
    if (params.orbit_radius_m) f.radius_m = *params.orbit_radius_m;  // given values win
    return f;
  };
  OrbitFraming& framing = views.framing;
  framing = frame(params.orbit_elevation_deg);
  if (params.orbit_height_m) {
    framing.height_m = *params.orbit_height_m;
  } else if (params.choose_side && orbit) {
    // The orbit mirrored below the centre, at the same distance, so the previews compare how
    // much of the surface each side sees. Below only when it sees clearly more: from above is
    // how rooms are drawn.
    OrbitFraming mirrored = framing;
    mirrored.height_m = -framing.height_m;
    if (PreviewHits(scene, params, camera, mirrored) >
        1.5 * PreviewHits(scene, params, camera, framing)) {
      // Framed for the views from there (for a box, the mirrored orbit itself).
      framing = samples.empty() ? mirrored : frame(-params.orbit_elevation_deg);
      views.from_below = true;
    }
  }
  framing.distance_m = std::hypot(framing.radius_m, framing.height_m);
  ShadeParams shade;
  if (!params.poses.empty()) {
    views.T_W_C = params.poses;  // depth range: per image
  } else if (params.T_W_C) {
    views.T_W_C.push_back(*params.T_W_C);  // depth range: per image
  } else {
    views.T_W_C = OrbitPoses(framing.centre_W, framing.radius_m, framing.height_m,
                             std::max(params.orbit_views, 1), params.up_W);
    // One depth range for the whole turntable, so colours mean the same depth in every view.
    shade.depth_near_m = std::max(0.0f, framing.distance_m - framing.bound_radius_m);
    shade.depth_far_m = framing.distance_m + framing.bound_radius_m;
  }

  camera = UprightCamera(camera, views.T_W_C, params.up_W, &views.rows_flipped);
  views.camera = camera;
  double hit_fraction_sum = 0.0;
  for (const Pose3f& T_W_C : views.T_W_C) {
    if (params.stop_requested && params.stop_requested())
      return Cancelled("stopped after " + std::to_string(views.images.size()) + " of " +
                       std::to_string(views.T_W_C.size()) + " views");
    const SurfaceImages surface = scene.Render(camera, T_W_C);
    const size_t hits = size_t(std::count_if(surface.depth.data.begin(), surface.depth.data.end(),
                                             [](float z) { return z > 0.0f; }));
    hit_fraction_sum += double(hits) / double(surface.depth.data.size());
    Result<ColorImage> image = Shade(surface, camera, T_W_C, params.mode, shade);
    if (!image.ok()) return image.status();
    views.images.push_back(std::move(*image));
  }
  views.hit_fraction = hit_fraction_sum / double(views.T_W_C.size());
  return views;
}

}  // namespace voxplan
