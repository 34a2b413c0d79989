// The topological skeleton of a tensor field and global routing over it, Xu et al. 2017 §4.2 and
// §6 (X L197-229, L312-314; planner-wave.md X6, X7, X13, G.2 items 3, 4, 7): separatrices traced
// by advection from every degenerate point along each of its separatrix directions; the graph of
// degenerate points and separatrix ends joined by them; docking at a passing trisector; the
// minimum-cost spanning tree (Prim) with c(e) = ((1/ℓ(e)) ∫_e I dp)⁻¹; the branch choice at a
// trisector; and the termination test (every accessible edge's gain below 0.01).
//
// The gain model is the planner's (X L220's appendix is unavailable): edges carry per-edge values
// computed by callbacks. Plain data; deterministic, single-threaded, prints nothing.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/advection.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {

// ---------------------------------------------------------------------------------------------
// The graph (X Fig. 7).

enum class SkeletonNodeKind : std::uint8_t {
  kWedge,
  kTrisector,
  kLeaf,  // a separatrix end that is no degenerate point: obstacle, boundary, flat field, length
};

struct SkeletonNode {
  SkeletonNodeKind kind = SkeletonNodeKind::kLeaf;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int degenerate_index = -1;  // into the degenerate points given (wedges and trisectors)
  AdvectionStop end = AdvectionStop::kLength;  // leaves: why the separatrix ended there
};

struct SkeletonEdge {
  int from = 0;  // node indices; from is the degenerate point the separatrix was traced from
  int to = 0;
  std::vector<Eigen::Vector2d> polyline;  // from's position first, to's position last
  double length_m = 0.0;                  // of the polyline
  double from_angle_rad = 0.0;            // the separatrix direction it was traced along
  int merged = 0;                         // further traced separatrices merged into this one
};

struct Skeleton {
  // Nodes 0..P-1 are the degenerate points in the order given; leaves follow.
  std::vector<SkeletonNode> nodes;
  std::vector<SkeletonEdge> edges;
  int traced = 0;  // separatrices traced (before merging)

  // Edge indices incident to a node, increasing.
  std::vector<int> IncidentEdges(int node) const;
  // The other end of edge e seen from node.
  int Other(int e, int node) const {
    const SkeletonEdge& edge = edges[static_cast<std::size_t>(e)];
    return edge.from == node ? edge.to : edge.from;
  }
};

struct SkeletonParams {
  double step_m = 0.05;        // RK4 step
  double max_length_m = 30.0;  // a separatrix longer than this ends in a leaf
  // A separatrix ends at another degenerate point when it comes within arrive_radius_m of it or
  // reaches its closest approach within capture_radius_m (AdvectionParams' rule). The paper pairs
  // points by shortest paths to repair missed connections (X L312, Palacios & Zhang 2007); a
  // generous capture radius stands in for it here.
  double capture_radius_m = 0.3;
  double arrive_radius_m = 0.05;
  double min_relative_magnitude = 1e-3;  // of the field's largest magnitude: ends in a leaf
  bool stop_outside_domain = true;
  // Obstacles (AdvectionObstacles): a separatrix ends in a leaf where the clearance falls below
  // this (no wall push while tracing).
  double block_clearance_m = 0.0;
  // Two separatrices joining the same two nodes are one edge when each one's points lie on average
  // within this of the other polyline (A→B traced from both ends); otherwise both are kept (two
  // routes around an island). Leaves closer than leaf_merge_radius_m are one node.
  double merge_distance_m = 0.25;
  double leaf_merge_radius_m = 0.15;
  double loop_radius_m = 0.1;
  double loop_min_arc_m = 1.0;
};

// Traces every separatrix of every point (from step_m along its direction) and builds the graph.
// Points without separatrix directions are isolated nodes.
Skeleton ExtractSkeleton(const TensorRaster& field, std::span<const DegeneratePoint> points,
                         const SkeletonParams& params, const AdvectionObstacles& obstacles = {});

// ---------------------------------------------------------------------------------------------
// Docking (X L314): the robot passes a trisector when its path first approaches and then leaves
// it, the minimal distance below 0.5 m.

struct DockingParams {
  double radius_m = 0.5;
  double leave_margin_m = 0.02;  // "leaving": the latest distance exceeds the minimum by this
};

struct Docking {
  int point = -1;          // the trisector, index into the degenerate points
  int closest_sample = 0;  // index into the positions where the distance was smallest
  double min_distance_m = 0.0;
};

// Over the robot's recent positions (oldest first), the trisector it docks at: the minimum
// distance within the radius, reached after the first sample and before the last, the last sample
// farther by the margin. Among several, the smallest minimum distance. Wedges are ignored.
std::optional<Docking> DetectDocking(std::span<const Eigen::Vector2d> positions,
                                     std::span<const DegeneratePoint> points,
                                     const DockingParams& params = {});

// ---------------------------------------------------------------------------------------------
// Routing (X6, X L216-220) and termination (X7, X L224-229).

struct RoutingParams {
  // c(e) = 1 / max(mean gain, min_gain): zero gain costs 1 / min_gain, not infinity.
  double min_gain = 1e-6;
  double termination_gain = 0.01;  // X L229
};

// Mean of point_gain along the polyline by arc length, (1/ℓ) ∫ I dp, trapezoidal on samples at
// most spacing_m apart; the point's value for a zero-length polyline, 0 for an empty one.
double MeanAlongPolyline(std::span<const Eigen::Vector2d> polyline,
                         const std::function<double(const Eigen::Vector2d&)>& point_gain,
                         double spacing_m = 0.1);

// Per edge: its mean gain (the planner's callback over the edge), and whether the robot's body
// fits along it (the planner's contact test).
using EdgeGainFn = std::function<double(const SkeletonEdge&)>;
using EdgeAccessibleFn = std::function<bool(const SkeletonEdge&)>;
std::vector<double> EdgeGains(const Skeleton& skeleton, const EdgeGainFn& gain);
std::vector<std::uint8_t> EdgeAccessibility(const Skeleton& skeleton,
                                            const EdgeAccessibleFn& accessible);

// The contact test with a clearance raster: every polyline segment keeps clearance ≥ radius_m
// (omt::SegmentClear).
bool EdgeClear(const SkeletonEdge& edge, const omt::ClearanceRaster& clearance, double radius_m);

// X's cost: the reciprocal of the mean gain, clamped.
inline double EdgeCost(double mean_gain, const RoutingParams& params = {}) {
  return 1.0 / std::max(mean_gain, params.min_gain);
}

// The routing root: the nearest trisector within docking_radius_m (the one the robot is at), else
// the nearest node; -1 for an empty graph.
int RoutingRoot(const Skeleton& skeleton, const Eigen::Vector2d& robot_m,
                double docking_radius_m = 0.5);

struct SpanningTree {
  int root = -1;
  std::vector<int> edges;        // in the order Prim adds them
  std::vector<int> parent_edge;  // per node: the tree edge towards the root; -1 root / unreached
  std::vector<int> order;        // nodes in the order reached, the root first
  double cost = 0.0;             // Σ of the tree edges' costs
};

// Prim's minimum spanning tree of the root's connected component over the usable edges (empty:
// all); ties go to the lower edge index. Self-loops are never tree edges.
SpanningTree MinimumSpanningTree(const Skeleton& skeleton, std::span<const double> edge_cost,
                                 int root, std::span<const std::uint8_t> usable = {});

// The branch choice at a trisector (X L195, L216): the tree rooted at the trisector splits into
// one subtree per tree edge at the root; a branch's value is the total expected gain of its
// subtree, Σ ℓ(e) × mean gain(e) = Σ ∫_e I dp over its edges (the first edge included). The
// chosen branch has the largest value (ties: the lower edge index), so the robot leaves along the
// branch with more unknown or uncertain space reachable through the tree; the MST's costs decide
// which edges belong to which branch.
struct BranchChoice {
  int edge = -1;       // the root's tree edge to leave along; -1: none has gain above 0
  int next_node = -1;  // its other end
  double departure_angle_rad = 0.0;   // the edge's direction leaving the root
  double value = 0.0;                 // the chosen branch's value
  std::vector<int> branch_edges;      // the root's tree edges, increasing
  std::vector<double> branch_values;  // parallel to branch_edges
  SpanningTree tree;
};
BranchChoice ChooseBranch(const Skeleton& skeleton, std::span<const double> edge_gain, int root,
                          std::span<const std::uint8_t> usable = {},
                          const RoutingParams& params = {});

struct TerminationCheck {
  bool done = true;  // every accessible edge's gain < termination_gain (true for no such edge)
  int accessible_edges = 0;
  int edges_above = 0;  // accessible edges at or above the threshold
  double max_accessible_gain = 0.0;
};
TerminationCheck CheckTermination(std::span<const double> edge_gain,
                                  std::span<const std::uint8_t> accessible,
                                  const RoutingParams& params = {});

}  // namespace voxplan::tensorfield
