// Path advection over tensor fields, Xu et al. 2017 §4.2 (X L182-195, L308; planner-wave.md X4,
// X5, X12, G.2 item 4): a pathline from the robot's pose along the major eigenvector field, the
// line field oriented at every step to agree with the direction of travel (< 90°, the robot's
// front), integrated with classical RK4 at a fixed arc-length step; the stop conditions the
// planner needs (length, obstacle, domain, near-zero field, a wedge or trisector ahead, a closed
// loop); the wall-clearance push of X L308; and the speed profile that slows down before the
// nearest wedge ahead (X L194). The same integrator traces separatrices (skeleton.h).
//
// Why RK4: four field samples per 5 cm step cost nothing next to the field itself (a 0.36 m
// pathline is 8 steps), and separatrices are traced over tens of metres, where RK2's O(h²) drift
// on curved tensor lines (the circle test: ~1e-3 m per metre) would be visible at the capture
// radius. The bilinear field is only C⁰ across cell edges, so the realised order is lower than 4
// there; RK4 is still the more accurate of the two at the same step.
//
// Plain data and callbacks; deterministic, single-threaded, prints nothing.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {

// Why a pathline ended.
enum class AdvectionStop : std::uint8_t {
  kLength,      // reached AdvectionParams::max_length_m
  kLeftDomain,  // the next point lies outside the raster or (stop_outside_domain) the field domain
  kBlocked,     // the next point is not traversable (obstacle): counts as a blocked pathline
  kDegenerate,  // the field magnitude fell below the threshold (a degenerate point or no field)
  kWedge,       // reached a wedge ahead (X L194: stop there and re-plan)
  kTrisector,   // reached a trisector ahead (X L195: stop and choose a branch)
  kLoop,        // came back onto its own earlier part
};

// True when the robot may stand at p (the planner's body/contact test). Empty: no test.
using TraversableFn = std::function<bool(const Eigen::Vector2d& p_m)>;

// What counts as an obstacle, both optional. With a clearance raster (omt::ComputeClearance: the
// distance from each cell centre to the nearest obstacle cell centre) a point is blocked when its
// bilinear clearance is below block_clearance_m and lower than the clearance of the point it comes
// from (a robot already inside the band may move along or out of it, never deeper); the raster
// also drives the wall push (X L308). The callback, when set, must also accept every point.
struct AdvectionObstacles {
  const omt::ClearanceRaster* clearance = nullptr;
  TraversableFn traversable;
};

struct AdvectionParams {
  double step_m = 0.05;  // RK4 step in arc length (the field grid, X§6)
  // X4: three sub-steps of 0.4 s at 0.3 m/s. The returned pathline ends here at the latest.
  double max_length_m = 0.36;
  // Stop when |τ| falls below this (absolute); negative: min_relative_magnitude × the largest
  // magnitude of the (first) field over its domain, which costs one pass over the raster per call
  // (0.4 ms on 20 m x 20 m, 40x the 0.36 m line itself: a planner should pass MaxFieldMagnitude
  // once per field). 1e-3 is TopologyParams' flat rule: beyond the blend's 3σ truncation the field
  // is exactly zero (room centres more than 1.5 m from every wall) and has no direction.
  double min_magnitude = -1.0;
  double min_relative_magnitude = 1e-3;
  // The magnitude test starts after this much arc (separatrices leave a point where |τ| = 0).
  double magnitude_check_after_m = 0.0;
  bool stop_outside_domain = true;  // false: only leaving the raster ends the line

  // Degenerate points ahead (X5, X6). A point triggers a stop when the line comes within
  // arrive_radius_m of it, or when the line, having approached it to within its capture radius,
  // starts to move away again (the closest approach: "first approaches and then leaves", X L314).
  // A point the line only moves away from (the robot just left it) never triggers.
  double wedge_capture_radius_m = 0.3;
  double trisector_capture_radius_m = 0.5;  // X L314's docking distance
  double arrive_radius_m = 0.025;           // half a step
  bool stop_at_wedges = true;
  bool stop_at_trisectors = true;

  // Loop: the new point is within loop_radius_m of a point at least loop_min_arc_m of arc earlier.
  double loop_radius_m = 0.1;
  double loop_min_arc_m = 1.0;

  // Obstacles (AdvectionObstacles::clearance).
  double block_clearance_m = 0.25;  // the robot radius [ours]
  // X L308: closer than this to a known wall, step away along the wall normal (the clearance
  // gradient), at most wall_push_per_step_m per step, when the pushed point is still traversable.
  // Non-positive: no push.
  double wall_clearance_m = 0.3;
  double wall_push_per_step_m = 0.025;

  // Speed profile (X5): max speed, slowing linearly over slowdown_distance_m of arc to min speed
  // at a wedge stop. The integration looks that far beyond max_length_m for the wedge.
  double max_speed_mps = 0.3;  // X L304
  double min_speed_mps = 0.05;
  double slowdown_distance_m = 0.6;

  // Time-varying fields (AdvectPathline over frames): the arc length travelled between two
  // consecutive frames (one sub-step: 0.4 s × 0.3 m/s); the field at arc length s is the linear
  // blend of frames floor(s / spacing) and the next, the last frame beyond the sequence.
  double frame_spacing_m = 0.12;

  // The vector-field baselines (X Fig. 2): the raster's two components are a vector (vx, vy), not
  // (τ11, τ12). The line follows the vector itself, or its opposite when that agrees better with
  // the start heading; the choice holds for the whole line (a vector field has a sign, so unlike
  // the line field it is not re-oriented along the way and runs into its sinks).
  bool vector_field = false;
};

struct PathPoint {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double arc_length_m = 0.0;  // from the start, non-decreasing
  double heading_rad = 0.0;   // the path's tangent (central difference; one-sided at the ends)
  double speed_mps = 0.0;     // the speed profile
};

struct Pathline {
  std::vector<PathPoint> points;  // the start first; never empty for a start inside the raster
  AdvectionStop stop = AdvectionStop::kLength;
  // The degenerate point (index into the given list) that stopped the line: kWedge, kTrisector.
  int stop_point = -1;
  // The nearest wedge ahead along the line, within the look-ahead: its index and the arc length
  // at which the line reaches it (equal to the last point's for a kWedge stop); -1 when none.
  int wedge_ahead = -1;
  double wedge_ahead_arc_m = -1.0;
  int wall_pushes = 0;  // steps moved away from a wall (X L308)

  bool Blocked() const { return stop == AdvectionStop::kBlocked; }
  double Length() const { return points.empty() ? 0.0 : points.back().arc_length_m; }
};

// Pathline from start_m, the first direction the major eigenvector oriented to agree with
// heading_rad. degenerate_points: the field's wedges and trisectors (FindDegeneratePoints; may be
// empty). A start outside the raster gives no points and kLeftDomain.
Pathline AdvectPathline(const TensorRaster& field, const Eigen::Vector2d& start_m,
                        double heading_rad, std::span<const DegeneratePoint> degenerate_points,
                        const AdvectionParams& params, const AdvectionObstacles& obstacles = {});

// The same over a time-varying sequence (InterpolateFrames' frames from the current sub-step on),
// frame k reached after k × frame_spacing_m of arc. All frames must share a geometry; the domain
// is that of the frame at the current arc length (rounded down), the relative magnitude threshold
// is taken from the first frame.
Pathline AdvectPathline(std::span<const TensorRaster> frames, const Eigen::Vector2d& start_m,
                        double heading_rad, std::span<const DegeneratePoint> degenerate_points,
                        const AdvectionParams& params, const AdvectionObstacles& obstacles = {});

// The largest |τ| over the field's domain (0 for an empty raster).
double MaxFieldMagnitude(const TensorRaster& field);

// The unit major eigenvector at p oriented to make an angle < 90° with `reference` (ties: as
// MajorEigenvector); nullopt outside the raster.
std::optional<Eigen::Vector2d> OrientedDirection(const TensorRaster& field,
                                                 const Eigen::Vector2d& p_m,
                                                 const Eigen::Vector2d& reference);

// Speed at arc length s for a stop at a wedge at arc length wedge_arc_m (negative: none): max
// speed, ramping linearly down to min speed over the slowdown distance before the wedge.
double SpeedBeforeWedge(double s_m, double wedge_arc_m, const AdvectionParams& params);

// The blocked-path metric (X Fig. 15, planner-wave.md §2.5): the share of advected pathlines that
// an obstacle stopped.
struct BlockedPathCounter {
  int pathlines = 0;
  int blocked = 0;

  void Add(const Pathline& line) {
    ++pathlines;
    if (line.Blocked()) ++blocked;
  }
  double Rate() const { return pathlines == 0 ? 0.0 : static_cast<double>(blocked) / pathlines; }
};

}  // namespace voxplan::tensorfield
