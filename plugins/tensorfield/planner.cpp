// One robot's tensorfield plan step: key frames and sub-steps, advection, wedge and trisector
// handling, routing, the frontier fallback and termination (camera: planner_camera.cpp).
#include "plugins/tensorfield/planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/tensorfield/gain.h"
#include "plugins/tensorfield/harmonic.h"
#include "plugins/tensorfield/potential_info.h"

namespace voxplan::tensorfield {
namespace {

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

double PolylineLength(std::span<const Eigen::Vector2d> line) {
  double s = 0.0;
  for (std::size_t i = 1; i < line.size(); ++i) s += (line[i] - line[i - 1]).norm();
  return s;
}

// Settled frontier goals: cells this close to a goal the robot reached.
constexpr double kSettleRadiusM = 0.6;
// Fallback targets: traversable cells this close to an unsettled frontier cell.
constexpr double kApproachM = 0.4;
// A route is finished when less than this of it is left.
constexpr double kRouteDoneM = 0.15;
// A degenerate point the robot has just routed from is not routed from again for this long.
constexpr double kBranchHoldS = 20.0;

}  // namespace

bool RobotPlanner::Traversable(const Eigen::Vector2d& p, double radius_m) const {
  const int c = window_.geometry.IndexOf(p);
  if (c < 0) return false;
  const std::uint8_t code = window_.codes[static_cast<std::size_t>(c)];
  return (code == kFloorFree || code == kFloorFrontier) && window_.clearance.At(c) >= radius_m;
}

std::vector<Eigen::Vector2d> RobotPlanner::TraversablePrefix(
    const std::vector<Eigen::Vector2d>& line, double radius_m) const {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < line.size(); ++i) {
    // Check the segment into point i at half-cell steps.
    if (i > 0) {
      const Eigen::Vector2d a = line[i - 1], b = line[i];
      const int steps = std::max(
          1, static_cast<int>(std::ceil((b - a).norm() / (0.5 * window_.geometry.resolution_m))));
      bool ok = true;
      for (int k = 1; k <= steps && ok; ++k)
        ok = Traversable(a + (b - a) * (double(k) / steps), radius_m);
      if (!ok) break;
    }
    out.push_back(line[i]);
  }
  return out;
}

RobotPlanner::Key RobotPlanner::KeyOf(const omt::RasterGeometry& g, int cell) const {
  const Eigen::Vector2d c = g.Center(cell) / g.resolution_m;
  return {static_cast<long>(std::floor(c.x())), static_cast<long>(std::floor(c.y()))};
}

bool RobotPlanner::Settled(const FloorInput& floor, int cell) const {
  return !settled_.empty() && settled_.count(KeyOf(floor.geometry, cell)) > 0;
}

bool RobotPlanner::Stuck() const {
  const std::size_t n = static_cast<std::size_t>(options_.stuck_calls);
  if (history_.size() <= n) return false;
  return (history_.back() - history_[history_.size() - 1 - n]).norm() < options_.stuck_m;
}

SkeletonParams RobotPlanner::SkeletonFor(const RobotInput& robot) const {
  SkeletonParams sp;
  sp.min_relative_magnitude = 1e-5;
  sp.block_clearance_m = robot.radius_m;
  sp.max_length_m = 2.0 * options_.window_m;
  return sp;
}

void RobotPlanner::BuildKeyFrame(const FloorInput& floor, const RobotInput& robot, double t_s,
                                 StepOutput* out) {
  const double t0 = NowMs();
  key_centre_ = robot.position_m;
  window_ = CropFloor(floor, key_centre_, options_.window_m);
  const KeyFrameParams kp;
  std::vector<BoundarySample> samples;
  TensorRaster next = WindowKeyFrame(window_, kp, options_.fill, &samples, options_.field);
  const double t1 = NowMs();
  // The census of X Fig. 2 from the same constraints (diagnostics only; the planner drives the
  // filled field).
  {
    const FieldCensus census = CountFieldCensus(
        window_.geometry, samples, FieldDomain(window_.raster, kp.include_unknown), kp);
    out->diag.census_degenerate = census.degenerate_points;
    out->diag.census_vector = census.vector_singularities;
  }
  const double t_control = NowMs();
  if (options_.topology_control && options_.field == FieldKind::kTensor) {
    // X8 (d) on the key frame, before the frames between key frames are interpolated from it.
    TopologyParams tp;
    tp.min_relative_magnitude = 1e-5;
    const std::vector<DegeneratePoint> points = FindDegeneratePoints(next, tp);
    AdvectionObstacles obstacles;
    obstacles.clearance = &window_.clearance;
    const Skeleton skeleton = ExtractSkeleton(next, points, SkeletonFor(robot), obstacles);
    const int cancelled =
        CancelDegeneratePairs(&next, points, skeleton, window_.clearance).cancelled;
    cancelled_pairs_ += cancelled;
    // X8 (a)-(c) on the points the cancellations left.
    std::vector<DegeneratePoint> left;
    Skeleton left_skeleton;
    if (cancelled > 0) {
      left = FindDegeneratePoints(next, tp);
      left_skeleton = ExtractSkeleton(next, left, SkeletonFor(robot), obstacles);
    }
    const ViewGain gain = GainModel(robot);
    // (b)'s "no more information after a round trip": the robot has passed within
    // kVisitRadiusM of the wedge, and its end separatrix carries no gain.
    const ExhaustedEndFn exhausted = [&](const DegeneratePoint& wedge, const SkeletonEdge& edge) {
      const bool visited = std::any_of(trail_.begin(), trail_.end(), [&](const Eigen::Vector2d& p) {
        return (p - wedge.position_m).norm() <= kVisitRadiusM;
      });
      return visited &&
             MeanAlongPolyline(
                 edge.polyline, [&](const Eigen::Vector2d& p) { return gain.PointGain(p); }, 0.3) <
                 options_.gain_threshold;
    };
    PointMovesParams mp;
    mp.robot_radius_m = robot.radius_m;
    mp.trace = SkeletonFor(robot);
    const PointMovesResult moved = MoveDegeneratePoints(&next, cancelled > 0 ? left : points,
                                                        cancelled > 0 ? left_skeleton : skeleton,
                                                        window_.clearance, exhausted, mp);
    corner_wedges_ += moved.corner_wedges;
    retracted_wedges_ += moved.retracted_wedges;
    moved_trisectors_ += moved.moved_trisectors;
    // X Fig. 17: the key frame's degenerate points before and after its control.
    out->diag.control_points_before = static_cast<int>(points.size());
    out->diag.control_points_after = static_cast<int>(FindDegeneratePoints(next, tp).size());
  }
  const double t_census = NowMs();
  frames_.clear();
  if (have_key_ && options_.frames_k >= 2) {
    const TensorRaster previous = Reindex(key_, next);
    MaskParams mp;
    mp.use_window = true;
    mp.window_centre_m = robot.position_m;
    mp.window_radius_m = options_.interp_window_m;
    const std::vector<std::uint8_t> mask = InterpolationMask(previous, next, mp);
    SpaceTimeParams sp;
    sp.mode = options_.interp;
    sp.rows = SpaceTimeRows::kInteriorFrames;
    sp.substeps = options_.frames_k;
    SpaceTimeResult r = InterpolateFrames(previous, next, mask, sp);
    if (r.status.ok() && r.frames.size() == static_cast<std::size_t>(options_.frames_k) + 1)
      frames_ = std::move(r.frames);
  }
  if (frames_.empty()) frames_.push_back(next);
  min_magnitude_ = 1e-5 * MaxFieldMagnitude(next);
  key_ = std::move(next);
  key_t_s_ = t_s;
  have_key_ = true;
  out->diag.keyframe = true;
  out->diag.field_ms = t1 - t0;
  out->diag.interp_ms = NowMs() - t_census;
  out->diag.census_ms = t_control - t1;
  out->diag.control_ms = t_census - t_control;
}

void RobotPlanner::BuildTopology(const RobotInput& robot, const ViewGain& gain, StepOutput* out) {
  const TensorRaster& frame = frames_[static_cast<std::size_t>(sub_)];
  AddGlyphs(frame, out);
  if (options_.field != FieldKind::kTensor) return;  // a vector field has no wedges or trisectors
  TopologyParams tp;
  tp.min_relative_magnitude = 1e-5;
  key_points_ = FindDegeneratePoints(frame, tp);
  AdvectionObstacles obstacles;
  obstacles.clearance = &window_.clearance;
  skeleton_ = ExtractSkeleton(frame, key_points_, SkeletonFor(robot), obstacles);
  edge_gain_ = EdgeGains(skeleton_, [&](const SkeletonEdge& e) {
    return MeanAlongPolyline(
        e.polyline, [&](const Eigen::Vector2d& p) { return gain.PointGain(p); }, 0.3);
  });
  edge_access_ = EdgeAccessibility(skeleton_, [&](const SkeletonEdge& e) {
    return EdgeClear(e, window_.clearance, robot.radius_m);
  });
  for (const SkeletonEdge& e : skeleton_.edges) out->skeleton_edges.push_back(e.polyline);
}

// The field as glyphs for the run's picture: a segment along the major eigenvector (a vector
// field: from the cell along the vector) every 0.4 m where the field is not flat.
void RobotPlanner::AddGlyphs(const TensorRaster& frame, StepOutput* out) const {
  constexpr double kGlyphSpacingM = 0.4, kGlyphHalfM = 0.15;
  const bool vector = options_.field != FieldKind::kTensor;
  const omt::RasterGeometry& g = frame.geometry;
  const int step = std::max(1, static_cast<int>(std::lround(kGlyphSpacingM / g.resolution_m)));
  for (int y = step / 2; y < g.height; y += step)
    for (int x = step / 2; x < g.width; x += step) {
      const int i = g.Index(x, y);
      if (!frame.InDomain(i) || frame.At(i).norm() <= min_magnitude_) continue;
      const Eigen::Vector2d c = g.Center(x, y);
      if (vector) {
        out->field_glyphs.push_back({c, c + 2.0 * kGlyphHalfM * frame.At(i).normalized()});
      } else {
        const Eigen::Vector2d d = kGlyphHalfM * MajorEigenvector(frame.At(i));
        out->field_glyphs.push_back({c - d, c + d});
      }
    }
}

Pathline RobotPlanner::Advect(const RobotInput& robot, double heading_rad, double length_m,
                              const std::vector<DegeneratePoint>& points) const {
  AdvectionParams ap;
  ap.max_length_m = length_m;
  ap.min_magnitude = min_magnitude_;
  ap.max_speed_mps = options_.speed_mps;
  ap.min_speed_mps = std::min(0.05, options_.speed_mps);
  ap.frame_spacing_m = options_.substep_s * options_.speed_mps;
  ap.block_clearance_m = robot.radius_m + options_.clearance_margin_m;
  ap.wall_clearance_m = std::max(0.3, ap.block_clearance_m + 0.05);
  ap.stop_at_wedges = ap.stop_at_trisectors = true;
  ap.vector_field = options_.field != FieldKind::kTensor;
  // A robot already closer to a wall than its radius (a bump) may still move along or away.
  const int c = window_.geometry.IndexOf(robot.position_m);
  const double start_clearance = c >= 0 ? window_.clearance.At(c) : 0.0;
  const double need = std::min(robot.radius_m, start_clearance) - 1e-3;
  AdvectionObstacles obstacles;
  obstacles.clearance = &window_.clearance;
  obstacles.traversable = [this, need](const Eigen::Vector2d& p) { return Traversable(p, need); };
  const std::span<const TensorRaster> frames(frames_.data() + sub_, frames_.size() - sub_);
  return AdvectPathline(frames, robot.position_m, heading_rad, points, ap, obstacles);
}

std::optional<RobotPlanner::Route> RobotPlanner::SeparatrixRoute(const RobotInput& robot,
                                                                 double t_s) {
  const int root = RoutingRoot(skeleton_, robot.position_m, 0.5);
  if (root < 0) return std::nullopt;
  const Eigen::Vector2d root_m = skeleton_.nodes[static_cast<std::size_t>(root)].position_m;
  if ((root_m - robot.position_m).norm() > 1.0) return std::nullopt;
  if ((root_m - last_branch_root_).norm() < 0.3 && t_s - last_branch_t_s_ < kBranchHoldS)
    return std::nullopt;
  RoutingParams rp;
  rp.termination_gain = options_.gain_threshold;
  const BranchChoice b = ChooseBranch(skeleton_, edge_gain_, root, edge_access_, rp);
  if (b.edge < 0) return std::nullopt;
  const SkeletonEdge& e = skeleton_.edges[static_cast<std::size_t>(b.edge)];
  std::vector<Eigen::Vector2d> line = e.polyline;
  if (e.from != root) std::reverse(line.begin(), line.end());
  // From the polyline point nearest the robot on.
  std::size_t nearest = 0;
  for (std::size_t i = 1; i < line.size(); ++i)
    if ((line[i] - robot.position_m).norm() < (line[nearest] - robot.position_m).norm())
      nearest = i;
  std::vector<Eigen::Vector2d> from_robot = {robot.position_m};
  from_robot.insert(from_robot.end(), line.begin() + static_cast<long>(nearest) + 1, line.end());
  const int c = window_.geometry.IndexOf(robot.position_m);
  const double need = std::min(robot.radius_m, c >= 0 ? double(window_.clearance.At(c)) : 0.0);
  std::vector<Eigen::Vector2d> prefix = TraversablePrefix(from_robot, need - 1e-3);
  if (PolylineLength(prefix) < kRouteDoneM) return std::nullopt;
  last_branch_root_ = root_m;
  last_branch_t_s_ = t_s;
  ++branch_choices_;
  Route route;
  route.kind = StepMode::kSeparatrix;
  route.goal = prefix.back();
  route.deadline_s = t_s + 2.0 * PolylineLength(prefix) / options_.speed_mps + 5.0;
  route.polyline = std::move(prefix);
  return route;
}

// X L136: routing over the skeleton "at any time step". When the field ahead gives nothing to see,
// the robot drives to the skeleton edge with the most gain that the spanning tree from its
// nearest node reaches (costs 1 / mean gain, X6), per metre of the way there (the edge's nearest
// free point, over the known map); the frontier fallback comes only after that. An edge point once
// routed to is not a target again (its gain is the key frame's, and the robot has now looked from
// there).
std::optional<RobotPlanner::Route> RobotPlanner::SkeletonRoute(const FloorInput& floor,
                                                               const RobotInput& robot, double t_s,
                                                               const RouteServices& services) {
  if (!services.shortest_path || !services.geodesic || skeleton_.edges.empty()) return std::nullopt;
  const int root = RoutingRoot(skeleton_, robot.position_m, 0.5);
  if (root < 0) return std::nullopt;
  RoutingParams rp;
  rp.termination_gain = options_.gain_threshold;
  std::vector<double> cost(edge_gain_.size());
  for (std::size_t e = 0; e < cost.size(); ++e) cost[e] = EdgeCost(edge_gain_[e], rp);
  const SpanningTree tree = MinimumSpanningTree(skeleton_, cost, root, edge_access_);
  const int c = window_.geometry.IndexOf(robot.position_m);
  const double need = std::min(robot.radius_m, c >= 0 ? double(window_.clearance.At(c)) : 0.0);
  const auto visited = [&](const Eigen::Vector2d& p) {
    for (const Eigen::Vector2d& g : skeleton_goals_)
      if ((g - p).norm() < kSettleRadiusM) return true;
    return false;
  };
  // Per tree edge with gain, its free, new point nearest the robot by the geodesic distance d;
  // edges by gain per metre driven, gain / (1 + d), best first (ties: lower index).
  const double clearance = robot.radius_m + options_.clearance_margin_m;
  const std::vector<float> field = services.geodesic(robot.position_m, clearance);
  struct Target {
    Eigen::Vector2d goal;
    double value;
  };
  std::vector<Target> targets;
  for (const int e : tree.edges) {
    const double g = edge_gain_[static_cast<std::size_t>(e)];
    if (g < options_.gain_threshold) continue;
    double best_d = std::numeric_limits<double>::infinity();
    Eigen::Vector2d best_p = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : skeleton_.edges[static_cast<std::size_t>(e)].polyline) {
      const int cell = floor.geometry.IndexOf(p);
      if (cell < 0 || static_cast<std::size_t>(cell) >= field.size()) continue;
      const double d = field[static_cast<std::size_t>(cell)];
      if (!std::isfinite(d) || d >= best_d || !Traversable(p, need) || visited(p)) continue;
      best_d = d;
      best_p = p;
    }
    if (std::isfinite(best_d)) targets.push_back({best_p, g / (1.0 + best_d)});
  }
  std::stable_sort(targets.begin(), targets.end(),
                   [](const Target& a, const Target& b) { return a.value > b.value; });
  for (const Target& t : targets) {
    const Eigen::Vector2d goal = t.goal;
    skeleton_goals_.push_back(goal);
    if ((goal - robot.position_m).norm() < kRouteDoneM) continue;
    std::optional<Route> route =
        RouteOverMap(StepMode::kSkeleton, robot.position_m, goal, clearance, t_s, services);
    if (!route) continue;
    ++skeleton_routes_;
    return route;
  }
  return std::nullopt;
}

std::optional<RobotPlanner::Route> RobotPlanner::RouteOverMap(StepMode kind,
                                                              const Eigen::Vector2d& from,
                                                              const Eigen::Vector2d& goal,
                                                              double clearance_m, double t_s,
                                                              const RouteServices& services) const {
  std::optional<std::vector<Eigen::Vector2d>> path =
      services.shortest_path(from, goal, clearance_m);
  if (!path || path->empty()) return std::nullopt;
  std::vector<Eigen::Vector2d> line = {from};
  for (const Eigen::Vector2d& p : *path)
    if ((p - line.back()).norm() > 1e-3) line.push_back(p);
  Route route;
  route.kind = kind;
  route.goal = goal;
  // Twice the drive at speed plus slack: a route that takes longer is given up.
  route.deadline_s = t_s + 2.0 * PolylineLength(line) / options_.speed_mps + 10.0;
  route.polyline = std::move(line);
  return route;
}

namespace {

// Unsettled frontier cells of the floor, dilated to the cells within approach_m of one.
std::vector<std::uint8_t> FrontierTargets(const FloorInput& floor,
                                          const std::function<bool(int)>& settled,
                                          double approach_m, bool* any) {
  const std::size_t n = floor.cells.size();
  std::vector<std::uint8_t> mask(n, 0);
  *any = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (floor.cells[i] != kFloorFrontier || settled(static_cast<int>(i))) continue;
    mask[i] = 1;
    *any = true;
  }
  if (!*any) return mask;
  const int r =
      std::max(0, static_cast<int>(std::lround(approach_m / floor.geometry.resolution_m)));
  return DilateMask(floor.geometry, mask, r);
}

}  // namespace

bool RobotPlanner::FrontierReachable(const FloorInput& floor, const RobotInput& robot,
                                     const RouteServices& services) const {
  bool any = false;
  const std::vector<std::uint8_t> targets = FrontierTargets(
      floor, [&](int c) { return Settled(floor, c); }, kApproachM, &any);
  if (!any) return false;
  if (!services.geodesic) return true;
  const std::vector<float> field =
      services.geodesic(robot.position_m, robot.radius_m + options_.clearance_margin_m);
  for (std::size_t i = 0; i < targets.size() && i < field.size(); ++i)
    if (targets[i] != 0 && std::isfinite(field[i])) return true;
  return false;
}

std::optional<RobotPlanner::Route> RobotPlanner::FrontierRoute(const FloorInput& floor,
                                                               const RobotInput& robot, double t_s,
                                                               const RouteServices& services) {
  if (!services.geodesic || !services.shortest_path) return std::nullopt;
  const double clearance = robot.radius_m + options_.clearance_margin_m;
  const std::vector<float> field = services.geodesic(robot.position_m, clearance);
  const omt::RasterGeometry& g = floor.geometry;
  for (int attempt = 0; attempt < 8; ++attempt) {
    bool any = false;
    const std::vector<std::uint8_t> targets = FrontierTargets(
        floor, [&](int c) { return Settled(floor, c); }, kApproachM, &any);
    if (!any) return std::nullopt;
    int best = -1;
    for (std::size_t i = 0; i < targets.size() && i < field.size(); ++i) {
      if (targets[i] == 0 || !std::isfinite(field[i])) continue;
      if (best < 0 || field[i] < field[static_cast<std::size_t>(best)]) best = static_cast<int>(i);
    }
    if (best < 0) return std::nullopt;
    const Eigen::Vector2d goal = g.Center(best);
    if ((goal - robot.position_m).norm() < 0.3) {
      // Already there and the frontier did not resolve: settle it, try the next one.
      SettleAround(floor, goal);
      continue;
    }
    return RouteOverMap(StepMode::kFrontier, robot.position_m, goal, clearance, t_s, services);
  }
  return std::nullopt;
}

void RobotPlanner::SettleAround(const FloorInput& floor, const Eigen::Vector2d& goal) {
  const omt::RasterGeometry& g = floor.geometry;
  for (int i = 0; i < g.NumCells(); ++i)
    if (floor.cells[static_cast<std::size_t>(i)] == kFloorFrontier &&
        (g.Center(i) - goal).norm() <= kSettleRadiusM)
      settled_.insert(KeyOf(g, i));
  visited_goals_.push_back(goal);
}

// The gain model on the current window; settled cells count as seen.
ViewGain RobotPlanner::GainModel(const RobotInput& robot, bool with_surface) const {
  std::vector<std::uint8_t> codes = window_.codes;
  for (int i = 0; i < window_.geometry.NumCells() && !settled_.empty(); ++i)
    if (settled_.count(KeyOf(window_.geometry, i)) > 0)
      codes[static_cast<std::size_t>(i)] = kFloorFree;
  GainParams gp;
  gp.range_m = robot.max_range_m;
  gp.near_m = std::max(0.3, robot.min_range_m);
  gp.fov_rad = robot.fov_rad;
  if (!with_surface || options_.surface_depth_m <= 0.0 || window_.surface.empty())
    return ViewGain(window_.geometry, std::move(codes), gp);
  gp.surface_depth_m = options_.surface_depth_m;
  return ViewGain(window_.geometry, std::move(codes), gp, window_.surface);
}

StepOutput RobotPlanner::Step(const FloorInput& floor, const RobotInput& robot, double sim_time_s,
                              const RouteServices& services) {
  StepOutput out;
  out.wakeup_t_s = sim_time_s + options_.substep_s;
  prev_mode_ = emitted_mode_;
  emitted_mode_ = StepMode::kNone;
  history_.push_back(robot.position_m);
  if (history_.size() > 32) history_.erase(history_.begin());
  if (options_.topology_control &&
      (trail_.empty() || (trail_.back() - robot.position_m).norm() >= kTrailSpacingM))
    trail_.push_back(robot.position_m);

  // Key frame when due (every substeps_per_keyframe sub-steps, or the robot nears the window's
  // edge), else the current window re-read on the key frame's grid.
  const double substep = options_.substep_s;
  const bool due =
      !have_key_ || sim_time_s - key_t_s_ >= options_.substeps_per_keyframe * substep - 1e-6 ||
      (robot.position_m - key_centre_).norm() > options_.window_m - options_.lookahead_m - 0.5;
  if (due) {
    BuildKeyFrame(floor, robot, sim_time_s, &out);
  } else {
    window_ = CropFloor(floor, key_centre_, options_.window_m);
  }
  // The sub-step: by the time since the key frame (the loop's calls come at its own steps).
  const int first = std::max(0, options_.frames_k - options_.substeps_per_keyframe);
  const int elapsed = static_cast<int>(std::floor((sim_time_s - key_t_s_) / substep + 1e-6));
  sub_ = frames_.size() <= 1 ? 0
                             : std::clamp(first + elapsed, 0, static_cast<int>(frames_.size()) - 1);
  out.diag.substep = sub_;

  const ViewGain gain = GainModel(robot);

  const double topo_t0 = NowMs();
  if (due) BuildTopology(robot, gain, &out);
  TopologyParams tp;
  tp.min_relative_magnitude = 1e-5;
  const std::vector<DegeneratePoint> points =
      options_.field == FieldKind::kTensor
          ? FindDegeneratePoints(frames_[static_cast<std::size_t>(sub_)], tp)
          : std::vector<DegeneratePoint>{};
  out.diag.topology_ms = NowMs() - topo_t0;
  out.diag.degenerate_points = static_cast<int>(points.size());
  for (const DegeneratePoint& p : points) {
    (p.type == DegenerateType::kWedge ? out.diag.wedges : out.diag.trisectors)++;
    out.degenerate_xy.push_back(p.position_m);
  }
  out.diag.skeleton_edges = static_cast<int>(skeleton_.edges.size());
  RoutingParams rp;
  rp.termination_gain = options_.gain_threshold;
  const TerminationCheck term = CheckTermination(edge_gain_, edge_access_, rp);
  out.diag.max_edge_gain = term.max_accessible_gain;

  auto finish = [&]() -> StepOutput {
    out.diag.fallback_routes = fallback_routes_;
    out.diag.blocked = blocked_.blocked;
    out.diag.pathlines = blocked_.pathlines;
    out.diag.branch_choices = branch_choices_;
    out.diag.skeleton_routes = skeleton_routes_;
    out.diag.cancelled_pairs = cancelled_pairs_;
    out.diag.corner_wedges = corner_wedges_;
    out.diag.retracted_wedges = retracted_wedges_;
    out.diag.moved_trisectors = moved_trisectors_;
    out.diag.settled_goals = static_cast<int>(visited_goals_.size());
    out.diag.camera_stops = camera_stops_;
    return std::move(out);
  };
  // X7: no accessible edge with gain, and (ours) no frontier anyone could still reach.
  const bool tensor = options_.method == Method::kTensor;
  if ((term.done || !tensor) && !FrontierReachable(floor, robot, services)) {
    out.done = true;
    route_.reset();
    return finish();
  }
  const bool stuck = Stuck();
  auto fallback = [&]() -> bool {
    std::optional<Route> r = FrontierRoute(floor, robot, sim_time_s, services);
    if (!r) return false;
    ++fallback_routes_;
    route_ = std::move(r);
    history_.clear();
    history_.push_back(robot.position_m);
    return true;
  };

  // A route in progress (a separatrix or a fallback to a frontier).
  if (route_) {
    const Route& r = *route_;
    std::size_t nearest = 0;
    for (std::size_t i = 1; i < r.polyline.size(); ++i)
      if ((r.polyline[i] - robot.position_m).norm() <
          (r.polyline[nearest] - robot.position_m).norm())
        nearest = i;
    std::vector<Eigen::Vector2d> rest = {robot.position_m};
    rest.insert(rest.end(), r.polyline.begin() + static_cast<long>(nearest) + 1, r.polyline.end());
    bool resolved = false;
    if (r.kind == StepMode::kFrontier) {
      resolved = true;
      const omt::RasterGeometry& g = floor.geometry;
      for (int i = 0; i < g.NumCells() && resolved; ++i)
        resolved = !(floor.cells[static_cast<std::size_t>(i)] == kFloorFrontier &&
                     (g.Center(i) - r.goal).norm() <= kSettleRadiusM && !Settled(floor, i));
    }
    const bool arrived = PolylineLength(rest) < kRouteDoneM;
    if (arrived && r.kind == StepMode::kFrontier && !resolved) SettleAround(floor, r.goal);
    if (stuck && r.kind == StepMode::kFrontier) SettleAround(floor, r.goal);
    if (arrived || resolved || stuck || sim_time_s > r.deadline_s) {
      route_.reset();
    } else {
      std::vector<float> speeds(rest.size(), static_cast<float>(options_.speed_mps));
      out.diag.mode = r.kind;
      EmitLine(rest, speeds, robot, gain, false, &out);
      return finish();
    }
  }

  const double min_move = 0.5 * substep * options_.speed_mps;
  if (!tensor) {
    // The potential baselines: down φ over the window around the robot, every call anew.
    const double t0 = NowMs();
    const FloorWindow w = CropFloor(floor, robot.position_m, options_.window_m);
    PotentialInfoParams pp;
    pp.sigma_m = 0.5 * robot.max_range_m;
    pp.repulse_within_m = robot.radius_m + 0.3;
    const std::vector<double> phi =
        options_.method == Method::kHarmonic
            ? SolveHarmonic(w.geometry, w.codes)
            : SolvePotentialInfo(w.geometry, w.codes, w.clearance.clearance_m, pp);
    const double need = robot.radius_m + options_.clearance_margin_m;
    const std::vector<Eigen::Vector2d> xy = DescendPotential(
        w.geometry, phi, w.codes, robot.position_m,
        options_.sent_substeps * substep * options_.speed_mps,
        [&](const Eigen::Vector2d& p) { return Traversable(p, std::min(need, robot.radius_m)); });
    out.diag.advect_ms = NowMs() - t0;
    if (PolylineLength(xy) < min_move || stuck) {
      if (fallback()) {
        std::vector<float> speeds(route_->polyline.size(), static_cast<float>(options_.speed_mps));
        out.diag.mode = StepMode::kFrontier;
        EmitLine(route_->polyline, speeds, robot, gain, true, &out);
      }
      return finish();
    }
    std::vector<float> speeds(xy.size(), static_cast<float>(options_.speed_mps));
    out.diag.mode = StepMode::kAdvect;
    EmitLine(xy, speeds, robot, gain, false, &out);
    return finish();
  }

  // Advection over the frames from the current sub-step (X4).
  const double adv_t0 = NowMs();
  Pathline line = Advect(robot, robot.heading_rad, options_.lookahead_m, points);
  blocked_.Add(line);
  out.diag.stop = static_cast<int>(line.stop);
  bool need_fallback = false;
  const bool readvected = line.Length() < min_move;  // X5: a stop, the path split there
  if (readvected) {
    const bool at_point =
        line.stop == AdvectionStop::kWedge || line.stop == AdvectionStop::kTrisector;
    if (at_point && options_.topology_routing) {
      // X5, X6: stopped at a wedge or trisector: leave along the branch with the most gain.
      std::optional<Route> r = SeparatrixRoute(robot, sim_time_s);
      out.diag.advect_ms = NowMs() - adv_t0;
      if (r) {
        route_ = std::move(r);
        std::vector<float> speeds(route_->polyline.size(), static_cast<float>(options_.speed_mps));
        out.diag.mode = StepMode::kSeparatrix;
        EmitLine(route_->polyline, speeds, robot, gain, true, &out);
        return finish();
      }
    }
    if (at_point && !options_.topology_routing && line.stop == AdvectionStop::kTrisector &&
        line.stop_point >= 0) {
      // Without routing, at a trisector: the freest separatrix, the one advecting farthest.
      Pathline best;
      for (double a : points[static_cast<std::size_t>(line.stop_point)].separatrix_angles_rad) {
        Pathline l = Advect(robot, a, options_.lookahead_m, points);
        if (l.Length() > best.Length() + 1e-9) best = std::move(l);
      }
      line = std::move(best);
    } else {
      // A wedge (a dead end of the line field), an obstacle, the known map's edge or a flat
      // field ahead: turn round and advect the other way.
      line = Advect(robot, robot.heading_rad + omt::kPi, options_.lookahead_m, points);
    }
    need_fallback = line.Length() < min_move;
  }
  out.diag.advect_ms = NowMs() - adv_t0;
  // The field alone gives nothing to see along the way.
  double look_gain = 0.0;
  for (std::size_t i = 0; i < line.points.size(); i += 6)
    look_gain = std::max(look_gain, gain.PointGain(line.points[i].position_m));
  out.diag.lookahead_gain = look_gain;
  no_gain_streak_ = look_gain < options_.gain_threshold ? no_gain_streak_ + 1 : 0;
  if (no_gain_streak_ >= options_.no_gain_calls || stuck) need_fallback = true;
  if (need_fallback && !stuck && options_.topology_routing) {
    if (std::optional<Route> r = SkeletonRoute(floor, robot, sim_time_s, services)) {
      no_gain_streak_ = 0;
      route_ = std::move(r);
      history_.clear();
      history_.push_back(robot.position_m);
      std::vector<float> speeds(route_->polyline.size(), static_cast<float>(options_.speed_mps));
      out.diag.mode = StepMode::kSkeleton;
      EmitLine(route_->polyline, speeds, robot, gain, true, &out);
      return finish();
    }
  }
  if (need_fallback && fallback()) {
    no_gain_streak_ = 0;
    std::vector<float> speeds(route_->polyline.size(), static_cast<float>(options_.speed_mps));
    out.diag.mode = StepMode::kFrontier;
    EmitLine(route_->polyline, speeds, robot, gain, true, &out);
    return finish();
  }
  if (line.Length() >= 1e-3) {
    std::vector<Eigen::Vector2d> xy;
    std::vector<float> speeds;
    for (const PathPoint& p : line.points) {
      xy.push_back(p.position_m);
      speeds.push_back(static_cast<float>(std::max(p.speed_mps, 0.05)));
    }
    out.diag.mode = StepMode::kAdvect;
    EmitLine(xy, speeds, robot, gain, readvected, &out);
  }
  return finish();
}

}  // namespace voxplan::tensorfield
