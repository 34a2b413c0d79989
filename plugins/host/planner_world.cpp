#include "plugins/host/planner_world.h"

#include <cmath>
#include <limits>
#include <queue>
#include <utility>

namespace voxplan {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int32_t kNoParent = -1;

// 8-connected Dijkstra from the source cell; diagonal steps need both side cells traversable so
// a path never cuts an obstacle corner. Deterministic: ties pop in cell order.
void Dijkstra(const PlannerFloor& floor, Eigen::Vector2i source, float min_clearance_m,
              std::vector<float>& dist, std::vector<int32_t>* parent) {
  const size_t n = size_t(floor.width) * size_t(floor.height);
  dist.assign(n, kInf);
  if (parent) parent->assign(n, kNoParent);
  if (!floor.Contains(source.x(), source.y())) return;
  using Entry = std::pair<float, int64_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  const size_t s = floor.Linear(source.x(), source.y());
  dist[s] = 0.f;
  open.push({0.f, int64_t(s)});
  const float diagonal = std::sqrt(2.f) * floor.cell_size_m;
  while (!open.empty()) {
    const auto [d, li] = open.top();
    open.pop();
    if (d > dist[size_t(li)]) continue;
    const int x = int(li % floor.width), y = int(li / floor.width);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) continue;
        const int nx = x + dx, ny = y + dy;
        if (!floor.Traversable(nx, ny, min_clearance_m)) continue;
        if (dx != 0 && dy != 0 &&
            (!floor.Traversable(x + dx, y, min_clearance_m) ||
             !floor.Traversable(x, y + dy, min_clearance_m))) {
          continue;
        }
        const float nd = d + (dx != 0 && dy != 0 ? diagonal : floor.cell_size_m);
        const size_t ni = floor.Linear(nx, ny);
        if (nd < dist[ni]) {
          dist[ni] = nd;
          if (parent) (*parent)[ni] = int32_t(li);
          open.push({nd, int64_t(ni)});
        }
      }
    }
  }
}

Status CheckFloor(const PlannerFloor& floor) {
  const size_t n = size_t(floor.width) * size_t(floor.height);
  if (floor.width <= 0 || floor.height <= 0 || !(floor.cell_size_m > 0.f)) {
    return Unsupported("the world has no floor raster");
  }
  if (floor.cells.size() != n || floor.clearance_m.size() != n) {
    return InvalidArgument("floor raster arrays do not match its size");
  }
  return Status::Ok();
}

}  // namespace

Eigen::Vector2i PlannerFloor::CellOf(const Eigen::Vector2f& p_W) const {
  const Eigen::Vector2f q = (p_W - origin_m) / cell_size_m;
  return {int(std::floor(q.x())), int(std::floor(q.y()))};
}

bool PlannerFloor::Traversable(int ix, int iy, float min_clearance_m) const {
  if (!Contains(ix, iy)) return false;
  const size_t i = Linear(ix, iy);
  return IsFree(cells[i]) && clearance_m[i] >= min_clearance_m;
}

Result<std::vector<float>> PlannerWorld::GeodesicField(const Eigen::Vector2f& source_m,
                                                       float min_clearance_m) const {
  const PlannerFloor& floor = Floor();
  VOXPLAN_RETURN_IF_ERROR(CheckFloor(floor));
  std::vector<float> dist;
  Dijkstra(floor, floor.CellOf(source_m), min_clearance_m, dist, nullptr);
  return dist;
}

Result<std::vector<float>> PlannerWorld::DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
                                                        float min_clearance_m) const {
  const PlannerFloor& floor = Floor();
  VOXPLAN_RETURN_IF_ERROR(CheckFloor(floor));
  const size_t n = points_m.size();
  std::vector<float> matrix(n * n, kInf);
  std::vector<float> dist;
  for (size_t i = 0; i < n; ++i) {
    Dijkstra(floor, floor.CellOf(points_m[i]), min_clearance_m, dist, nullptr);
    for (size_t j = 0; j < n; ++j) {
      const Eigen::Vector2i c = floor.CellOf(points_m[j]);
      if (floor.Contains(c.x(), c.y())) matrix[i * n + j] = dist[floor.Linear(c.x(), c.y())];
    }
  }
  return matrix;
}

Result<std::vector<Eigen::Vector2f>> PlannerWorld::ShortestPath(const Eigen::Vector2f& from_m,
                                                                const Eigen::Vector2f& to_m,
                                                                float min_clearance_m) const {
  const PlannerFloor& floor = Floor();
  VOXPLAN_RETURN_IF_ERROR(CheckFloor(floor));
  std::vector<float> dist;
  std::vector<int32_t> parent;
  Dijkstra(floor, floor.CellOf(from_m), min_clearance_m, dist, &parent);
  const Eigen::Vector2i goal = floor.CellOf(to_m);
  if (!floor.Contains(goal.x(), goal.y()) ||
      !std::isfinite(dist[floor.Linear(goal.x(), goal.y())])) {
    return NotFound("no traversable path between the points");
  }
  std::vector<Eigen::Vector2f> reversed = {to_m};
  for (int32_t c = parent[floor.Linear(goal.x(), goal.y())]; c != kNoParent;
       c = parent[size_t(c)]) {
    if (parent[size_t(c)] == kNoParent) break;  // the source cell: `from` stands for it
    reversed.push_back(floor.CellCenter(c % floor.width, c / floor.width));
  }
  reversed.push_back(from_m);
  if (reversed.size() == 2 && from_m == to_m) reversed.pop_back();
  return std::vector<Eigen::Vector2f>(reversed.rbegin(), reversed.rend());
}

}  // namespace voxplan
