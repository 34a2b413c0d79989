#include "plugins/tensorfield/algorithms/topology_control.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
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

// A disc's bounding box of cells, one cell beyond it where the raster allows.
struct Box {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

std::optional<Box> DiscBox(const omt::RasterGeometry& g, const Eigen::Vector2d& centre_m,
                           double radius_m) {
  const double res = g.resolution_m;
  Box b;
  b.x0 = std::max(
      0, static_cast<int>(std::floor((centre_m.x() - radius_m - g.origin_m.x()) / res)) - 1);
  b.y0 = std::max(
      0, static_cast<int>(std::floor((centre_m.y() - radius_m - g.origin_m.y()) / res)) - 1);
  b.x1 =
      std::min(g.width - 1,
               static_cast<int>(std::ceil((centre_m.x() + radius_m - g.origin_m.x()) / res)) + 1);
  b.y1 =
      std::min(g.height - 1,
               static_cast<int>(std::ceil((centre_m.y() + radius_m - g.origin_m.y()) / res)) + 1);
  if (b.x1 - b.x0 < 2 || b.y1 - b.y0 < 2) return std::nullopt;
  return b;
}

// A cell whose centre lies in the disc and that has all four neighbours in the raster.
bool InDisc(const omt::RasterGeometry& g, int x, int y, const Eigen::Vector2d& centre_m,
            double radius_m) {
  return x > 0 && y > 0 && x + 1 < g.width && y + 1 < g.height &&
         (g.Center(x, y) - centre_m).norm() <= radius_m;
}

// Gauss-Seidel sweeps of the 4-neighbour Laplacian of τ11 and τ12 over the box's cells that
// `update` accepts (each with four neighbours in the raster); the rest hold their values.
template <class Update>
void Relax(TensorRaster* field, const Box& b, int sweeps, const Update& update) {
  const omt::RasterGeometry& g = field->geometry;
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (int y = b.y0; y <= b.y1; ++y)
      for (int x = b.x0; x <= b.x1; ++x) {
        if (!update(x, y)) continue;
        const std::size_t i = static_cast<std::size_t>(g.Index(x, y));
        const std::size_t l = i - 1, r = i + 1, d = i - static_cast<std::size_t>(g.width),
                          u = i + static_cast<std::size_t>(g.width);
        field->tau11[i] =
            0.25 * (field->tau11[l] + field->tau11[r] + field->tau11[d] + field->tau11[u]);
        field->tau12[i] =
            0.25 * (field->tau12[l] + field->tau12[r] + field->tau12[d] + field->tau12[u]);
      }
}

// The degenerate points near_point accepts, found on the box as its own raster (with the field's
// domain when use_domain, else every loop), cell_x and cell_y the field's. The flat rule is
// relative to the whole field's largest magnitude.
template <class Near>
std::vector<DegeneratePoint> PointsIn(const TensorRaster& field, const Box& b,
                                      const Near& near_point, double min_relative_magnitude,
                                      bool use_domain) {
  const omt::RasterGeometry& g = field.geometry;
  const double res = g.resolution_m;
  double top = 0.0;
  for (int i = 0; i < g.NumCells(); ++i)
    if (field.InDomain(i)) top = std::max(top, field.At(i).norm());
  omt::RasterGeometry crop;
  crop.width = b.x1 - b.x0 + 1;
  crop.height = b.y1 - b.y0 + 1;
  crop.resolution_m = res;
  crop.origin_m = g.origin_m + res * Eigen::Vector2d(b.x0, b.y0);
  TensorRaster local = MakeTensorRaster(crop);
  if (use_domain && !field.domain.empty())
    local.domain.assign(static_cast<std::size_t>(crop.NumCells()), 0);
  double local_top = 0.0;
  for (int y = 0; y < crop.height; ++y)
    for (int x = 0; x < crop.width; ++x) {
      const int s = g.Index(b.x0 + x, b.y0 + y);
      const std::size_t t = static_cast<std::size_t>(crop.Index(x, y));
      local.tau11[t] = field.tau11[static_cast<std::size_t>(s)];
      local.tau12[t] = field.tau12[static_cast<std::size_t>(s)];
      if (!local.domain.empty()) local.domain[t] = field.InDomain(s) ? 1 : 0;
      local_top = std::max(local_top, field.At(s).norm());
    }
  TopologyParams tp;
  tp.min_relative_magnitude = local_top > 0.0 ? min_relative_magnitude * top / local_top : 0.0;
  std::vector<DegeneratePoint> near;
  for (DegeneratePoint& p : FindDegeneratePoints(local, tp)) {
    if (!near_point(p.position_m)) continue;
    p.cell_x += b.x0;
    p.cell_y += b.y0;
    near.push_back(std::move(p));
  }
  return near;
}

double ClearanceAt(const omt::ClearanceRaster& clearance, const Eigen::Vector2d& p_m) {
  return static_cast<double>(clearance.AtPoint(p_m));
}

// (b): the point retract_m along the end separatrix from the wedge (node), stopping
// retract_keep_m short of its other end; none when that leaves less than two steps.
std::optional<Eigen::Vector2d> RetractTarget(const SkeletonEdge& edge, int node,
                                             const PointMovesParams& params) {
  const double distance = std::min(params.retract_m, edge.length_m - params.retract_keep_m);
  if (!(distance >= 2.0 * params.step_m) || edge.polyline.size() < 2) return std::nullopt;
  std::vector<Eigen::Vector2d> line = edge.polyline;
  if (edge.from != node) std::reverse(line.begin(), line.end());
  double walked = 0.0;
  for (std::size_t k = 1; k < line.size(); ++k) {
    const double segment = (line[k] - line[k - 1]).norm();
    if (walked + segment >= distance && segment > 0.0)
      return line[k - 1] + (distance - walked) / segment * (line[k] - line[k - 1]);
    walked += segment;
  }
  return std::nullopt;
}

// (a): a wedge whose two nearest separatrices meet at less than the angle is moved along their
// bisector towards the obstacle it faces (the side where the clearance falls), to the first step
// where the robot's centre cannot reach it; none when no obstacle is that near along it.
std::optional<Eigen::Vector2d> CornerTarget(const DegeneratePoint& wedge,
                                            const omt::ClearanceRaster& clearance, double res,
                                            const PointMovesParams& params) {
  const std::vector<double>& a = wedge.separatrix_angles_rad;  // increasing, in [0, 2π)
  if (a.size() < 2) return std::nullopt;
  double gap = std::numeric_limits<double>::infinity(), bisector = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double next = k + 1 < a.size() ? a[k + 1] : a[0] + 2.0 * M_PI;
    if (next - a[k] < gap) {
      gap = next - a[k];
      bisector = a[k] + 0.5 * gap;
    }
  }
  if (!(gap < params.corner_max_angle_rad)) return std::nullopt;
  const Eigen::Vector2d p = wedge.position_m;
  const double c0 = ClearanceAt(clearance, p);
  if (c0 < params.robot_radius_m || c0 > params.corner_max_move_m + params.robot_radius_m)
    return std::nullopt;
  Eigen::Vector2d u(std::cos(bisector), std::sin(bisector));
  constexpr double kProbeM = 0.2;
  if (ClearanceAt(clearance, p + kProbeM * u) > ClearanceAt(clearance, p - kProbeM * u)) u = -u;
  for (double d = params.step_m; d <= params.corner_max_move_m + 1e-9; d += params.step_m) {
    const Eigen::Vector2d q = p + d * u;
    const double c = ClearanceAt(clearance, q);
    if (c < 2.0 * res) return std::nullopt;  // at the wall first: no loop of free cells there
    if (c < params.robot_radius_m) return q;
  }
  return std::nullopt;
}

// (c)'s collision test: the trisector (node of skeleton) stands closer to an obstacle than the
// robot's radius, or one of its separatrices ends blocked within trisector_check_m.
bool TrisectorBlocked(const DegeneratePoint& trisector, int node, const Skeleton& skeleton,
                      const omt::ClearanceRaster& clearance, const PointMovesParams& params) {
  if (ClearanceAt(clearance, trisector.position_m) < params.robot_radius_m) return true;
  if (node < 0 || static_cast<std::size_t>(node) >= skeleton.nodes.size()) return false;
  for (const int e : skeleton.IncidentEdges(node)) {
    const SkeletonNode& end = skeleton.nodes[static_cast<std::size_t>(skeleton.Other(e, node))];
    if (end.kind == SkeletonNodeKind::kLeaf && end.end == AdvectionStop::kBlocked &&
        skeleton.edges[static_cast<std::size_t>(e)].length_m <= params.trisector_check_m)
      return true;
  }
  return false;
}

// (c): up the clearance from the trisector in steps of 2 step_m; the first target where the moved
// trisector and its separatrices are clear. False when none is within trisector_max_move_m.
bool MoveTrisectorClear(TensorRaster* field, const DegeneratePoint& trisector,
                        const omt::ClearanceRaster& clearance, const PointMovesParams& params) {
  const double h = 2.0 * clearance.geometry.resolution_m, step = 2.0 * params.step_m;
  SkeletonParams trace = params.trace;
  trace.max_length_m = std::min(trace.max_length_m, params.trisector_check_m);
  AdvectionObstacles obstacles;
  obstacles.clearance = &clearance;
  Eigen::Vector2d q = trisector.position_m;
  for (double moved = step; moved <= params.trisector_max_move_m + 1e-9; moved += step) {
    const Eigen::Vector2d grad(ClearanceAt(clearance, q + Eigen::Vector2d(h, 0)) -
                                   ClearanceAt(clearance, q - Eigen::Vector2d(h, 0)),
                               ClearanceAt(clearance, q + Eigen::Vector2d(0, h)) -
                                   ClearanceAt(clearance, q - Eigen::Vector2d(0, h)));
    if (!(grad.norm() > 0.0)) return false;  // a clearance plateau or maximum: nowhere better
    q += step * grad.normalized();
    if (ClearanceAt(clearance, q) < params.robot_radius_m) continue;
    TensorRaster trial = *field;
    DegeneratePoint moved_point;
    if (!MoveDegeneratePoint(&trial, trisector, q, params.move, &moved_point)) continue;
    const DegeneratePoint one[] = {moved_point};
    const Skeleton own = ExtractSkeleton(trial, one, trace, obstacles);
    if (TrisectorBlocked(moved_point, 0, own, clearance, params)) continue;
    *field = std::move(trial);
    return true;
  }
  return false;
}

}  // namespace

bool SmoothDisc(TensorRaster* field, const Eigen::Vector2d& centre_m, double radius_m, int sweeps,
                double min_relative_magnitude) {
  const omt::RasterGeometry& g = field->geometry;
  const std::optional<Box> box = DiscBox(g, centre_m, radius_m);
  if (!box) return false;
  Relax(field, *box, sweeps, [&](int x, int y) { return InDisc(g, x, y, centre_m, radius_m); });
  // No degenerate point may be left in the disc, domain or not.
  const double res = g.resolution_m;
  const auto near = [&](const Eigen::Vector2d& p) {
    return (p - centre_m).norm() <= radius_m + res;
  };
  return PointsIn(*field, *box, near, min_relative_magnitude, false).empty();
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

bool MoveDegeneratePoint(TensorRaster* field, const DegeneratePoint& point,
                         const Eigen::Vector2d& target_m, const PointMoveParams& params,
                         DegeneratePoint* moved_out) {
  const omt::RasterGeometry& g = field->geometry;
  const double res = g.resolution_m;
  const Eigen::Vector2d a = point.position_m, ab = target_m - point.position_m;
  if (!(params.inner_m >= 0.0 && params.outer_m > params.inner_m)) return false;
  const auto segment_distance = [&](const Eigen::Vector2d& p) {
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (p - a - s * ab).norm();
  };
  const std::optional<Box> box = DiscBox(g, a + 0.5 * ab, 0.5 * ab.norm() + params.outer_m);
  if (!box) return false;
  const auto near = [&](const Eigen::Vector2d& p) {
    return segment_distance(p) <= params.outer_m + res;
  };
  const std::vector<DegeneratePoint> before =
      PointsIn(*field, *box, near, params.min_relative_magnitude, true);
  if (before.size() != 1 || before[0].type != point.type || (before[0].position_m - a).norm() > res)
    return false;  // not alone (or not where it was said to be)

  using Complex = std::complex<double>;
  const bool wedge = point.type == DegenerateType::kWedge;
  const Complex z_p(a.x(), a.y()), z_t(target_m.x(), target_m.y());
  const std::vector<double> tau11 = field->tau11, tau12 = field->tau12;
  for (int y = box->y0; y <= box->y1; ++y)
    for (int x = box->x0; x <= box->x1; ++x) {
      const Eigen::Vector2d c = g.Center(x, y);
      const double rho = segment_distance(c);
      if (rho >= params.outer_m) continue;
      const Complex z(c.x(), c.y());
      if (std::abs(z - z_p) < 1e-12) continue;  // the old zero itself: V is 0 there
      Complex f = (z - z_t) / (z - z_p);
      if (!wedge) f = std::conj(f);
      // f's principal logarithm is cut along the segment only, where w = 1 and f^w = f.
      const double s =
          std::clamp((params.outer_m - rho) / (params.outer_m - params.inner_m), 0.0, 1.0);
      const double w = s * s * (3.0 - 2.0 * s);
      const Complex factor = w >= 1.0 ? f : (std::abs(f) > 0.0 ? std::exp(w * std::log(f)) : f);
      const std::size_t i = static_cast<std::size_t>(g.Index(x, y));
      const Complex v = Complex(field->tau11[i], field->tau12[i]) * factor;
      field->tau11[i] = v.real();
      field->tau12[i] = v.imag();
    }
  const std::vector<DegeneratePoint> after =
      PointsIn(*field, *box, near, params.min_relative_magnitude, true);
  if (after.size() != 1 || after[0].type != point.type ||
      (after[0].position_m - target_m).norm() > res) {
    field->tau11 = tau11;
    field->tau12 = tau12;
    return false;
  }
  if (moved_out) *moved_out = after[0];
  return true;
}

PointMovesResult MoveDegeneratePoints(TensorRaster* field, std::span<const DegeneratePoint> points,
                                      const Skeleton& skeleton,
                                      const omt::ClearanceRaster& clearance,
                                      const ExhaustedEndFn& exhausted,
                                      const PointMovesParams& params) {
  PointMovesResult result;
  const double res = field->geometry.resolution_m;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const DegeneratePoint& p = points[i];
    const int node = static_cast<int>(i);
    if (p.type == DegenerateType::kTrisector) {
      if (!TrisectorBlocked(p, node, skeleton, clearance, params)) continue;
      if (MoveTrisectorClear(field, p, clearance, params))
        ++result.moved_trisectors;
      else
        ++result.failed;
      continue;
    }
    std::optional<Eigen::Vector2d> target;
    bool retract = false;
    if (exhausted && i < skeleton.nodes.size()) {
      const std::vector<int> incident = skeleton.IncidentEdges(node);
      const SkeletonEdge* edge =
          incident.size() == 1 ? &skeleton.edges[static_cast<std::size_t>(incident[0])] : nullptr;
      if (edge && edge->from != edge->to && exhausted(p, *edge)) {
        target = RetractTarget(*edge, node, params);
        retract = target.has_value();
      }
    }
    if (!target) target = CornerTarget(p, clearance, res, params);
    if (!target) continue;
    if (!MoveDegeneratePoint(field, p, *target, params.move))
      ++result.failed;
    else
      ++(retract ? result.retracted_wedges : result.corner_wedges);
  }
  return result;
}

}  // namespace voxplan::tensorfield
