#include "planning/integrate_planning.h"

#include "core/stopwatch.h"

namespace voxplan {

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
  const Stopwatch total_clock;
  Stopwatch clock;
  Result<IntegrateStats> integrated = IntegrateFrame(depth, color, camera, T_W_C, params, volume);
  if (!integrated.ok()) return integrated.status();
  stats.integrate = std::move(integrated).value();
  stats.integrate_ms = clock.ElapsedMs();
  clock.Restart();
  stats.map = map.Update(stats.integrate.touched_blocks);
  stats.map_ms = clock.ElapsedMs();
  clock.Restart();
  if (with_labels) {
    VOXPLAN_RETURN_IF_ERROR(map.FuseLabels(depth, *labels, camera, T_W_C,
                                           stats.integrate.touched_blocks, params.min_depth_m,
                                           params.max_depth_m));
  }
  stats.labels_ms = clock.ElapsedMs();
  stats.total_ms = total_clock.ElapsedMs();
  stats.revision = map.revision();
  return stats;
}

}  // namespace voxplan
