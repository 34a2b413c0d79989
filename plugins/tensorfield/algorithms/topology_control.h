// Topology control, Xu 2017 §4.3 (X L245-253, eq. 6; planner-wave.md X8 (d)): a wedge-trisector
// pair is cancelled when its shortest distance over the topological skeleton is below the sum of
// the two points' local feature sizes (their distance to the nearest obstacle), by Laplacian
// smoothing of τ11 and τ12 in a small disc around the pair until no degenerate point is left in
// it. A pair whose disc stays degenerate is left as it was. The moves of single points (X8 a-c)
// are not built. Plain data; deterministic; prints nothing.
#pragma once

#include <Eigen/Core>
#include <span>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/skeleton.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {

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

}  // namespace voxplan::tensorfield
