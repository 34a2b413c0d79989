#include "plugins/omt/algorithms/geodesic.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::omt {

GeodesicGrid BuildGeodesicGrid(const ClearanceRaster& clearance, double cell_m,
                               double robot_radius_m) {
  GeodesicGrid grid;
  grid.fine = clearance.geometry;
  const double res = grid.fine.resolution_m;
  grid.factor = std::max(1, static_cast<int>(std::lround(cell_m / res)));
  grid.width = grid.fine.width / grid.factor;
  grid.height = grid.fine.height / grid.factor;
  grid.step_m = grid.factor * res;
  // Half a diagonal step plus half a fine cell: SegmentClear samples the nearest fine cell, so
  // edges then pass SegmentClear(robot_radius_m) too.
  const double needed = robot_radius_m + 0.5 * std::sqrt(2.0) * (grid.step_m + res);
  grid.traversable.assign(static_cast<std::size_t>(grid.NumNodes()), 0);
  for (int cy = 0; cy < grid.height; ++cy) {
    for (int cx = 0; cx < grid.width; ++cx) {
      const int fine =
          grid.fine.Index(cx * grid.factor + grid.factor / 2, cy * grid.factor + grid.factor / 2);
      grid.traversable[static_cast<std::size_t>(cy * grid.width + cx)] =
          clearance.At(fine) >= needed ? 1 : 0;
    }
  }
  return grid;
}

Anchor AnchorPoint(const GeodesicGrid& grid, const ClearanceRaster& clearance,
                   const Eigen::Vector2d& p_m, double robot_radius_m, int search_nodes) {
  Anchor a;
  a.point_m = p_m;
  if (grid.NumNodes() == 0) return a;
  const Eigen::Vector2d q = (p_m - grid.fine.origin_m) / grid.step_m;
  const int px = static_cast<int>(std::floor(q.x()));
  const int py = static_cast<int>(std::floor(q.y()));
  std::vector<std::pair<double, int>> candidates;
  for (int cy = py - search_nodes; cy <= py + search_nodes; ++cy) {
    for (int cx = px - search_nodes; cx <= px + search_nodes; ++cx) {
      if (cx < 0 || cy < 0 || cx >= grid.width || cy >= grid.height) continue;
      const int node = cy * grid.width + cx;
      if (!grid.traversable[static_cast<std::size_t>(node)]) continue;
      candidates.emplace_back((grid.Position(node) - p_m).norm(), node);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  for (const auto& [d, node] : candidates) {
    if (SegmentClear(clearance, p_m, grid.Position(node), robot_radius_m)) {
      a.node = node;
      a.offset_m = d;
      return a;
    }
  }
  return a;
}

void Dijkstra(const GeodesicGrid& grid, int source, ShortestPaths* out,
              const std::vector<std::uint8_t>* targets, int num_targets) {
  const int n = grid.NumNodes();
  out->dist_m.assign(static_cast<std::size_t>(n), std::numeric_limits<float>::infinity());
  out->parent.assign(static_cast<std::size_t>(n), -1);
  if (source < 0 || source >= n) return;
  const int w = grid.width;
  const float straight = static_cast<float>(grid.step_m);
  const float diagonal = static_cast<float>(grid.step_m * std::sqrt(2.0));
  static constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  using Item = std::pair<float, int>;  // (distance, node): ties resolve by node index
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  out->dist_m[static_cast<std::size_t>(source)] = 0.0f;
  heap.emplace(0.0f, source);
  while (!heap.empty()) {
    const auto [d, u] = heap.top();
    heap.pop();
    if (d > out->dist_m[static_cast<std::size_t>(u)]) continue;
    if (targets && (*targets)[static_cast<std::size_t>(u)] && --num_targets == 0) break;
    const int ux = u % w;
    const int uy = u / w;
    for (int k = 0; k < 8; ++k) {
      const int vx = ux + kDx[k];
      const int vy = uy + kDy[k];
      if (vx < 0 || vy < 0 || vx >= w || vy >= grid.height) continue;
      const int v = vy * w + vx;
      if (!grid.traversable[static_cast<std::size_t>(v)]) continue;
      // Diagonal moves must not cut a blocked corner.
      if (k >= 4 && (!grid.traversable[static_cast<std::size_t>(uy * w + vx)] ||
                     !grid.traversable[static_cast<std::size_t>(vy * w + ux)]))
        continue;
      const float nd = d + (k < 4 ? straight : diagonal);
      if (nd < out->dist_m[static_cast<std::size_t>(v)]) {
        out->dist_m[static_cast<std::size_t>(v)] = nd;
        out->parent[static_cast<std::size_t>(v)] = u;
        heap.emplace(nd, v);
      }
    }
  }
}

std::vector<std::uint8_t> ReachableNodes(const GeodesicGrid& grid,
                                         const std::vector<int>& sources) {
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(grid.NumNodes()), 0);
  std::vector<int> stack;
  for (int s : sources) {
    if (s < 0 || seen[static_cast<std::size_t>(s)]) continue;
    seen[static_cast<std::size_t>(s)] = 1;
    stack.push_back(s);
  }
  while (!stack.empty()) {
    const int u = stack.back();
    stack.pop_back();
    const int ux = u % grid.width;
    const int uy = u / grid.width;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int vx = ux + dx;
        const int vy = uy + dy;
        if ((dx == 0 && dy == 0) || vx < 0 || vy < 0 || vx >= grid.width || vy >= grid.height)
          continue;
        const int v = vy * grid.width + vx;
        if (seen[static_cast<std::size_t>(v)] || !grid.traversable[static_cast<std::size_t>(v)])
          continue;
        if (dx != 0 && dy != 0 &&
            (!grid.traversable[static_cast<std::size_t>(uy * grid.width + vx)] ||
             !grid.traversable[static_cast<std::size_t>(vy * grid.width + ux)]))
          continue;
        seen[static_cast<std::size_t>(v)] = 1;
        stack.push_back(v);
      }
    }
  }
  return seen;
}

std::vector<Eigen::Vector2d> ExtractPath(const GeodesicGrid& grid, const ShortestPaths& paths,
                                         const Anchor& from, const Anchor& to) {
  std::vector<Eigen::Vector2d> out;
  if (from.node < 0 || to.node < 0) return out;
  if (!std::isfinite(paths.dist_m[static_cast<std::size_t>(to.node)])) return out;
  std::vector<int> nodes;
  for (int v = to.node; v >= 0; v = paths.parent[static_cast<std::size_t>(v)]) nodes.push_back(v);
  std::reverse(nodes.begin(), nodes.end());
  auto push = [&](const Eigen::Vector2d& p) {
    if (out.empty() || (out.back() - p).squaredNorm() > 1e-12) out.push_back(p);
  };
  push(from.point_m);
  for (int v : nodes) push(grid.Position(v));
  push(to.point_m);
  return out;
}

}  // namespace voxplan::omt
