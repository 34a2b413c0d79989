#include "plugins/tensorfield/algorithms/topology_control.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <vector>

namespace voxplan::tensorfield {
namespace {

// Dijkstra over the skeleton's edges (their polyline lengths) from node `from`.
std::vector<double> SkeletonDistances(const Skeleton& skeleton, int from) {
  std::vector<double> d(skeleton.nodes.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  d[static_cast<std::size_t>(from)] = 0.0;
  queue.push({0.0, from});
  while (!queue.empty()) {
    const auto [dist, node] = queue.top();
    queue.pop();
    if (dist > d[static_cast<std::size_t>(node)]) continue;
    for (const int e : skeleton.IncidentEdges(node)) {
      const int other = skeleton.Other(e, node);
      const double nd = dist + skeleton.edges[static_cast<std::size_t>(e)].length_m;
      if (nd < d[static_cast<std::size_t>(other)]) {
        d[static_cast<std::size_t>(other)] = nd;
        queue.push({nd, other});
      }
    }
  }
  return d;
}

}  // namespace

bool SmoothDisc(TensorRaster* field, const Eigen::Vector2d& centre_m, double radius_m, int sweeps,
                double min_relative_magnitude) {
  const omt::RasterGeometry& g = field->geometry;
  const double res = g.resolution_m;
  const int x0 = std::max(
      0, static_cast<int>(std::floor((centre_m.x() - radius_m - g.origin_m.x()) / res)) - 1);
  const int y0 = std::max(
      0, static_cast<int>(std::floor((centre_m.y() - radius_m - g.origin_m.y()) / res)) - 1);
  const int x1 =
      std::min(g.width - 1,
               static_cast<int>(std::ceil((centre_m.x() + radius_m - g.origin_m.x()) / res)) + 1);
  const int y1 =
      std::min(g.height - 1,
               static_cast<int>(std::ceil((centre_m.y() + radius_m - g.origin_m.y()) / res)) + 1);
  if (x1 - x0 < 2 || y1 - y0 < 2) return false;
  const auto inside = [&](int x, int y) {
    return x > 0 && y > 0 && x + 1 < g.width && y + 1 < g.height &&
           (g.Center(x, y) - centre_m).norm() <= radius_m;
  };
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        if (!inside(x, y)) continue;
        const std::size_t i = static_cast<std::size_t>(g.Index(x, y));
        const std::size_t l = i - 1, r = i + 1, d = i - static_cast<std::size_t>(g.width),
                          u = i + static_cast<std::size_t>(g.width);
        field->tau11[i] =
            0.25 * (field->tau11[l] + field->tau11[r] + field->tau11[d] + field->tau11[u]);
        field->tau12[i] =
            0.25 * (field->tau12[l] + field->tau12[r] + field->tau12[d] + field->tau12[u]);
      }
  // The disc's bounding box as its own raster: no degenerate point may be left in the disc. The
  // flat rule is relative to the whole field's largest magnitude.
  double top = 0.0;
  for (int i = 0; i < g.NumCells(); ++i)
    if (field->InDomain(i)) top = std::max(top, field->At(i).norm());
  omt::RasterGeometry crop;
  crop.width = x1 - x0 + 1;
  crop.height = y1 - y0 + 1;
  crop.resolution_m = res;
  crop.origin_m = g.origin_m + res * Eigen::Vector2d(x0, y0);
  TensorRaster local = MakeTensorRaster(crop);
  double local_top = 0.0;
  for (int y = 0; y < crop.height; ++y)
    for (int x = 0; x < crop.width; ++x) {
      const int s = g.Index(x0 + x, y0 + y);
      const std::size_t t = static_cast<std::size_t>(crop.Index(x, y));
      local.tau11[t] = field->tau11[static_cast<std::size_t>(s)];
      local.tau12[t] = field->tau12[static_cast<std::size_t>(s)];
      local_top = std::max(local_top, field->At(s).norm());
    }
  TopologyParams tp;
  tp.min_relative_magnitude = local_top > 0.0 ? min_relative_magnitude * top / local_top : 0.0;
  for (const DegeneratePoint& p : FindDegeneratePoints(local, tp))
    if ((p.position_m - centre_m).norm() <= radius_m + res) return false;
  return true;
}

PairCancelResult CancelDegeneratePairs(TensorRaster* field, std::span<const DegeneratePoint> points,
                                       const Skeleton& skeleton,
                                       const omt::ClearanceRaster& clearance,
                                       const PairCancelParams& params) {
  PairCancelResult result;
  struct Pair {
    double ds;
    int wedge, trisector;
  };
  std::vector<Pair> pairs;
  const int n = static_cast<int>(points.size());
  const auto lfs = [&](int i) {
    return static_cast<double>(clearance.AtPoint(points[static_cast<std::size_t>(i)].position_m));
  };
  for (int w = 0; w < n; ++w) {
    if (points[static_cast<std::size_t>(w)].type != DegenerateType::kWedge) continue;
    std::vector<double> ds;  // computed only when some trisector is near enough (d_s ≥ |pW - pT|)
    for (int t = 0; t < n; ++t) {
      if (points[static_cast<std::size_t>(t)].type != DegenerateType::kTrisector) continue;
      const double bound = lfs(w) + lfs(t);
      const double euclid = (points[static_cast<std::size_t>(w)].position_m -
                             points[static_cast<std::size_t>(t)].position_m)
                                .norm();
      if (euclid >= bound || static_cast<std::size_t>(std::max(w, t)) >= skeleton.nodes.size())
        continue;
      if (ds.empty()) ds = SkeletonDistances(skeleton, w);
      if (ds[static_cast<std::size_t>(t)] < bound)
        pairs.push_back({ds[static_cast<std::size_t>(t)], w, t});  // eq. 6
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const Pair& a, const Pair& b) { return a.ds < b.ds; });
  result.candidates = static_cast<int>(pairs.size());
  std::vector<std::uint8_t> used(points.size(), 0);
  for (const Pair& pair : pairs) {
    if (used[static_cast<std::size_t>(pair.wedge)] ||
        used[static_cast<std::size_t>(pair.trisector)])
      continue;
    const Eigen::Vector2d a = points[static_cast<std::size_t>(pair.wedge)].position_m;
    const Eigen::Vector2d b = points[static_cast<std::size_t>(pair.trisector)].position_m;
    const std::vector<double> tau11 = field->tau11, tau12 = field->tau12;
    bool ok = false;
    for (int round = 1; round <= params.rounds && !ok; ++round)
      ok = SmoothDisc(field, 0.5 * (a + b), 0.5 * (a - b).norm() + round * params.margin_m,
                      params.sweeps, params.min_relative_magnitude);
    if (!ok) {  // topologically significant after all: leave the field as it was
      field->tau11 = tau11;
      field->tau12 = tau12;
      continue;
    }
    used[static_cast<std::size_t>(pair.wedge)] = used[static_cast<std::size_t>(pair.trisector)] = 1;
    ++result.cancelled;
  }
  return result;
}

}  // namespace voxplan::tensorfield
