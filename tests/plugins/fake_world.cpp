#include "tests/plugins/fake_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

#include "core/image.h"
#include "planning/geodesic.h"

namespace voxplan::test {
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

RasterWorld::RasterWorld(int width, int height, float cell_m) {
  floor_.origin_m = {0.f, 0.f};
  floor_.cell_size_m = cell_m;
  floor_.width = width;
  floor_.height = height;
  floor_.revision = 7;
  floor_.cells.assign(size_t(width) * size_t(height), FloorCell::kFree);
  Finish();
}

void RasterWorld::Fill(int x0, int y0, int x1, int y1, FloorCell cell) {
  for (int y = std::max(y0, 0); y <= std::min(y1, floor_.height - 1); ++y) {
    for (int x = std::max(x0, 0); x <= std::min(x1, floor_.width - 1); ++x) {
      floor_.cells[floor_.Linear(x, y)] = cell;
    }
  }
}

void RasterWorld::Walls() {
  Fill(0, 0, floor_.width - 1, 0, FloorCell::kObstacle);
  Fill(0, floor_.height - 1, floor_.width - 1, floor_.height - 1, FloorCell::kObstacle);
  Fill(0, 0, 0, floor_.height - 1, FloorCell::kObstacle);
  Fill(floor_.width - 1, 0, floor_.width - 1, floor_.height - 1, FloorCell::kObstacle);
}

void RasterWorld::Finish() {
  // Frontier: free and 8-adjacent to unknown (re-derived, so earlier marks may go).
  std::vector<FloorCell> cells = floor_.cells;
  for (int y = 0; y < floor_.height; ++y) {
    for (int x = 0; x < floor_.width; ++x) {
      FloorCell& c = cells[floor_.Linear(x, y)];
      if (!IsFree(c)) continue;
      c = FloorCell::kFree;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (floor_.Contains(x + dx, y + dy) &&
              floor_.cells[floor_.Linear(x + dx, y + dy)] == FloorCell::kUnknown) {
            c = FloorCell::kFrontier;
          }
        }
      }
    }
  }
  floor_.cells = cells;
  // Clearance: exact distance from the cell centre to the nearest obstacle cell centre.
  Image<uint8_t> sites(floor_.width, floor_.height, 0);
  for (size_t i = 0; i < cells.size(); ++i) sites.data[i] = cells[i] == FloorCell::kObstacle;
  const Image<float> d2 = SquaredDistanceTransform(sites);
  floor_.clearance_m.resize(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    floor_.clearance_m[i] = std::sqrt(d2.data[i]) * floor_.cell_size_m;
  }
}

PlannerRobot& RasterWorld::AddRobot(int ix, int iy, float radius_m) {
  ScanMode explorer, reconstructor;
  explorer.max_speed_mps = 0.6f;
  explorer.max_range_m = 5.f;
  reconstructor.max_speed_mps = 0.2f;
  reconstructor.horizontal_fov_rad = 0.8f;
  reconstructor.max_range_m = 1.5f;
  PlannerRobot r;
  r.id = uint32_t(10 + robots_.size());
  r.position_m = Center(ix, iy);
  r.radius_m = radius_m;
  r.modes = {explorer, reconstructor};
  robots_.push_back(r);
  return robots_.back();
}

FloorCell RasterWorld::CellAt(const Eigen::Vector2f& p) const {
  const Eigen::Vector2i c = floor_.CellOf(p);
  return floor_.Contains(c.x(), c.y()) ? floor_.cells[floor_.Linear(c.x(), c.y())]
                                       : FloorCell::kUnknown;
}

PlannerMapInfo RasterWorld::MapInfo() const {
  PlannerMapInfo info;
  info.revision = 42;
  info.voxel_size_m = 0.05f;
  info.floor_z_m = 0.f;
  info.bounds_min = {0.f, 0.f, 0.f};
  info.bounds_max = {float(floor_.width) * floor_.cell_size_m,
                     float(floor_.height) * floor_.cell_size_m, 2.f};
  return info;
}

void RasterWorld::VoxelStates(std::span<const Eigen::Vector3f> points,
                              std::span<VoxelState> out) const {
  for (size_t i = 0; i < points.size(); ++i) {
    const FloorCell c = CellAt(points[i].head<2>());
    out[i] = c == FloorCell::kObstacle  ? VoxelState::kOccupied
             : c == FloorCell::kUnknown ? VoxelState::kUnobserved
                                        : VoxelState::kFree;
  }
}

void RasterWorld::Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const {
  constexpr float kStep = 0.01f;
  for (size_t i = 0; i < rays.size(); ++i) {
    PlannerRayHit hit;
    hit.result = RayResult::kMaxRange;
    hit.distance_m = rays[i].max_range_m;
    for (float s = 0.f; s <= rays[i].max_range_m; s += kStep) {
      const Eigen::Vector2f p = (rays[i].origin + s * rays[i].direction).head<2>();
      const Eigen::Vector2i c = floor_.CellOf(p);
      if (!floor_.Contains(c.x(), c.y())) {
        hit = {s, hit.unobserved_m, RayResult::kLeftMap};
        break;
      }
      const FloorCell cell = floor_.cells[floor_.Linear(c.x(), c.y())];
      if (cell == FloorCell::kObstacle) {
        hit = {s, hit.unobserved_m, RayResult::kSurface};
        break;
      }
      if (cell == FloorCell::kUnknown) hit.unobserved_m += kStep;
    }
    out[i] = hit;
  }
}

std::vector<Eigen::Vector3f> RasterWorld::FrontierVoxels() const {
  std::vector<Eigen::Vector3f> v;
  for (int y = 0; y < floor_.height; ++y) {
    for (int x = 0; x < floor_.width; ++x) {
      if (floor_.cells[floor_.Linear(x, y)] == FloorCell::kFrontier) {
        v.emplace_back(Center(x, y).x(), Center(x, y).y(), 0.5f);
      }
    }
  }
  return v;
}

std::vector<SurfaceVoxel> RasterWorld::SurfaceVoxels() const {
  // Obstacle cells with a free 4-neighbour, facing the first one found.
  std::vector<SurfaceVoxel> v;
  const int dirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int y = 0; y < floor_.height; ++y) {
    for (int x = 0; x < floor_.width; ++x) {
      if (floor_.cells[floor_.Linear(x, y)] != FloorCell::kObstacle) continue;
      for (const auto& d : dirs) {
        const int nx = x + d[0], ny = y + d[1];
        if (floor_.Contains(nx, ny) && IsFree(floor_.cells[floor_.Linear(nx, ny)])) {
          SurfaceVoxel s;
          s.position = {Center(x, y).x(), Center(x, y).y(), 0.5f};
          s.normal = {float(d[0]), float(d[1]), 0.f};
          s.uncertainty = 1.f / std::max(surface_weight_, 1e-6f);
          s.weight = surface_weight_;
          v.push_back(s);
          break;
        }
      }
    }
  }
  return v;
}

Result<std::vector<float>> RasterWorld::GeodesicField(const Eigen::Vector2f& source_m,
                                                      float min_clearance_m) const {
  const PlannerFloor& floor = Floor();
  VOXPLAN_RETURN_IF_ERROR(CheckFloor(floor));
  std::vector<float> dist;
  Dijkstra(floor, floor.CellOf(source_m), min_clearance_m, dist, nullptr);
  return dist;
}

Result<std::vector<float>> RasterWorld::DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
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

Result<std::vector<Eigen::Vector2f>> RasterWorld::ShortestPath(const Eigen::Vector2f& from_m,
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

FakeWorld::FakeWorld() : RasterWorld(kWidth, kHeight, kCell) {
  Walls();
  Fill(9, 0, 9, 4, FloorCell::kObstacle);  // wall with a door at y 5..7
  Fill(9, 8, 9, kHeight - 1, FloorCell::kObstacle);
  // The sealed pocket.
  Fill(2, 6, 6, 6, FloorCell::kObstacle);
  Fill(2, 10, 6, 10, FloorCell::kObstacle);
  Fill(2, 6, 2, 10, FloorCell::kObstacle);
  Fill(6, 6, 6, 10, FloorCell::kObstacle);
  Fill(13, 1, 17, 4, FloorCell::kUnknown);
  Finish();

  AddRobot(3, 2, kRobotRadius);
  PlannerRobot& r1 = AddRobot(14, 8, kRobotRadius);
  r1.theta_rad = 0.5f;
  PlannerTask queued;
  queued.position_m = Center(12, 6);
  queued.mode = 1;
  queued.tag = 99;
  r1.queue = {queued};
  r1.executing = true;
}

std::vector<ObjectInstance> FakeWorld::Instances() const {
  ObjectInstance chair;
  chair.id = 3;
  chair.class_id = 56;
  chair.label = "chair";
  chair.bbox_min = {1.f, 1.f, 0.f};
  chair.bbox_max = {1.5f, 1.5f, 0.9f};
  chair.completeness = 0.25f;
  return {chair};
}

RasterWorld ApartmentWorld(float width_m, float height_m, float cell_m, int robots, float known_x_m,
                           float room_m) {
  const int w = int(std::lround(width_m / cell_m)), h = int(std::lround(height_m / cell_m));
  RasterWorld world(w, h, cell_m);
  world.Fill(0, 0, w - 1, 1, FloorCell::kObstacle);
  world.Fill(0, h - 2, w - 1, h - 1, FloorCell::kObstacle);
  world.Fill(0, 0, 1, h - 1, FloorCell::kObstacle);
  world.Fill(w - 2, 0, w - 1, h - 1, FloorCell::kObstacle);
  const int cols = std::max(1, int(std::lround(width_m / room_m)));
  const int rows = std::max(1, int(std::lround(height_m / room_m)));
  const int door = int(std::lround(1.0f / cell_m));
  std::vector<int> xs{0}, ys{0};  // room borders in cells
  for (int c = 1; c <= cols; ++c) xs.push_back(c * w / cols);
  for (int r = 1; r <= rows; ++r) ys.push_back(r * h / rows);
  for (int c = 1; c < cols; ++c) {  // vertical walls, a door in every room's stretch
    world.Fill(xs[c] - 1, 0, xs[c], h - 1, FloorCell::kObstacle);
    for (int r = 0; r < rows; ++r) {
      const int mid = (ys[r] + ys[r + 1]) / 2;
      world.Fill(xs[c] - 1, mid - door / 2, xs[c], mid - door / 2 + door - 1, FloorCell::kFree);
    }
  }
  for (int r = 1; r < rows; ++r) {  // horizontal walls, likewise
    for (int c = 0; c < cols; ++c) {
      world.Fill(xs[c] + 1, ys[r] - 1, xs[c + 1] - 2, ys[r], FloorCell::kObstacle);
      const int mid = (xs[c] + xs[c + 1]) / 2;
      world.Fill(mid - door / 2, ys[r] - 1, mid - door / 2 + door - 1, ys[r], FloorCell::kFree);
    }
  }
  const int known_cells = int(std::lround(known_x_m / cell_m));
  world.Fill(known_cells, 0, w - 1, h - 1, FloorCell::kUnknown);
  world.Finish();
  // Robots at the centres of the known rooms, round robin, 0.5 m apart within a room.
  std::vector<Eigen::Vector2i> centres;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector2i m((xs[c] + xs[c + 1]) / 2, (ys[r] + ys[r + 1]) / 2);
      if (m.x() + int(0.5f / cell_m) < known_cells) centres.push_back(m);
    }
  }
  if (centres.empty()) centres.push_back({known_cells / 2, h / 2});
  const int step = int(std::lround(0.5f / cell_m));
  for (int i = 0; i < robots; ++i) {
    const Eigen::Vector2i m = centres[size_t(i) % centres.size()];
    const int k = i / int(centres.size());
    world.AddRobot(m.x() + (k % 2 ? -1 : 1) * ((k + 1) / 2) * step, m.y(), 0.18f);
  }
  return world;
}

}  // namespace voxplan::test
