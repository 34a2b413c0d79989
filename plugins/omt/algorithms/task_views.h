// Task-view extraction of §3.2: a priority queue of frontier and uncertain surface cells, the
// best valid, collision-free view for its head, FOV-covered cells removed, κR views at most,
// each scored by expected uncertainty reduction.
#pragma once

#include <vector>

#include "plugins/omt/algorithms/types.h"
#include "plugins/omt/algorithms/validness.h"

namespace voxplan::omt {

struct UncertaintyParams {
  // Unknown cells get a "very high" uncertainty; surface cells 1 / (1 + w) from their TSDF
  // weight, so an unscanned surface ties with unknown space and a well-scanned one tends to 0.
  double unknown_uncertainty = 1.0;
  double weight_scale = 1.0;             // w is divided by this before 1 / (1 + w)
  double min_surface_uncertainty = 0.2;  // surface cells below this are not queued
  // Expected weight one more observation of quality q adds to a surface cell.
  double observation_weight = 1.0;
  // Unknown cells behind unknown cells are seen with probability exp(-s / decay) after
  // s metres of unknown space: the expected reveal of a view into unexplored space.
  double unknown_decay_m = 1.0;
};

// §3.2 uncertainty of one cell: 0 free, unknown_uncertainty unknown, 1 / (1 + w) occupied.
double CellUncertainty(Cell cell, float tsdf_weight, const UncertaintyParams& params);

struct Candidate {
  int cell = -1;
  float uncertainty = 0.0f;
};
// The priority queue's entries, sorted by uncertainty (descending, ties by cell index): frontier
// cells (unknown, 4-adjacent to free) and surface cells (occupied, 4-adjacent to free) whose
// uncertainty is at least min_surface_uncertainty.
std::vector<Candidate> CollectCandidates(const OccupancyRaster& raster,
                                         const UncertaintyParams& params);

struct TaskView {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;         // towards the target cell centre
  int cell = -1;                // raster cell of the view position
  int target_cell = -1;         // the queue head it was chosen for
  bool target_unknown = false;  // the target is unknown floor (not a surface to rescan)
  double target_near_m = 0.0;   // from the view to the near edge of the target cell
  float validness = 0.0f;
  double importance = 0.0;  // expected uncertainty reduction, in reference-cell units
};

struct TaskViewParams {
  SensorParams sensor;
  UncertaintyParams uncertainty;
  double robot_radius_m = 0.18;
  double clearance_factor = 1.5;  // views need clearance > 1.5 robot radii (§3.2)
  int max_views = 60;             // κR
  // Importance is summed over cells and scaled by (resolution / reference)² so that it does
  // not depend on the raster resolution; the paper's 10 cm grid is the reference.
  double reference_cell_m = 0.1;
  // NoTV ablation: the task is the frontier point itself (nearest collision-free cell, facing
  // the target) instead of the best view of it.
  bool frontier_points_only = false;
  // Heads tried before giving up (each failure costs one backward ray fan).
  int max_heads = 4000;
  // Return views by decreasing importance (stable), else in extraction (priority) order.
  bool sort_by_importance = true;
};

// Expected uncertainty reduction of one view (the paper's Krainin-style importance): rays over
// the FOV up to d_max; a surface cell hit with quality q = φψ loses 1/(1+w) - 1/(1+w+q·w_obs);
// unknown cells count unknown_uncertainty · ψ · exp(-s / decay). When covered is given,
// every cell the fan reaches is appended to it (deduplicated).
double ViewImportance(const OccupancyRaster& raster, const Eigen::Vector2d& p_m, double yaw_rad,
                      const TaskViewParams& params, std::vector<int>* covered = nullptr);

// Views in extraction order. accessible (optional, one byte per cell, non-zero = reachable by
// some robot) restricts view positions; clearance gives the collision test.
std::vector<TaskView> ExtractTaskViews(const OccupancyRaster& raster,
                                       const ClearanceRaster& clearance,
                                       const TaskViewParams& params,
                                       const std::vector<std::uint8_t>* accessible = nullptr);

// What one view can see at most, in m²: the fan's area weighted by ψ up to d_max (the importance
// of a view into unknown space with nothing in the way, before the reference-cell scale).
double ViewCapacity(const SensorParams& sensor);

// Termination test of §4: true when no view has importance above the threshold (1.5).
bool ShouldTerminate(const std::vector<TaskView>& views, double importance_threshold = 1.5);

}  // namespace voxplan::omt
