#include "plugins/omt/algorithms/planner.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <thread>

#include "plugins/omt/algorithms/geodesic.h"
#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::omt {
namespace {

// Runs fn(i) for i in [0, n) on up to `threads` threads, index i always on the same kind of
// work slot so results (written per index) do not depend on the thread count.
void ParallelFor(int n, int threads, const std::function<void(int)>& fn) {
  threads = std::max(1, std::min(threads, n));
  if (threads == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&, t] {
      for (int i = t; i < n; i += threads) fn(i);
    });
  }
  for (auto& th : pool) th.join();
}

}  // namespace

std::vector<std::uint8_t> AccessibleCells(const OccupancyRaster& raster,
                                          const ClearanceRaster& clearance,
                                          const std::vector<RobotState>& robots,
                                          double robot_radius_m, double snap_radius_m,
                                          int* anchored) {
  const RasterGeometry& g = raster.geometry;
  const auto n = static_cast<std::size_t>(g.NumCells());
  std::vector<std::uint8_t> open(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    open[i] = raster.cells[i] == Cell::kFree && clearance.clearance_m[i] >= robot_radius_m;
  std::vector<std::uint8_t> seen(n, 0);
  std::vector<int> stack;
  int seeded = 0;
  const int snap = static_cast<int>(std::ceil(snap_radius_m / g.resolution_m));
  for (const RobotState& robot : robots) {
    const Eigen::Vector2d q = (robot.position_m - g.origin_m) / g.resolution_m;
    const int rx = static_cast<int>(std::floor(q.x()));
    const int ry = static_cast<int>(std::floor(q.y()));
    // Its own cell, else the nearest open one within the snap radius (ties: scan order).
    int seed = -1;
    double best_d2 = snap_radius_m * snap_radius_m;
    for (int y = ry - snap; y <= ry + snap; ++y) {
      for (int x = rx - snap; x <= rx + snap; ++x) {
        if (!g.InBounds(x, y) || !open[static_cast<std::size_t>(g.Index(x, y))]) continue;
        const double d2 = (g.Center(x, y) - robot.position_m).squaredNorm();
        if (x == rx && y == ry) {
          seed = g.Index(x, y);
          best_d2 = -1.0;
        } else if (d2 < best_d2) {
          seed = g.Index(x, y);
          best_d2 = d2;
        }
      }
    }
    if (seed < 0) continue;
    ++seeded;
    if (!seen[static_cast<std::size_t>(seed)]) {
      seen[static_cast<std::size_t>(seed)] = 1;
      stack.push_back(seed);
    }
  }
  while (!stack.empty()) {
    const int u = stack.back();
    stack.pop_back();
    const int ux = g.X(u);
    const int uy = g.Y(u);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int vx = ux + dx;
        const int vy = uy + dy;
        if ((dx == 0 && dy == 0) || !g.InBounds(vx, vy)) continue;
        const auto v = static_cast<std::size_t>(g.Index(vx, vy));
        if (seen[v] || !open[v]) continue;
        if (dx != 0 && dy != 0 &&
            (!open[static_cast<std::size_t>(g.Index(vx, uy))] ||
             !open[static_cast<std::size_t>(g.Index(ux, vy))]))
          continue;
        seen[v] = 1;
        stack.push_back(static_cast<int>(v));
      }
    }
  }
  if (anchored) *anchored = seeded;
  return seen;
}

ViewSet ExtractAccessibleViews(const OccupancyRaster& raster, const ClearanceRaster& clearance,
                               const std::vector<RobotState>& robots, const PlannerOptions& options,
                               const std::vector<std::uint8_t>* accessible_cells,
                               int anchored_robots) {
  ViewSet out;
  if (accessible_cells && accessible_cells->size() == raster.cells.size()) {
    out.accessible = *accessible_cells;
    out.anchored_robots = anchored_robots;
  } else {
    out.accessible = AccessibleCells(raster, clearance, robots, options.robot_radius_m,
                                     options.snap_radius_m, &out.anchored_robots);
  }
  // Task views (§3.2), or frontier points for NoTV.
  TaskViewParams view_params = options.views;
  view_params.max_views = options.kappa * static_cast<int>(robots.size());
  view_params.robot_radius_m = options.robot_radius_m;
  view_params.frontier_points_only = !options.use_task_views;
  out.views = ExtractTaskViews(raster, clearance, view_params, &out.accessible);
  return out;
}

Status PlanOmt(const OccupancyRaster& raster, const ClearanceRaster* clearance_in,
               const std::vector<RobotState>& robots, const PlannerOptions& options,
               PlanResult* result, const GeodesicProvider* provider) {
  *result = PlanResult{};
  const RasterGeometry& g = raster.geometry;
  if (g.NumCells() <= 0 || raster.cells.size() != static_cast<std::size_t>(g.NumCells()))
    return Status::Error(Status::Code::kInvalidInput, "raster size does not match its geometry");
  if (!raster.tsdf_weight.empty() && raster.tsdf_weight.size() != raster.cells.size())
    return Status::Error(Status::Code::kInvalidInput, "tsdf_weight size does not match");
  if (!raster.settled.empty() && raster.settled.size() != raster.cells.size())
    return Status::Error(Status::Code::kInvalidInput, "settled size does not match");
  if (robots.empty()) return Status::Error(Status::Code::kInvalidInput, "no robots");
  if (clearance_in && clearance_in->clearance_m.size() != raster.cells.size())
    return Status::Error(Status::Code::kInvalidInput, "clearance size does not match");
  ClearanceRaster computed;
  if (!clearance_in) computed = ComputeClearance(raster, /*unknown_is_obstacle=*/true);
  const ClearanceRaster& clearance = clearance_in ? *clearance_in : computed;
  const int R = static_cast<int>(robots.size());
  result->robots.resize(static_cast<std::size_t>(R));

  const std::vector<std::uint8_t>* given = provider ? provider->accessible_cells : nullptr;
  ViewSet view_set = ExtractAccessibleViews(raster, clearance, robots, options, given,
                                            provider ? provider->anchored_robots : 0);
  result->views = std::move(view_set.views);
  result->anchored_robots = view_set.anchored_robots;
  result->extracted_views = static_cast<int>(result->views.size());
  result->terminated = ShouldTerminate(result->views, options.importance_threshold);
  if (result->terminated) return Status::Ok();
  // A view too poor to keep the run going (the termination test) is not worth a trip while a
  // better one remains: assigned, it fills tours ahead of the views that matter, and
  // re-planning keeps redrawing those tours.
  if (!options.assign_unimportant_views) {
    std::erase_if(result->views, [&](const TaskView& v) {
      return !(v.importance > options.importance_threshold);
    });
  }
  const int K = static_cast<int>(result->views.size());

  // Geodesics between all robots and views (robots first): the provider's, or one Dijkstra
  // per node on the internal grid.
  const int n_nodes = R + K;
  auto position = [&](int node) {
    return node < R ? robots[static_cast<std::size_t>(node)].position_m
                    : result->views[static_cast<std::size_t>(node - R)].position_m;
  };
  const bool external_matrix = provider && provider->distance_matrix;
  const bool external_paths = provider && provider->shortest_path;
  GeodesicGrid grid;
  std::vector<Anchor> anchors;  // robots, then views
  std::vector<ShortestPaths> paths(static_cast<std::size_t>(n_nodes));
  if (!external_matrix || !external_paths) {
    grid = BuildGeodesicGrid(clearance, options.geodesic_cell_m, options.robot_radius_m);
    for (int i = 0; i < n_nodes; ++i)
      anchors.push_back(AnchorPoint(grid, clearance, position(i), options.robot_radius_m));
    // Each search stops once every robot and view anchor is settled.
    std::vector<std::uint8_t> wanted(static_cast<std::size_t>(grid.NumNodes()), 0);
    int num_wanted = 0;
    for (const Anchor& a : anchors) {
      if (a.node >= 0 && !wanted[static_cast<std::size_t>(a.node)]) {
        wanted[static_cast<std::size_t>(a.node)] = 1;
        ++num_wanted;
      }
    }
    ParallelFor(n_nodes, options.num_threads, [&](int i) {
      Dijkstra(grid, anchors[static_cast<std::size_t>(i)].node, &paths[static_cast<std::size_t>(i)],
               &wanted, num_wanted);
    });
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  DistanceMatrix dist(n_nodes, n_nodes, kInf);
  if (external_matrix) {
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < n_nodes; ++i) points.push_back(position(i));
    if (!provider->distance_matrix(points, &dist) || dist.rows != n_nodes || dist.cols != n_nodes ||
        dist.values.size() != static_cast<std::size_t>(n_nodes) * n_nodes)
      return Status::Error(Status::Code::kInvalidInput,
                           "geodesic provider: distance matrix failed");
  } else {
    for (int i = 0; i < n_nodes; ++i) {
      for (int j = 0; j < n_nodes; ++j) {
        const Anchor& ai = anchors[static_cast<std::size_t>(i)];
        const Anchor& aj = anchors[static_cast<std::size_t>(j)];
        if (i == j) {
          dist(i, j) = 0.0;
        } else if (ai.node >= 0 && aj.node >= 0) {
          const double d =
              paths[static_cast<std::size_t>(i)].dist_m[static_cast<std::size_t>(aj.node)];
          if (std::isfinite(d)) dist(i, j) = ai.offset_m + d + aj.offset_m;
        }
      }
    }
  }

  // OMT assignment (eq. 4). Unreachable pairs get a large finite cost so sums stay ordered.
  AssignmentProblem problem;
  problem.num_robots = R;
  problem.num_tasks = K;
  problem.task_task = DistanceMatrix(K, K);
  problem.robot_task = DistanceMatrix(R, K);
  double finite_max = 0.0;
  for (double d : dist.values)
    if (std::isfinite(d)) finite_max = std::max(finite_max, d);
  const double unreachable = 10.0 * (finite_max + 1.0);
  auto finite = [&](double d) { return std::isfinite(d) ? d : unreachable; };
  for (int a = 0; a < K; ++a)
    for (int b = 0; b < K; ++b) problem.task_task(a, b) = finite(dist(R + a, R + b));
  for (int r = 0; r < R; ++r)
    for (int k = 0; k < K; ++k) problem.robot_task(r, k) = finite(dist(r, R + k));
  std::vector<double> speeds;
  for (const RobotState& r : robots) speeds.push_back(r.speed_mps);
  std::vector<double> reach_m;  // empty: every robot shares the work (§3.4)
  if (options.reach_horizon_s > 0.0) {
    for (double v : speeds) reach_m.push_back(v * options.reach_horizon_s);
    problem.capacity = ReachCapacities(problem, speeds, reach_m);
  } else {
    problem.capacity = RobotCapacities(K, speeds);
  }
  std::vector<double> driven_m;
  for (const RobotState& r : robots) driven_m.push_back(r.driven_m);
  if (options.team_views_per_robot > 0.0) {
    const std::vector<double> shared = problem.capacity;
    problem.capacity = TeamCapacities(problem, speeds, driven_m, options.team_views_per_robot,
                                      options.team_driven_weight);
    for (int r = 0; r < R; ++r) {
      if (!(shared[r] > 0.0) || problem.capacity[r] > 0.0) continue;
      // Held back: a reach of -inf lets HandOutUnassigned give it nothing either.
      if (reach_m.empty()) reach_m.assign(R, std::numeric_limits<double>::infinity());
      reach_m[r] = -std::numeric_limits<double>::infinity();
    }
  }
  for (int r = 0; K > 0 && r < R; ++r)  // a robot with speed 0 has no capacity anyway
    result->robots_held_back += problem.capacity[r] == 0.0 && speeds[r] > 0.0;
  AssignmentParams assignment_params = options.assignment;
  assignment_params.refine = options.refine;
  result->assignment = AssignTasks(problem, assignment_params);
  if (options.hand_out_unassigned)
    HandOutUnassigned(problem, unreachable, &result->assignment, reach_m);
  if (options.balance_tolerance_m > 0.0) {
    BalanceLoads(problem, driven_m, options.balance_tolerance_m, &result->assignment);
  }

  // Per robot: open TSP robot → farthest task, geodesic polyline, eq. 5, camera yaw.
  std::vector<double> task_yaw(static_cast<std::size_t>(K));
  for (int k = 0; k < K; ++k)
    task_yaw[static_cast<std::size_t>(k)] = result->views[static_cast<std::size_t>(k)].yaw_rad;
  SmoothingParams smoothing = options.smoothing;
  smoothing.min_clearance_m = options.robot_radius_m + options.path_margin_m;
  std::vector<Status> statuses(static_cast<std::size_t>(R));
  // First each robot's polyline through its tasks, then the smoothing. Provider callbacks (the
  // host's) are only ever called from this thread, so with them the polylines are built one
  // robot after the other; the smoothing, each robot's own, always runs in parallel.
  std::vector<std::vector<Eigen::Vector2d>> polylines(static_cast<std::size_t>(R));
  std::vector<std::vector<std::pair<int, int>>> task_vertices(static_cast<std::size_t>(R));
  const int robot_threads = external_paths ? 1 : options.num_threads;
  ParallelFor(R, robot_threads, [&](int r) {
    RobotPlan& plan = result->robots[static_cast<std::size_t>(r)];
    std::vector<int> nodes{r};  // global node ids: robot, then its tasks
    for (int k = 0; k < K; ++k)
      if (result->assignment.task_robot[static_cast<std::size_t>(k)] == r) nodes.push_back(R + k);
    if (nodes.size() < 2 || (!external_paths && anchors[static_cast<std::size_t>(r)].node < 0))
      return;
    const int n = static_cast<int>(nodes.size());
    DistanceMatrix local(n, n);
    int end = 1;
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) local(a, b) = finite(dist(nodes[a], nodes[b]));
    for (int a = 2; a < n; ++a)
      if (local(0, a) > local(0, end)) end = a;
    const std::vector<int> order = options.use_tsp
                                       ? OpenPathChristofides(local, 0, end, options.tsp)
                                       : OpenPathGreedy(local, 0);
    std::vector<Eigen::Vector2d>& polyline = polylines[static_cast<std::size_t>(r)];
    int from = nodes[static_cast<std::size_t>(order[0])];
    for (std::size_t i = 1; i < order.size(); ++i) {
      const int to = nodes[static_cast<std::size_t>(order[i])];
      std::vector<Eigen::Vector2d> leg;
      if (external_paths) {
        if (!provider->shortest_path(position(from), position(to), &leg)) leg.clear();
      } else {
        leg = ExtractPath(grid, paths[static_cast<std::size_t>(from)],
                          anchors[static_cast<std::size_t>(from)],
                          anchors[static_cast<std::size_t>(to)]);
      }
      if (leg.empty()) continue;  // not reachable from here: the task is skipped
      for (std::size_t v = polyline.empty() ? 0 : 1; v < leg.size(); ++v)
        polyline.push_back(leg[v]);
      task_vertices[static_cast<std::size_t>(r)].emplace_back(static_cast<int>(polyline.size()) - 1,
                                                              to - R);
      plan.tasks.push_back(to - R);
      from = to;
    }
  });
  ParallelFor(R, options.num_threads, [&](int r) {
    const std::vector<Eigen::Vector2d>& polyline = polylines[static_cast<std::size_t>(r)];
    if (polyline.empty()) return;
    RobotPlan& plan = result->robots[static_cast<std::size_t>(r)];
    plan.path = SamplePolyline(polyline, task_vertices[static_cast<std::size_t>(r)],
                               smoothing.sample_spacing_m);
    plan.geodesic_length_m = PolylineLength(plan.path);
    const RobotState& robot = robots[static_cast<std::size_t>(r)];
    if (options.optimize_paths) {
      statuses[static_cast<std::size_t>(r)] = SmoothPath(clearance, smoothing, &plan.path);
      plan.yaw_rad = InterpolateYaw(plan.path, robot.yaw_rad, task_yaw);
    } else {
      plan.yaw_rad = StepYaw(plan.path, robot.yaw_rad, task_yaw);
    }
    plan.length_m = PolylineLength(plan.path);
  });
  for (const Status& s : statuses)
    if (!s.ok()) return s;
  return Status::Ok();
}

}  // namespace voxplan::omt
