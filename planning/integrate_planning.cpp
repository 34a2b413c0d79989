#include "planning/integrate_planning.h"

#include <chrono>

namespace voxplan {

namespace {
double MsBetween(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}
}  // namespace

Result<PlanningFrameStats> IntegratePlanningFrame(const DepthImage& depth, const ColorImage& color,
                                                  const LabelImage* labels,
                                                  const PinholeCamera& camera, const Pose3f& T_W_C,
                                                  IntegrateParams params, TsdfVolume& volume,
                                                  PlanningMap& map) {
  if (&map.volume() != &volume)
    return InvalidArgument("the planning map is derived from a different volume");
  const bool with_labels = labels != nullptr && !labels->empty();
  if (with_labels && (labels->width != depth.width || labels->height != depth.height))
    return InvalidArgument("label image size differs from the depth image size");
  params.carve_free_space = true;
  PlanningFrameStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  Result<IntegrateStats> integrated = IntegrateFrame(depth, color, camera, T_W_C, params, volume);
  if (!integrated.ok()) return integrated.status();
  stats.integrate = std::move(integrated).value();
  const auto t1 = std::chrono::steady_clock::now();
  stats.map = map.Update(stats.integrate.touched_blocks);
  const auto t2 = std::chrono::steady_clock::now();
  if (with_labels) {
    VOXPLAN_RETURN_IF_ERROR(map.FuseLabels(depth, *labels, camera, T_W_C,
                                           stats.integrate.touched_blocks, params.min_depth_m,
                                           params.max_depth_m));
  }
  const auto t3 = std::chrono::steady_clock::now();
  stats.integrate_ms = MsBetween(t0, t1);
  stats.map_ms = MsBetween(t1, t2);
  stats.labels_ms = MsBetween(t2, t3);
  stats.total_ms = MsBetween(t0, t3);
  stats.revision = map.revision();
  return stats;
}

}  // namespace voxplan
