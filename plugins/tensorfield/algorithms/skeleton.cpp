// Separatrix tracing, the skeleton graph, docking, Prim routing and termination (X L197-229,
// L312-314).
#include "plugins/tensorfield/algorithms/skeleton.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::tensorfield {
namespace {

double PolylineLength(std::span<const Eigen::Vector2d> polyline) {
  double length = 0.0;
  for (std::size_t i = 1; i < polyline.size(); ++i)
    length += (polyline[i] - polyline[i - 1]).norm();
  return length;
}

double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double DistanceToPolyline(const Eigen::Vector2d& p, std::span<const Eigen::Vector2d> polyline) {
  if (polyline.size() == 1) return (p - polyline[0]).norm();
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < polyline.size(); ++i) {
    best = std::min(best, DistanceToSegment(p, polyline[i - 1], polyline[i]));
  }
  return best;
}

// Mean distance of a's vertices to polyline b.
double MeanDistance(std::span<const Eigen::Vector2d> a, std::span<const Eigen::Vector2d> b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (const Eigen::Vector2d& p : a) sum += DistanceToPolyline(p, b);
  return sum / static_cast<double>(a.size());
}

SkeletonNodeKind KindOf(DegenerateType type) {
  return type == DegenerateType::kWedge ? SkeletonNodeKind::kWedge : SkeletonNodeKind::kTrisector;
}

// The edge's direction leaving `node`.
double DepartureAngle(const Skeleton& skeleton, int e, int node) {
  const SkeletonEdge& edge = skeleton.edges[static_cast<std::size_t>(e)];
  Eigen::Vector2d a, b;
  if (edge.polyline.size() >= 2) {
    const bool forward = edge.from == node;
    a = forward ? edge.polyline[0] : edge.polyline.back();
    b = forward ? edge.polyline[1] : edge.polyline[edge.polyline.size() - 2];
  } else {
    a = skeleton.nodes[static_cast<std::size_t>(node)].position_m;
    b = skeleton.nodes[static_cast<std::size_t>(skeleton.Other(e, node))].position_m;
  }
  const Eigen::Vector2d d = b - a;
  return std::atan2(d.y(), d.x());
}

}  // namespace

std::vector<int> Skeleton::IncidentEdges(int node) const {
  std::vector<int> out;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].from == node || edges[e].to == node) out.push_back(static_cast<int>(e));
  }
  return out;
}

Skeleton ExtractSkeleton(const TensorRaster& field, std::span<const DegeneratePoint> points,
                         const SkeletonParams& params, const AdvectionObstacles& obstacles) {
  Skeleton skeleton;
  for (std::size_t i = 0; i < points.size(); ++i) {
    SkeletonNode node;
    node.kind = KindOf(points[i].type);
    node.position_m = points[i].position_m;
    node.degenerate_index = static_cast<int>(i);
    skeleton.nodes.push_back(node);
  }
  AdvectionParams trace;
  trace.step_m = params.step_m;
  trace.max_length_m = params.max_length_m;
  trace.min_magnitude = params.min_relative_magnitude * MaxFieldMagnitude(field);
  trace.magnitude_check_after_m = params.capture_radius_m;
  trace.stop_outside_domain = params.stop_outside_domain;
  trace.wedge_capture_radius_m = params.capture_radius_m;
  trace.trisector_capture_radius_m = params.capture_radius_m;
  trace.arrive_radius_m = params.arrive_radius_m;
  trace.loop_radius_m = params.loop_radius_m;
  trace.loop_min_arc_m = params.loop_min_arc_m;
  trace.block_clearance_m = params.block_clearance_m;
  trace.wall_clearance_m = 0.0;
  trace.slowdown_distance_m = 0.0;  // no look-ahead beyond max_length_m

  for (std::size_t i = 0; i < points.size(); ++i) {
    for (double angle : points[i].separatrix_angles_rad) {
      const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
      const Eigen::Vector2d start = points[i].position_m + params.step_m * dir;
      const Pathline line = AdvectPathline(field, start, angle, points, trace, obstacles);
      ++skeleton.traced;
      if (line.points.empty()) continue;
      SkeletonEdge edge;
      edge.from = static_cast<int>(i);
      edge.from_angle_rad = angle;
      edge.polyline.push_back(points[i].position_m);
      for (const PathPoint& p : line.points) edge.polyline.push_back(p.position_m);
      if (line.stop_point >= 0) {
        edge.to = line.stop_point;
        edge.polyline.push_back(points[static_cast<std::size_t>(line.stop_point)].position_m);
      } else {
        const Eigen::Vector2d end = edge.polyline.back();
        int leaf = -1;
        for (std::size_t n = points.size(); n < skeleton.nodes.size(); ++n) {
          if ((skeleton.nodes[n].position_m - end).norm() <= params.leaf_merge_radius_m) {
            leaf = static_cast<int>(n);
            break;
          }
        }
        if (leaf < 0) {
          SkeletonNode node;
          node.kind = SkeletonNodeKind::kLeaf;
          node.position_m = end;
          node.end = line.stop;
          leaf = static_cast<int>(skeleton.nodes.size());
          skeleton.nodes.push_back(node);
        }
        edge.to = leaf;
      }
      edge.length_m = PolylineLength(edge.polyline);
      // Merge with an edge joining the same nodes along (nearly) the same curve.
      bool merged = false;
      for (SkeletonEdge& other : skeleton.edges) {
        const bool same = (other.from == edge.from && other.to == edge.to) ||
                          (other.from == edge.to && other.to == edge.from);
        if (!same) continue;
        if (MeanDistance(edge.polyline, other.polyline) <= params.merge_distance_m &&
            MeanDistance(other.polyline, edge.polyline) <= params.merge_distance_m) {
          ++other.merged;
          merged = true;
          break;
        }
      }
      if (!merged) skeleton.edges.push_back(std::move(edge));
    }
  }
  return skeleton;
}

std::optional<Docking> DetectDocking(std::span<const Eigen::Vector2d> positions,
                                     std::span<const DegeneratePoint> points,
                                     const DockingParams& params) {
  std::optional<Docking> best;
  if (positions.size() < 3) return best;
  for (std::size_t j = 0; j < points.size(); ++j) {
    if (points[j].type != DegenerateType::kTrisector) continue;
    double d_min = std::numeric_limits<double>::infinity();
    std::size_t k_min = 0;
    for (std::size_t k = 0; k < positions.size(); ++k) {
      const double d = (positions[k] - points[j].position_m).norm();
      if (d < d_min) {
        d_min = d;
        k_min = k;
      }
    }
    const double d_last = (positions.back() - points[j].position_m).norm();
    const bool docked = d_min <= params.radius_m && k_min > 0 && k_min + 1 < positions.size() &&
                        d_last >= d_min + params.leave_margin_m;
    if (docked && (!best || d_min < best->min_distance_m)) {
      best = Docking{static_cast<int>(j), static_cast<int>(k_min), d_min};
    }
  }
  return best;
}

double MeanAlongPolyline(std::span<const Eigen::Vector2d> polyline,
                         const std::function<double(const Eigen::Vector2d&)>& point_gain,
                         double spacing_m) {
  if (polyline.empty() || !point_gain) return 0.0;
  const double length = PolylineLength(polyline);
  if (length <= 0.0) return point_gain(polyline[0]);
  const double spacing = spacing_m > 0.0 ? spacing_m : length;
  double integral = 0.0;
  for (std::size_t i = 1; i < polyline.size(); ++i) {
    const Eigen::Vector2d a = polyline[i - 1], b = polyline[i];
    const double len = (b - a).norm();
    if (len <= 0.0) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    double previous = point_gain(a);
    for (int k = 1; k <= n; ++k) {
      const double value = point_gain(a + (b - a) * (static_cast<double>(k) / n));
      integral += 0.5 * (previous + value) * (len / n);
      previous = value;
    }
  }
  return integral / length;
}

std::vector<double> EdgeGains(const Skeleton& skeleton, const EdgeGainFn& gain) {
  std::vector<double> out;
  out.reserve(skeleton.edges.size());
  for (const SkeletonEdge& e : skeleton.edges) out.push_back(gain ? gain(e) : 0.0);
  return out;
}

std::vector<std::uint8_t> EdgeAccessibility(const Skeleton& skeleton,
                                            const EdgeAccessibleFn& accessible) {
  std::vector<std::uint8_t> out;
  out.reserve(skeleton.edges.size());
  for (const SkeletonEdge& e : skeleton.edges) out.push_back(!accessible || accessible(e) ? 1 : 0);
  return out;
}

bool EdgeClear(const SkeletonEdge& edge, const omt::ClearanceRaster& clearance, double radius_m) {
  if (edge.polyline.empty()) return false;
  if (edge.polyline.size() == 1) {
    return omt::ClearanceBilinear(clearance, edge.polyline[0]) >= radius_m;
  }
  for (std::size_t i = 1; i < edge.polyline.size(); ++i) {
    if (!omt::SegmentClear(clearance, edge.polyline[i - 1], edge.polyline[i], radius_m)) {
      return false;
    }
  }
  return true;
}

int RoutingRoot(const Skeleton& skeleton, const Eigen::Vector2d& robot_m, double docking_radius_m) {
  int nearest = -1, trisector = -1;
  double d_nearest = std::numeric_limits<double>::infinity();
  double d_trisector = std::numeric_limits<double>::infinity();
  for (std::size_t n = 0; n < skeleton.nodes.size(); ++n) {
    const double d = (skeleton.nodes[n].position_m - robot_m).norm();
    if (d < d_nearest) {
      d_nearest = d;
      nearest = static_cast<int>(n);
    }
    if (skeleton.nodes[n].kind == SkeletonNodeKind::kTrisector && d <= docking_radius_m &&
        d < d_trisector) {
      d_trisector = d;
      trisector = static_cast<int>(n);
    }
  }
  return trisector >= 0 ? trisector : nearest;
}

SpanningTree MinimumSpanningTree(const Skeleton& skeleton, std::span<const double> edge_cost,
                                 int root, std::span<const std::uint8_t> usable) {
  SpanningTree tree;
  const int n = static_cast<int>(skeleton.nodes.size());
  tree.parent_edge.assign(static_cast<std::size_t>(std::max(n, 0)), -1);
  if (root < 0 || root >= n) return tree;
  tree.root = root;
  std::vector<std::vector<int>> incident(static_cast<std::size_t>(n));
  for (std::size_t e = 0; e < skeleton.edges.size(); ++e) {
    const SkeletonEdge& edge = skeleton.edges[e];
    if (edge.from == edge.to) continue;
    if (!usable.empty() && usable[e] == 0) continue;
    if (edge.from < 0 || edge.to < 0 || edge.from >= n || edge.to >= n) continue;
    incident[static_cast<std::size_t>(edge.from)].push_back(static_cast<int>(e));
    incident[static_cast<std::size_t>(edge.to)].push_back(static_cast<int>(e));
  }
  std::vector<std::uint8_t> in_tree(static_cast<std::size_t>(n), 0);
  using Entry = std::tuple<double, int>;  // (cost, edge): ties to the lower edge index
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> frontier;
  auto add = [&](int node) {
    in_tree[static_cast<std::size_t>(node)] = 1;
    tree.order.push_back(node);
    for (int e : incident[static_cast<std::size_t>(node)]) {
      if (in_tree[static_cast<std::size_t>(skeleton.Other(e, node))] == 0) {
        frontier.emplace(edge_cost[static_cast<std::size_t>(e)], e);
      }
    }
  };
  add(root);
  while (!frontier.empty()) {
    const auto [cost, e] = frontier.top();
    frontier.pop();
    const SkeletonEdge& edge = skeleton.edges[static_cast<std::size_t>(e)];
    const bool from_in = in_tree[static_cast<std::size_t>(edge.from)] != 0;
    const bool to_in = in_tree[static_cast<std::size_t>(edge.to)] != 0;
    if (from_in && to_in) continue;
    const int next = from_in ? edge.to : edge.from;
    tree.edges.push_back(e);
    tree.parent_edge[static_cast<std::size_t>(next)] = e;
    tree.cost += cost;
    add(next);
  }
  return tree;
}

BranchChoice ChooseBranch(const Skeleton& skeleton, std::span<const double> edge_gain, int root,
                          std::span<const std::uint8_t> usable, const RoutingParams& params) {
  BranchChoice choice;
  std::vector<double> cost(edge_gain.size());
  for (std::size_t e = 0; e < edge_gain.size(); ++e) cost[e] = EdgeCost(edge_gain[e], params);
  choice.tree = MinimumSpanningTree(skeleton, cost, root, usable);
  if (choice.tree.root < 0) return choice;
  const SpanningTree& tree = choice.tree;
  // The branch (the root's tree edge) each node hangs from; parents are reached before children.
  std::vector<int> branch(skeleton.nodes.size(), -1);
  for (int node : tree.order) {
    if (node == root) continue;
    const int e = tree.parent_edge[static_cast<std::size_t>(node)];
    const int parent = skeleton.Other(e, node);
    branch[static_cast<std::size_t>(node)] =
        parent == root ? e : branch[static_cast<std::size_t>(parent)];
    if (parent == root) choice.branch_edges.push_back(e);
  }
  std::sort(choice.branch_edges.begin(), choice.branch_edges.end());
  choice.branch_values.assign(choice.branch_edges.size(), 0.0);
  for (int node : tree.order) {
    if (node == root) continue;
    const int e = tree.parent_edge[static_cast<std::size_t>(node)];
    const int b = branch[static_cast<std::size_t>(node)];
    const auto it = std::lower_bound(choice.branch_edges.begin(), choice.branch_edges.end(), b);
    const double gain = std::max(0.0, edge_gain[static_cast<std::size_t>(e)]);
    choice.branch_values[static_cast<std::size_t>(it - choice.branch_edges.begin())] +=
        skeleton.edges[static_cast<std::size_t>(e)].length_m * gain;
  }
  for (std::size_t k = 0; k < choice.branch_edges.size(); ++k) {
    if (choice.branch_values[k] > choice.value) {
      choice.value = choice.branch_values[k];
      choice.edge = choice.branch_edges[k];
    }
  }
  if (choice.edge >= 0) {
    choice.next_node = skeleton.Other(choice.edge, root);
    choice.departure_angle_rad = DepartureAngle(skeleton, choice.edge, root);
  }
  return choice;
}

TerminationCheck CheckTermination(std::span<const double> edge_gain,
                                  std::span<const std::uint8_t> accessible,
                                  const RoutingParams& params) {
  TerminationCheck check;
  for (std::size_t e = 0; e < edge_gain.size(); ++e) {
    if (!accessible.empty() && accessible[e] == 0) continue;
    ++check.accessible_edges;
    check.max_accessible_gain = std::max(check.max_accessible_gain, edge_gain[e]);
    if (edge_gain[e] >= params.termination_gain) ++check.edges_above;
  }
  check.done = check.edges_above == 0;
  return check;
}

}  // namespace voxplan::tensorfield
