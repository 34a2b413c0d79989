#pragma once
// One frame into a planning map: TSDF integration with free-space carving into the planning
// volume, then the derived maps (state, frontier, surface, object labels) for the blocks the
// frame touched.
#include "fusion/integrate.h"
#include "planning/planning_map.h"

namespace voxplan {

struct PlanningFrameStats {
  IntegrateStats integrate;  // touched_blocks lists the blocks this frame changed
  PlanningUpdateStats map;
  double integrate_ms = 0.0;  // allocation + TSDF update
  double map_ms = 0.0;        // derived masks
  double labels_ms = 0.0;     // label fusion (0 without labels)
  double total_ms = 0.0;
  uint64_t revision = 0;  // the map's revision after this frame
};

// `params.carve_free_space` is forced on. `labels` may be null or empty; otherwise the same size
// as depth (0 = no label). `map` must be derived from `volume` (InvalidArgument otherwise).
Result<PlanningFrameStats> IntegratePlanningFrame(const DepthImage& depth, const ColorImage& color,
                                                  const LabelImage* labels,
                                                  const PinholeCamera& camera, const Pose3f& T_W_C,
                                                  IntegrateParams params, TsdfVolume& volume,
                                                  PlanningMap& map);

}  // namespace voxplan
