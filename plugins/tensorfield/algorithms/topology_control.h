// Topology control, Xu 2017 §4.3 (X L231-253, eq. 6; planner-wave.md X8), all optional (X L233):
//  (a) a wedge whose two nearest separatrices meet at less than 90° is formed by a sharp corner:
//      it is moved into the corner, out of the robot's reach, so the turn there is smooth;
//  (b) an end wedge of the skeleton with nothing left to gain after the robot has been there is
//      retracted along its separatrix, so the robot does not revisit it with a deep U-turn;
//  (c) a trisector the robot would collide at, or whose separatrices run into an obstacle close
//      to it, is moved away from the obstacles until it and its separatrices are clear;
//  (d) a wedge-trisector pair is cancelled when its shortest distance over the topological
//      skeleton is below the sum of the two points' local feature sizes (their distance to the
//      nearest obstacle), by Laplacian smoothing of τ11 and τ12 in a small disc around the pair
//      until no degenerate point is left in it.
// A point is moved (after Zhang et al. 2007's editing, in the paper's V = μ (cos 2θ, sin 2θ)) by
// a local multiplicative factor whose pole cancels the point and whose zero makes it again at the
// target. Every operation is checked by finding the degenerate points in its region again: one
// that does not give the intended topology is undone. Plain data; deterministic; prints nothing.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <span>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/skeleton.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {

// ---------------------------------------------------------------------------------------------
// (d) Pair cancellation.

struct PairCancelParams {
  double margin_m = 0.15;  // the disc: half the pair's distance plus this [ours]
  int sweeps = 200;        // Gauss-Seidel sweeps per round
  int rounds = 3;          // rounds (the disc grows by one margin each) before giving up
  double min_relative_magnitude = 1e-5;  // the degenerate-point test's flat rule (TopologyParams)
};

struct PairCancelResult {
  int candidates = 0;  // pairs meeting eq. 6
  int cancelled = 0;
};

// Smooths τ11 and τ12 inside the disc (cells whose centre lies within radius_m), the cells
// outside held fixed, and reports whether the disc is then free of degenerate points.
bool SmoothDisc(TensorRaster* field, const Eigen::Vector2d& centre_m, double radius_m, int sweeps,
                double min_relative_magnitude);

// X8 (d) on `field` in place. points and skeleton: the field's before (ExtractSkeleton's nodes
// 0..P-1 are the points); clearance: the obstacle distance for lfs. Pairs by increasing skeleton
// distance, each point in at most one.
PairCancelResult CancelDegeneratePairs(TensorRaster* field, std::span<const DegeneratePoint> points,
                                       const Skeleton& skeleton,
                                       const omt::ClearanceRaster& clearance,
                                       const PairCancelParams& params = {});

// ---------------------------------------------------------------------------------------------
// Moving one degenerate point (the primitive of a-c).

struct PointMoveParams {
  // The weight of the move (below) is 1 within inner_m of the segment from the point to its
  // target and falls smoothly to 0 at outer_m [ours].
  double inner_m = 0.1;
  double outer_m = 0.4;
  double min_relative_magnitude = 1e-5;  // the degenerate-point test's flat rule (TopologyParams)
};

// Moves `point`, a degenerate point of `field` and the only one within outer_m of the segment
// from it to target_m, to target_m. With V = τ11 + i τ12 as a complex number, V is multiplied by
// f^w, f = (z - z_t) / (z - z_p) for a wedge and its conjugate for a trisector: f's pole cancels
// the zero at z_p and its zero makes one at z_t, so the linear field around the point is carried
// to the target; w is the weight above, so nothing changes beyond outer_m and, f^w having no zero
// where w < 1, no other point is made. True, with the point as found afterwards in moved_out
// (optional), when the region then holds exactly one degenerate point, of the same type, within
// one cell of the target; otherwise the field is left as it was.
bool MoveDegeneratePoint(TensorRaster* field, const DegeneratePoint& point,
                         const Eigen::Vector2d& target_m, const PointMoveParams& params = {},
                         DegeneratePoint* moved_out = nullptr);

// ---------------------------------------------------------------------------------------------
// (a)-(c) over a key frame.

struct PointMovesParams {
  PointMoveParams move;
  double robot_radius_m = 0.2;  // a point with less clearance is out of the robot centre's reach
  double step_m = 0.05;         // candidate targets along a move's direction
  // (a) X L235: the separatrices' angle, and how far the corner may be.
  double corner_max_angle_rad = 1.5707963267948966;
  double corner_max_move_m = 1.0;
  // (b) X L243: how far along the end separatrix, stopping this short of its other end [ours].
  double retract_m = 1.0;
  double retract_keep_m = 0.3;
  // (c) X L243: the separatrices must be clear this far from the trisector, which moves up the
  // clearance at most this far, in steps of 2 step_m [ours].
  double trisector_check_m = 0.6;
  double trisector_max_move_m = 1.0;
  // Separatrix tracing for (c)'s check; block_clearance_m should be the robot radius.
  SkeletonParams trace;
};

struct PointMovesResult {
  int corner_wedges = 0;     // (a)
  int retracted_wedges = 0;  // (b)
  int moved_trisectors = 0;  // (c)
  int failed = 0;            // moves asked for whose check failed (the field kept as it was)
};

// The planner's test for (b): whether the end wedge, with `edge` its one skeleton edge, is
// exhausted (the robot has been there and nothing along the edge is left to gain).
using ExhaustedEndFn = std::function<bool(const DegeneratePoint& wedge, const SkeletonEdge& edge)>;

// X8 (a)-(c) on `field` in place, each point at most once, in the order given: a wedge with one
// skeleton edge that `exhausted` accepts is retracted (b), else a corner wedge is moved into its
// corner (a); a trisector in collision is moved away (c). points and skeleton: the field's before;
// clearance: the window's obstacle distance. exhausted may be empty (no retraction).
PointMovesResult MoveDegeneratePoints(TensorRaster* field, std::span<const DegeneratePoint> points,
                                      const Skeleton& skeleton,
                                      const omt::ClearanceRaster& clearance,
                                      const ExhaustedEndFn& exhausted,
                                      const PointMovesParams& params = {});

}  // namespace voxplan::tensorfield
