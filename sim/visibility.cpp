#include "sim/visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/image.h"

namespace voxplan {

namespace {

struct View {
  Pose3f T_C_W;
  DepthImage depth;
};

struct Views {
  PinholeCamera camera;
  VisibilityParams params;
  std::vector<View> views;
};

bool SeenIn(const View& view, const PinholeCamera& camera, const VisibilityParams& params,
            const Eigen::Vector3f& p_W) {
  const Eigen::Vector3f p_C = view.T_C_W * p_W;
  const float z = p_C.z();
  if (!(z >= params.min_depth_m && z <= params.max_depth_m)) return false;
  const Eigen::Vector2f uv = camera.Project(p_C);
  // Pixel footprints span +-0.5 around the integer centres.
  if (!(uv.x() >= -0.5f && uv.y() >= -0.5f && uv.x() < float(camera.width) - 0.5f &&
        uv.y() < float(camera.height) - 0.5f))
    return false;
  const int u0 = std::clamp(int(std::floor(uv.x())), 0, camera.width - 1);
  const int v0 = std::clamp(int(std::floor(uv.y())), 0, camera.height - 1);
  const int u1 = std::min(u0 + 1, camera.width - 1), v1 = std::min(v0 + 1, camera.height - 1);
  float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
  for (const float d : {view.depth.at(u0, v0), view.depth.at(u1, v0), view.depth.at(u0, v1),
                        view.depth.at(u1, v1)}) {
    if (!(d > 0.f)) continue;  // no hit there
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return hi > 0.f && z >= lo - params.depth_tolerance_m && z <= hi + params.depth_tolerance_m;
}

}  // namespace

Result<PointFilter> ObservableSurfaceFilter(const MeshRaycaster& raycaster,
                                            const PinholeCamera& camera,
                                            const std::vector<Pose3d>& T_W_C,
                                            const VisibilityParams& params) {
  if (!camera.Valid()) return InvalidArgument("ObservableSurfaceFilter: invalid camera");
  if (T_W_C.empty()) return InvalidArgument("ObservableSurfaceFilter: no poses");
  if (params.pose_stride < 1)
    return InvalidArgument("ObservableSurfaceFilter: pose_stride must be >= 1");
  if (!(params.min_depth_m >= 0.f && params.max_depth_m > params.min_depth_m) ||
      !std::isfinite(params.max_depth_m))
    return InvalidArgument("ObservableSurfaceFilter: need 0 <= min_depth_m < max_depth_m");
  if (!(params.depth_tolerance_m > 0.f) || !std::isfinite(params.depth_tolerance_m))
    return InvalidArgument("ObservableSurfaceFilter: depth_tolerance_m must be positive");

  auto views = std::make_shared<Views>();
  views->camera = camera;
  views->params = params;
  // Render to the full range: a nearer hit beyond max_depth_m still hides what is behind it.
  const RenderParams render_params;
  for (size_t k = 0; k < T_W_C.size(); k += size_t(params.pose_stride)) {
    if (!T_W_C[k].matrix().allFinite())
      return InvalidArgument("ObservableSurfaceFilter: pose " + std::to_string(k) +
                             " is not finite");
    const Pose3f T_W_Ck = T_W_C[k].cast<float>();
    views->views.push_back(
        {T_W_Ck.inverse(), raycaster.Render(camera, T_W_Ck, render_params).depth});
  }
  std::shared_ptr<const Views> shared = std::move(views);
  return PointFilter([shared](const Eigen::Vector3f& p_W) {
    for (const View& view : shared->views)
      if (SeenIn(view, shared->camera, shared->params, p_W)) return true;
    return false;
  });
}

}  // namespace voxplan
