#include "sim/tour.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>

#include "core/parallel.h"

namespace voxplan {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kInf = std::numeric_limits<float>::infinity();

// The plan as a graph of cells where the robot fits. "Fit" uses the footprint inflated by 0.75
// cell: then the straight move between two 8-neighbour fit cells (and any segment whose samples,
// half a cell apart, each round to a fit cell) keeps the real footprint free.
struct Grid {
  const FloorPlan& plan;
  std::vector<uint8_t> fit;
  std::vector<int> component;  // -1 where not fit

  int Index(int x, int y) const { return y * plan.width + x; }
  int X(int i) const { return i % plan.width; }
  int Y(int i) const { return i / plan.width; }
  Eigen::Vector2f Center(int i) const { return plan.CellCenter(X(i), Y(i)); }
  int CellAt(const Eigen::Vector2f& p_W) const {
    const Eigen::Vector2f c = (p_W - plan.origin_W) / plan.resolution_m;
    const int x = int(std::floor(c.x())), y = int(std::floor(c.y()));
    return plan.Contains(x, y) ? Index(x, y) : -1;
  }
  bool Fit(int x, int y) const { return plan.Contains(x, y) && fit[size_t(Index(x, y))]; }

  // Neighbours of cell i with move lengths; diagonals only where both side cells fit too.
  template <typename F>
  void ForNeighbours(int i, F&& f) const {
    const int x = X(i), y = Y(i);
    const float res = plan.resolution_m, diag = res * std::numbers::sqrt2_v<float>;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !Fit(x + dx, y + dy)) continue;
        if (dx != 0 && dy != 0 && !(Fit(x + dx, y) && Fit(x, y + dy))) continue;
        f(Index(x + dx, y + dy), (dx != 0 && dy != 0) ? diag : res);
      }
  }

  bool LineFits(const Eigen::Vector2f& a, const Eigen::Vector2f& b) const {
    const int steps = std::max(1, int(std::ceil((b - a).norm() / (0.5f * plan.resolution_m))));
    for (int k = 0; k <= steps; ++k) {
      const int c = CellAt(a + (b - a) * (float(k) / float(steps)));
      if (c < 0 || !fit[size_t(c)]) return false;
    }
    return true;
  }

  // Line of sight for the camera: no obstacle cell strictly between the two points.
  bool LineOfSight(const Eigen::Vector2f& a, const Eigen::Vector2f& b) const {
    const int steps = int(std::ceil((b - a).norm() / (0.5f * plan.resolution_m)));
    for (int k = 1; k < steps; ++k) {
      const int c = CellAt(a + (b - a) * (float(k) / float(steps)));
      if (c < 0 || plan.cells[size_t(c)] == PlanCell::kObstacle) return false;
    }
    return true;
  }
};

// Grid distance from every cell to the nearest cell that is not free (brushfire, 8-connected).
std::vector<float> Clearance(const FloorPlan& plan) {
  const size_t n = plan.cells.size();
  std::vector<float> dist(n, kInf);
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (size_t i = 0; i < n; ++i)
    if (plan.cells[i] != PlanCell::kFree) {
      dist[i] = 0.f;
      queue.push({0.f, int(i)});
    }
  const float res = plan.resolution_m, diag = res * std::numbers::sqrt2_v<float>;
  while (!queue.empty()) {
    // Plain locals, not a structured binding: the lambda below captures them (clang 14).
    const float d = queue.top().first;
    const int i = queue.top().second;
    queue.pop();
    if (d > dist[size_t(i)]) continue;
    const int x = i % plan.width, y = i / plan.width;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !plan.Contains(x + dx, y + dy)) continue;
        const int j = (y + dy) * plan.width + (x + dx);
        const float nd = d + ((dx != 0 && dy != 0) ? diag : res);
        if (nd < dist[size_t(j)]) {
          dist[size_t(j)] = nd;
          queue.push({nd, j});
        }
      }
  }
  return dist;
}

struct Dijkstra {
  std::vector<float> dist;
  std::vector<int> parent;  // towards the source; -1 at the source and unreached cells
};

Dijkstra RunDijkstra(const Grid& grid, int source) {
  const size_t n = grid.fit.size();
  Dijkstra out{std::vector<float>(n, kInf), std::vector<int>(n, -1)};
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  out.dist[size_t(source)] = 0.f;
  queue.push({0.f, source});
  while (!queue.empty()) {
    // Plain locals, not a structured binding: the lambda below captures them (clang 14).
    const float d = queue.top().first;
    const int i = queue.top().second;
    queue.pop();
    if (d > out.dist[size_t(i)]) continue;
    grid.ForNeighbours(i, [&](int j, float step) {
      const float nd = d + step;
      if (nd < out.dist[size_t(j)]) {
        out.dist[size_t(j)] = nd;
        out.parent[size_t(j)] = i;
        queue.push({nd, j});
      }
    });
  }
  return out;
}

// Open path through all nodes from node 0: nearest neighbour, then 2-opt with 0 fixed.
std::vector<int> OrderViewpoints(const std::vector<std::vector<float>>& d, int rounds) {
  const int n = int(d.size());
  std::vector<int> order = {0};
  std::vector<bool> used(size_t(n), false);
  used[0] = true;
  for (int k = 1; k < n; ++k) {
    const int last = order.back();
    int best = -1;
    for (int j = 0; j < n; ++j)
      if (!used[size_t(j)] &&
          (best < 0 || d[size_t(last)][size_t(j)] < d[size_t(last)][size_t(best)]))
        best = j;
    used[size_t(best)] = true;
    order.push_back(best);
  }
  auto D = [&](int a, int b) { return d[size_t(order[size_t(a)])][size_t(order[size_t(b)])]; };
  for (int round = 0; round < rounds; ++round) {
    bool improved = false;
    for (int i = 1; i + 1 < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const float before = D(i - 1, i) + (j + 1 < n ? D(j, j + 1) : 0.f);
        const float after = D(i - 1, j) + (j + 1 < n ? D(i, j + 1) : 0.f);
        if (after < before - 1e-4f) {
          std::reverse(order.begin() + i, order.begin() + j + 1);
          improved = true;
        }
      }
    if (!improved) break;
  }
  return order;
}

// Emits frames while a robot drives and turns, stepping its clock.
struct Recorder {
  Robot& robot;
  const TourParams& params;
  Tour& tour;

  void Emit() {
    tour.timestamps_s.push_back(robot.clock_s());
    tour.T_W_C.push_back(robot.T_W_C());
  }
  void TurnTo(float heading) {
    const float delta = std::remainder(heading - robot.state().heading_rad, 2.f * kPi);
    const int steps = int(std::ceil(std::abs(delta) / Deg2Rad(params.frame_step_deg) - 1e-4f));
    const float start = robot.state().heading_rad;
    for (int k = 1; k <= steps; ++k) {
      robot.TurnTo(start + delta * float(k) / float(steps));
      Emit();
    }
  }
  Status DriveTo(const Eigen::Vector2f& goal) {
    const Eigen::Vector2f from = robot.state().position_W;
    const float length = (goal - from).norm();
    if (length < 1e-6f) return Status::Ok();
    TurnTo(std::atan2(goal.y() - from.y(), goal.x() - from.x()));
    const int steps = std::max(1, int(std::ceil(length / params.frame_step_m - 1e-4f)));
    for (int k = 1; k <= steps; ++k) {
      VOXPLAN_RETURN_IF_ERROR(robot.DriveTo(from + (goal - from) * (float(k) / float(steps))));
      Emit();
    }
    return Status::Ok();
  }
  // Tilts the camera to `pitch_deg` in steps of at most frame_step_deg, a frame after each.
  Status TiltTo(float pitch_deg) {
    const float start = robot.state().camera_pitch_rad;
    const float delta = Deg2Rad(pitch_deg) - start;
    const int steps = int(std::ceil(std::abs(delta) / Deg2Rad(params.frame_step_deg) - 1e-4f));
    for (int k = 1; k <= steps; ++k) {
      VOXPLAN_RETURN_IF_ERROR(robot.SetCameraPitch(start + delta * float(k) / float(steps)));
      Emit();
    }
    return Status::Ok();
  }
  Status Spin() {
    robot.Dwell();
    Emit();
    const int steps = std::max(1, int(std::ceil(360.f / params.frame_step_deg - 1e-4f)));
    for (const float pitch_deg : params.spin_pitches_deg) {
      VOXPLAN_RETURN_IF_ERROR(TiltTo(pitch_deg));
      const float start = robot.state().camera_yaw_rad;
      for (int k = 1; k <= steps; ++k) {
        robot.SetCameraYaw(start + 2.f * kPi * float(k) / float(steps));
        robot.Dwell();
        Emit();  // the last one repeats the first view: later turns then start from it
      }
      robot.WrapCameraYaw();
    }
    return TiltTo(params.camera_pitch_deg);
  }
};

}  // namespace

Status TourParams::Validate() const {
  VOXPLAN_RETURN_IF_ERROR(robot.Validate());
  if (!(view_range_m > 0.f)) return InvalidArgument("TourParams: view_range_m must be > 0");
  if (!(candidate_spacing_m > 0.f))
    return InvalidArgument("TourParams: candidate_spacing_m must be > 0");
  if (!(min_coverage >= 0.f && min_coverage <= 1.f))
    return InvalidArgument("TourParams: min_coverage must be in [0, 1]");
  if (min_gain_cells < 1) return InvalidArgument("TourParams: min_gain_cells must be >= 1");
  if (!(frame_step_m > 0.f) || !(frame_step_deg > 0.f && frame_step_deg <= 90.f))
    return InvalidArgument("TourParams: frame_step_m must be > 0, frame_step_deg in (0, 90]");
  if (!(std::abs(camera_pitch_deg) <= robot.max_abs_pitch_deg))
    return InvalidArgument("TourParams: camera_pitch_deg beyond the robot's pitch limit");
  if (spin_pitches_deg.empty())
    return InvalidArgument("TourParams: spin_pitches_deg needs at least one pitch");
  for (const float pitch_deg : spin_pitches_deg)
    if (!(std::abs(pitch_deg) <= robot.max_abs_pitch_deg))
      return InvalidArgument("TourParams: spin pitch " + std::to_string(pitch_deg) +
                             " deg is beyond the robot's pitch limit of " +
                             std::to_string(robot.max_abs_pitch_deg) + " deg");
  if (start_W && !start_W->allFinite()) return InvalidArgument("TourParams: start is not finite");
  return Status::Ok();
}

Result<Tour> PlanTour(const FloorPlan& plan, const std::vector<Room>& rooms,
                      const TourParams& params) {
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  if (plan.width <= 0 || plan.height <= 0 ||
      plan.cells.size() != size_t(plan.width) * size_t(plan.height) || !(plan.resolution_m > 0.f))
    return InvalidArgument("PlanTour: empty or inconsistent floor plan");
  const size_t n = plan.cells.size();
  const float res = plan.resolution_m;
  const float radius = params.robot.radius_m;

  // 1. Cells where the (inflated) footprint fits, and their connected pieces.
  Grid grid{plan, std::vector<uint8_t>(n, 0), std::vector<int>(n, -1)};
  const std::vector<float> clearance = Clearance(plan);
  const float fit_clearance = radius + 0.75f * res;
  ParallelFor(n, 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      if (clearance[i] > fit_clearance - 0.5f * res)  // cheap pre-test; exact check below
        grid.fit[i] = FootprintFree(plan, grid.Center(int(i)), fit_clearance) ? 1 : 0;
  });
  std::vector<size_t> component_size;
  for (size_t i = 0; i < n; ++i) {
    if (!grid.fit[i] || grid.component[i] >= 0) continue;
    const int id = int(component_size.size());
    size_t size = 0;
    std::vector<int> stack = {int(i)};
    grid.component[i] = id;
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      ++size;
      grid.ForNeighbours(c, [&](int j, float) {
        if (grid.component[size_t(j)] < 0) {
          grid.component[size_t(j)] = id;
          stack.push_back(j);
        }
      });
    }
    component_size.push_back(size);
  }
  if (component_size.empty()) {
    const size_t free_cells =
        size_t(std::count(plan.cells.begin(), plan.cells.end(), PlanCell::kFree));
    return InvalidArgument("PlanTour: no free cell leaves room for a robot of radius " +
                           std::to_string(radius) + " m (" + std::to_string(free_cells) + " of " +
                           std::to_string(n) + " floor plan cells are free)");
  }
  int chosen =
      int(std::max_element(component_size.begin(), component_size.end()) - component_size.begin());
  int start_cell = -1;
  if (params.start_W) {
    start_cell = grid.CellAt(*params.start_W);
    if (start_cell < 0 || !grid.fit[size_t(start_cell)])
      return InvalidArgument("PlanTour: start (" + std::to_string(params.start_W->x()) + ", " +
                             std::to_string(params.start_W->y()) +
                             ") is outside the plan or too close to an obstacle");
    chosen = grid.component[size_t(start_cell)];
  }
  auto reachable = [&](int i) { return i >= 0 && grid.component[size_t(i)] == chosen; };

  Tour tour;
  // 2a. Viewpoints: the start, then one per room.
  std::vector<int> viewpoint_cells;
  std::vector<int> viewpoint_rooms;
  auto room_of = [&](int cell) {
    for (size_t r = 0; r < rooms.size(); ++r)
      if (rooms[r].footprint_W.contains(grid.Center(cell))) return int(r);
    return -1;
  };
  if (start_cell >= 0) {
    viewpoint_cells.push_back(start_cell);
    viewpoint_rooms.push_back(room_of(start_cell));
  }
  for (size_t r = 0; r < rooms.size(); ++r) {
    const Eigen::AlignedBox2f& box = rooms[r].footprint_W;
    float best_clearance = 0.f;
    std::vector<int> cells;
    for (size_t i = 0; i < n; ++i)
      if (reachable(int(i)) && box.contains(grid.Center(int(i)))) {
        cells.push_back(int(i));
        best_clearance = std::max(best_clearance, clearance[i]);
      }
    if (cells.empty()) {
      tour.unreachable_rooms.push_back(int(r));
      continue;
    }
    // Near the centre, but away from furniture: among cells with at least half the room's best
    // clearance (capped at 1 m, enough for any view).
    const float wanted = std::min(0.5f * best_clearance, 1.0f);
    int best = -1;
    float best_d = kInf;
    for (int c : cells) {
      if (clearance[size_t(c)] < wanted) continue;
      const float d = (grid.Center(c) - box.center()).squaredNorm();
      if (d < best_d) best = c, best_d = d;
    }
    viewpoint_cells.push_back(best);
    viewpoint_rooms.push_back(int(r));
  }

  // 2b. Greedy cover of the reachable cells, sampled every ~0.2 m.
  const int target_stride = std::max(1, int(std::lround(0.2f / res)));
  const int candidate_stride = std::max(1, int(std::lround(params.candidate_spacing_m / res)));
  std::vector<int> targets, candidates;
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x) {
      const int i = grid.Index(x, y);
      if (!reachable(i)) continue;
      if (x % target_stride == 0 && y % target_stride == 0) targets.push_back(i);
      if (x % candidate_stride == 0 && y % candidate_stride == 0) candidates.push_back(i);
    }
  if (targets.empty()) targets.push_back(viewpoint_cells.empty() ? -1 : viewpoint_cells[0]);
  if (targets[0] < 0) {  // tiny piece: its first cell
    for (size_t i = 0; i < n; ++i)
      if (reachable(int(i))) {
        targets[0] = int(i);
        break;
      }
  }
  const float range2 = params.view_range_m * params.view_range_m;
  auto sees = [&](int from) {
    std::vector<int> seen;
    const Eigen::Vector2f p = grid.Center(from);
    for (size_t t = 0; t < targets.size(); ++t) {
      const Eigen::Vector2f q = grid.Center(targets[t]);
      if ((q - p).squaredNorm() <= range2 && grid.LineOfSight(p, q)) seen.push_back(int(t));
    }
    return seen;
  };
  std::vector<std::vector<int>> candidate_sees(candidates.size());
  ParallelFor(candidates.size(), 4, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) candidate_sees[c] = sees(candidates[c]);
  });
  std::vector<uint8_t> covered(targets.size(), 0);
  size_t covered_count = 0;
  auto cover = [&](const std::vector<int>& seen) {
    for (int t : seen) covered_count += covered[size_t(t)] ? 0 : 1, covered[size_t(t)] = 1;
  };
  for (int c : viewpoint_cells) cover(sees(c));
  while (double(covered_count) < params.min_coverage * double(targets.size())) {
    int best = -1;
    int best_gain = 0;
    for (size_t c = 0; c < candidates.size(); ++c) {
      int gain = 0;
      for (int t : candidate_sees[c]) gain += covered[size_t(t)] ? 0 : 1;
      if (gain > best_gain) best = int(c), best_gain = gain;
    }
    // The first viewpoint is taken whatever it adds (a small piece may have few cells).
    if (best < 0 || (best_gain < params.min_gain_cells && !viewpoint_cells.empty())) break;
    cover(candidate_sees[size_t(best)]);
    viewpoint_cells.push_back(candidates[size_t(best)]);
    viewpoint_rooms.push_back(-1);
  }
  if (viewpoint_cells.empty()) {  // no candidate sees anything: stand at the first target
    viewpoint_cells.push_back(targets[0]);
    viewpoint_rooms.push_back(-1);
    cover(sees(targets[0]));
  }
  tour.reachable_cells = size_t(component_size[size_t(chosen)]);
  tour.coverage = double(covered_count) / double(targets.size());

  // 3. Order on grid path lengths.
  const size_t m = viewpoint_cells.size();
  std::vector<Dijkstra> trees(m);
  ParallelFor(m, 1, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) trees[k] = RunDijkstra(grid, viewpoint_cells[k]);
  });
  std::vector<std::vector<float>> d(m, std::vector<float>(m, 0.f));
  for (size_t a = 0; a < m; ++a)
    for (size_t b = 0; b < m; ++b) d[a][b] = trees[b].dist[size_t(viewpoint_cells[a])];
  const std::vector<int> order = OrderViewpoints(d, params.two_opt_rounds);

  // 4. Drive it.
  RobotState start;
  start.position_W =
      params.start_W ? *params.start_W : grid.Center(viewpoint_cells[size_t(order[0])]);
  start.camera_pitch_rad = Deg2Rad(params.camera_pitch_deg);
  auto robot = Robot::Create(params.robot, plan, start, params.mode);
  if (!robot.ok()) return robot.status().WithContext("PlanTour");
  Recorder rec{*robot, params, tour};
  for (size_t k = 0; k < m; ++k) {
    const int cell = viewpoint_cells[size_t(order[k])];
    if (k > 0) {
      // Grid path from the previous viewpoint, following the parents towards this one.
      const Dijkstra& tree = trees[size_t(order[k])];
      std::vector<Eigen::Vector2f> path;
      for (int c = viewpoint_cells[size_t(order[k - 1])]; c >= 0; c = tree.parent[size_t(c)])
        path.push_back(grid.Center(c));
      // Shortcut: from each kept point, go straight to the farthest point still in reach.
      size_t i = 0;
      while (i + 1 < path.size()) {
        size_t j = i + 1;
        while (j + 1 < path.size() && grid.LineFits(path[i], path[j + 1])) ++j;
        VOXPLAN_RETURN_IF_ERROR(rec.DriveTo(path[j]).WithContext("PlanTour"));
        i = j;
      }
    } else if ((robot->state().position_W - grid.Center(cell)).norm() > 1e-6f) {
      VOXPLAN_RETURN_IF_ERROR(rec.DriveTo(grid.Center(cell)).WithContext("PlanTour"));
    }
    tour.viewpoints_W.push_back(robot->state().position_W);
    tour.viewpoint_room.push_back(viewpoint_rooms[size_t(order[k])]);
    VOXPLAN_RETURN_IF_ERROR(rec.Spin().WithContext("PlanTour"));
  }
  tour.length_m = robot->distance_m();
  tour.duration_s = robot->clock_s();
  return tour;
}

}  // namespace voxplan
