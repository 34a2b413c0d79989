#include "plugins/omt/planner.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <thread>

#include "plugins/omt/geodesic.h"
#include "plugins/omt/raster_ops.h"

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

ViewSet ExtractAccessibleViews(const OccupancyRaster& raster, const ClearanceRaster& clearance,
                               const std::vector<RobotState>& robots,
                               const PlannerOptions& options) {
  const RasterGeometry& g = raster.geometry;
  const int R = static_cast<int>(robots.size());
  ViewSet out;
  // Geodesic grid, robots joined to it, the part of it they can reach.
  out.grid = BuildGeodesicGrid(clearance, options.geodesic_cell_m, options.robot_radius_m);
  const GeodesicGrid& grid = out.grid;
  std::vector<int> sources;
  for (const RobotState& r : robots) {
    out.anchors.push_back(AnchorPoint(grid, clearance, r.position_m, options.robot_radius_m));
    sources.push_back(out.anchors.back().node);
  }
  out.reachable = ReachableNodes(grid, sources);
  const std::vector<std::uint8_t>& reachable = out.reachable;
  // A fine cell is accessible when a reachable node lies within one grid step; the exact
  // test (a clear anchor segment) follows per view.
  std::vector<std::uint8_t> accessible(static_cast<std::size_t>(g.NumCells()), 0);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int cx = x / grid.factor;
      const int cy = y / grid.factor;
      bool any = false;
      for (int dy = -1; dy <= 1 && !any; ++dy)
        for (int dx = -1; dx <= 1 && !any; ++dx) {
          const int nx = cx + dx;
          const int ny = cy + dy;
          any = nx >= 0 && ny >= 0 && nx < grid.width && ny < grid.height &&
                reachable[static_cast<std::size_t>(ny * grid.width + nx)];
        }
      accessible[static_cast<std::size_t>(g.Index(x, y))] = any ? 1 : 0;
    }
  }

  // Task views (§3.2), or frontier points for NoTV.
  TaskViewParams view_params = options.views;
  view_params.max_views = options.kappa * R;
  view_params.robot_radius_m = options.robot_radius_m;
  view_params.frontier_points_only = !options.use_task_views;
  const std::vector<TaskView> extracted =
      ExtractTaskViews(raster, clearance, view_params, &accessible);
  for (const TaskView& v : extracted) {
    Anchor a = AnchorPoint(grid, clearance, v.position_m, options.robot_radius_m);
    if (a.node < 0 || !reachable[static_cast<std::size_t>(a.node)]) continue;
    out.views.push_back(v);
    out.anchors.push_back(a);
  }
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
  if (robots.empty()) return Status::Error(Status::Code::kInvalidInput, "no robots");
  if (clearance_in && clearance_in->clearance_m.size() != raster.cells.size())
    return Status::Error(Status::Code::kInvalidInput, "clearance size does not match");
  ClearanceRaster computed;
  if (!clearance_in) computed = ComputeClearance(raster, /*unknown_is_obstacle=*/true);
  const ClearanceRaster& clearance = clearance_in ? *clearance_in : computed;
  const int R = static_cast<int>(robots.size());
  result->robots.resize(static_cast<std::size_t>(R));

  ViewSet view_set = ExtractAccessibleViews(raster, clearance, robots, options);
  const GeodesicGrid& grid = view_set.grid;
  std::vector<Anchor>& anchors = view_set.anchors;
  result->views = std::move(view_set.views);
  for (int r = 0; r < R; ++r)
    result->anchored_robots += anchors[static_cast<std::size_t>(r)].node >= 0;
  result->terminated = ShouldTerminate(result->views, options.importance_threshold);
  if (result->terminated) return Status::Ok();
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
  std::vector<ShortestPaths> paths(static_cast<std::size_t>(n_nodes));
  if (!external_matrix || !external_paths) {
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
  problem.capacity = RobotCapacities(K, speeds);
  AssignmentParams assignment_params = options.assignment;
  assignment_params.refine = options.refine;
  result->assignment = AssignTasks(problem, assignment_params);

  // Per robot: open TSP robot → farthest task, geodesic polyline, eq. 5, camera yaw.
  std::vector<double> task_yaw(static_cast<std::size_t>(K));
  for (int k = 0; k < K; ++k)
    task_yaw[static_cast<std::size_t>(k)] = result->views[static_cast<std::size_t>(k)].yaw_rad;
  SmoothingParams smoothing = options.smoothing;
  smoothing.min_clearance_m = options.robot_radius_m;
  std::vector<Status> statuses(static_cast<std::size_t>(R));
  // Provider callbacks (the host's) are only ever called from this thread.
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
    std::vector<Eigen::Vector2d> polyline;
    std::vector<std::pair<int, int>> task_vertices;
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
      task_vertices.emplace_back(static_cast<int>(polyline.size()) - 1, to - R);
      plan.tasks.push_back(to - R);
      from = to;
    }
    if (polyline.empty()) return;
    plan.path = SamplePolyline(polyline, task_vertices, smoothing.sample_spacing_m);
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
