#include "eval/visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/image.h"
#include "core/parallel.h"

namespace voxplan {

namespace {

constexpr size_t kPointGrain = 4096;
constexpr size_t kViewsPerPass = 32;

struct View {
  Pose3f T_C_W;
  DepthImage depth;
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

Result<PointSetFilter> ObservableSurfaceFilter(const MeshRaycaster& raycaster,
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
  std::vector<Pose3f> poses;
  for (size_t k = 0; k < T_W_C.size(); k += size_t(params.pose_stride)) {
    if (!T_W_C[k].matrix().allFinite())
      return InvalidArgument("ObservableSurfaceFilter: pose " + std::to_string(k) +
                             " is not finite");
    poses.push_back(T_W_C[k].cast<float>());
  }
  return PointSetFilter([&raycaster, camera, params,
                         poses = std::move(poses)](const std::vector<Eigen::Vector3f>& points) {
    std::vector<uint8_t> kept(points.size(), 0);
    // Render to the full range: a nearer hit beyond max_depth_m still hides what is behind it.
    const RenderParams render_params;
    // Views a batch at a time: memory for kViewsPerPass depth images, and one sweep over the
    // points per batch rather than per view.
    std::vector<View> views;
    for (size_t first = 0; first < poses.size(); first += kViewsPerPass) {
      views.clear();
      for (size_t k = first; k < std::min(first + kViewsPerPass, poses.size()); ++k)
        views.push_back(
            {poses[k].inverse(), raycaster.Render(camera, poses[k], render_params).depth});
      ParallelFor(points.size(), kPointGrain, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
          if (kept[i]) continue;
          for (const View& view : views)
            if (SeenIn(view, camera, params, points[i])) {
              kept[i] = 1;
              break;
            }
        }
      });
    }
    return kept;
  });
}

}  // namespace voxplan
