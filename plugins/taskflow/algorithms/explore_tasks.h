// Exploration tasks of the task-flow planner (Guo et al. 2022, §4.1): frontier cells of the
// floor raster, farthest-point sampled; candidate viewpoints that see a sample from a given
// distance band; a validity score; greedy cover with the explorer camera's FOV and range.
//
// Plain data over the planner ABI's floor raster (no voxplan library dependency), so the plugin
// passes the host's arrays straight in as spans.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::taskflow {

// VP_FLOOR_* values of the planner ABI; frontier = free and 8-adjacent to unknown.
enum class FloorCell : std::uint8_t { kUnknown = 0, kFree = 1, kFrontier = 2, kObstacle = 3 };

// The host's floor raster, not owned: cells and clearance_m hold geometry.NumCells() values.
struct FloorView {
  omt::RasterGeometry geometry;
  std::span<const std::uint8_t> cells;  // FloorCell values
  std::span<const float> clearance_m;   // cell centre to the nearest obstacle
  FloorCell At(int index) const { return static_cast<FloorCell>(cells[index]); }
};

// The explorer mode's camera (vp_mode_params of VP_MODE_EXPLORER).
struct ExplorerCamera {
  double horizontal_fov_rad = 1.5707963267948966;
  double min_range_m = 0.0;
  double max_range_m = 5.0;
};

struct ExploreInput {
  FloorView floor;
  std::vector<Eigen::Vector2d> robots_xy_m;
  // Per robot, a geodesic distance field over the raster (one value per cell, +inf where the
  // robot cannot go), as the host's geodesic_field returns it.
  std::vector<std::span<const float>> geodesic_m;
  ExplorerCamera camera;
};

struct ExploreParams {
  double frontier_spacing_m = 0.5;  // farthest-point sampling stops below this spacing
  double min_view_distance_m = 1.0;
  double max_view_distance_m = 4.0;
  double min_clearance_m = 0.25;  // a candidate's clearance; the robot radius plus a margin
  // Candidates lie on a lattice of about this spacing (at least one cell): a view cell every
  // 5 cm would cost ~20k line-of-sight rays per frontier sample for no better view.
  double candidate_spacing_m = 0.2;
  int views_per_robot = 2;  // at most views_per_robot × R views per round ...
  int max_views = 0;        // ... unless this is > 0
  // Literal G§4.1 score d_r − d_f. Maximising it prefers cells far from robots and near walls,
  // the opposite of the text's intent (design doc §1.4), so the default is d_f − d_r.
  bool paper_sign = false;
};

// A cell from which at least one frontier sample is visible within the distance band.
struct ViewCandidate {
  int cell = -1;
  double d_free_m = 0.0;       // d_f: distance to the nearest non-free cell
  double d_robot_m = 0.0;      // d_r: geodesic distance to the nearest robot
  double score = 0.0;          // d_f − d_r (or d_r − d_f with paper_sign)
  std::vector<int> frontiers;  // indices into the frontier samples it sees, ascending
};

struct ExploreView {
  Eigen::Vector2d xy_m = Eigen::Vector2d::Zero();
  double theta_rad = 0.0;  // centred on the frontier samples it covers
  double score = 0.0;
  int cell = -1;
  std::vector<int> covered;  // frontier sample indices first covered by this view, ascending
};

struct ExploreResult {
  omt::Status status;
  std::vector<int> frontier_samples;  // cell indices, in sampling order
  int num_candidates = 0;
  std::vector<ExploreView> views;  // in selection order
  int uncovered = 0;               // frontier samples no view covers
};

// Farthest-point sampling of the frontier cells (Euclidean, cell centres): starts at the first
// frontier cell in row-major order, then repeatedly takes the cell farthest from the samples
// (ties to the lower index) while that distance is >= spacing_m. Hence samples are pairwise
// >= spacing_m apart and every frontier cell lies within spacing_m of one.
std::vector<int> SampleFrontiers(const FloorView& floor, double spacing_m);

// Euclidean distance (metres) from every cell centre to the nearest obstacle or unknown cell
// centre. The host's clearance counts obstacles only; d_f of G§4.1 also avoids unknown space.
std::vector<float> NonFreeDistance(const FloorView& floor);

// 2-D line of sight between cell centres: no obstacle or unknown cell strictly between them
// (both end cells excluded). Rays touching a cell corner count that cell, so it is
// conservative at corners.
bool LineOfSight(const FloorView& floor, int from_cell, int to_cell);

// Traversable: free or frontier, clearance >= min_clearance_m, finite geodesic distance for
// at least one robot.
std::vector<std::uint8_t> TraversableCells(const ExploreInput& input, double min_clearance_m);

// Candidates (ascending cell index) for the frontier samples, with their scores.
std::vector<ViewCandidate> ViewCandidates(const ExploreInput& input,
                                          const std::vector<int>& frontier_samples,
                                          const std::vector<float>& non_free_distance_m,
                                          const ExploreParams& params);

// The whole of G§4.1. Greedy cover: the best-scoring candidate takes the heading that covers
// the most uncovered samples inside the camera's FOV and range with line of sight (ties: the
// narrowest bearing spread), centred on them; candidates whose samples are all covered are
// removed (scores may be negative, so the paper's "set to zero" becomes "remove").
ExploreResult GenerateExplorationTasks(const ExploreInput& input, const ExploreParams& params);

}  // namespace voxplan::taskflow
