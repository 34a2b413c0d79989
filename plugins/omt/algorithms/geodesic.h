// Geodesic distances and shortest paths for the planner (γ of eq. 4, the TSP graph of §3.5)
// on a coarse 8-connected grid over the clearance raster. A node is traversable when its
// clearance exceeds the robot radius by half a diagonal step (and half a fine cell): clearance is
// 1-Lipschitz, so every edge between traversable nodes keeps the robot radius free.
#pragma once

#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

struct GeodesicGrid {
  RasterGeometry fine;  // the clearance raster's geometry
  int factor = 1;       // fine cells per coarse cell side
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> traversable;
  double step_m = 0.0;  // distance between 4-neighbour nodes

  int NumNodes() const { return width * height; }
  // Node positions are fine-cell centres, exactly step_m apart.
  Eigen::Vector2d Position(int node) const {
    const int cx = node % width;
    const int cy = node / width;
    return fine.Center(cx * factor + factor / 2, cy * factor + factor / 2);
  }
};

GeodesicGrid BuildGeodesicGrid(const ClearanceRaster& clearance, double cell_m,
                               double robot_radius_m);

// A world point joined to the grid by a collision-free straight segment.
struct Anchor {
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  int node = -1;  // -1: the point cannot be joined (inaccessible)
  double offset_m = 0.0;
};
// Nearest traversable node within search_nodes grid steps whose segment to p_m is clear.
Anchor AnchorPoint(const GeodesicGrid& grid, const ClearanceRaster& clearance,
                   const Eigen::Vector2d& p_m, double robot_radius_m, int search_nodes = 3);

struct ShortestPaths {
  std::vector<float> dist_m;  // infinity where unreachable
  std::vector<int> parent;    // -1 at the source and unreachable nodes
};
// Shortest paths from source. With targets (one byte per node, non-zero = wanted, their
// number in num_targets) the search stops once all of them are settled: their distances and
// parent chains are then exact, other nodes may hold tentative values.
void Dijkstra(const GeodesicGrid& grid, int source, ShortestPaths* out,
              const std::vector<std::uint8_t>* targets = nullptr, int num_targets = 0);

// Flood fill from the sources: traversable nodes reachable by some source.
std::vector<std::uint8_t> ReachableNodes(const GeodesicGrid& grid, const std::vector<int>& sources);

// Polyline from anchor `from` (the source of paths) to anchor `to`; empty if unreachable.
std::vector<Eigen::Vector2d> ExtractPath(const GeodesicGrid& grid, const ShortestPaths& paths,
                                         const Anchor& from, const Anchor& to);

}  // namespace voxplan::omt
