#include "tests/plugins/fake_world.h"

#include <cmath>
#include <limits>

namespace voxplan::test {

FakeWorld::FakeWorld() {
  floor_.origin_m = {0.f, 0.f};
  floor_.cell_size_m = kCell;
  floor_.width = kWidth;
  floor_.height = kHeight;
  floor_.revision = 7;
  floor_.cells.assign(size_t(kWidth) * kHeight, FloorCell::kFree);
  auto set = [&](int x, int y, FloorCell c) { floor_.cells[floor_.Linear(x, y)] = c; };
  for (int x = 0; x < kWidth; ++x) {
    set(x, 0, FloorCell::kObstacle);
    set(x, kHeight - 1, FloorCell::kObstacle);
  }
  for (int y = 0; y < kHeight; ++y) {
    set(0, y, FloorCell::kObstacle);
    set(kWidth - 1, y, FloorCell::kObstacle);
    if (y < 5 || y > 7) set(9, y, FloorCell::kObstacle);  // wall with a door at y 5..7
  }
  for (int x = 2; x <= 6; ++x) {  // the sealed pocket
    for (int y = 6; y <= 10; ++y) {
      if (x == 2 || x == 6 || y == 6 || y == 10) set(x, y, FloorCell::kObstacle);
    }
  }
  for (int x = 13; x <= 17; ++x) {
    for (int y = 1; y <= 4; ++y) set(x, y, FloorCell::kUnknown);
  }
  // Frontier: free and 8-adjacent to unknown.
  std::vector<FloorCell> cells = floor_.cells;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if (floor_.cells[floor_.Linear(x, y)] != FloorCell::kFree) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (floor_.Contains(x + dx, y + dy) &&
              floor_.cells[floor_.Linear(x + dx, y + dy)] == FloorCell::kUnknown) {
            cells[floor_.Linear(x, y)] = FloorCell::kFrontier;
          }
        }
      }
    }
  }
  floor_.cells = cells;
  // Clearance: centre to the nearest obstacle cell centre (brute force; the grid is tiny).
  floor_.clearance_m.assign(floor_.cells.size(), std::numeric_limits<float>::infinity());
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      float& c = floor_.clearance_m[floor_.Linear(x, y)];
      for (int oy = 0; oy < kHeight; ++oy) {
        for (int ox = 0; ox < kWidth; ++ox) {
          if (floor_.cells[floor_.Linear(ox, oy)] != FloorCell::kObstacle) continue;
          c = std::min(c, kCell * std::hypot(float(ox - x), float(oy - y)));
        }
      }
    }
  }

  ScanMode explorer, reconstructor;
  explorer.max_speed_mps = 0.6f;
  explorer.max_range_m = 5.f;
  reconstructor.max_speed_mps = 0.2f;
  reconstructor.horizontal_fov_rad = 0.8f;
  reconstructor.max_range_m = 1.5f;
  for (int i = 0; i < 2; ++i) {
    PlannerRobot r;
    r.id = uint32_t(10 + i);
    r.position_m = i == 0 ? Center(3, 2) : Center(14, 8);
    r.theta_rad = 0.5f * float(i);
    r.radius_m = kRobotRadius;
    r.modes = {explorer, reconstructor};
    robots_.push_back(r);
  }
  PlannerTask queued;
  queued.position_m = Center(12, 6);
  queued.mode = 1;
  queued.tag = 99;
  robots_[1].queue = {queued};
  robots_[1].executing = true;
}

FloorCell FakeWorld::CellAt(const Eigen::Vector2f& p) const {
  const Eigen::Vector2i c = floor_.CellOf(p);
  return floor_.Contains(c.x(), c.y()) ? floor_.cells[floor_.Linear(c.x(), c.y())]
                                       : FloorCell::kUnknown;
}

PlannerMapInfo FakeWorld::MapInfo() const {
  PlannerMapInfo info;
  info.revision = 42;
  info.voxel_size_m = 0.05f;
  info.floor_z_m = 0.f;
  info.bounds_min = {0.f, 0.f, 0.f};
  info.bounds_max = {kWidth * kCell, kHeight * kCell, 2.f};
  return info;
}

void FakeWorld::VoxelStates(std::span<const Eigen::Vector3f> points,
                            std::span<VoxelState> out) const {
  for (size_t i = 0; i < points.size(); ++i) {
    const FloorCell c = CellAt(points[i].head<2>());
    out[i] = c == FloorCell::kObstacle  ? VoxelState::kOccupied
             : c == FloorCell::kUnknown ? VoxelState::kUnobserved
                                        : VoxelState::kFree;
  }
}

void FakeWorld::Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const {
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

std::vector<Eigen::Vector3f> FakeWorld::FrontierVoxels() const {
  std::vector<Eigen::Vector3f> v;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if (floor_.cells[floor_.Linear(x, y)] == FloorCell::kFrontier) {
        v.emplace_back(Center(x, y).x(), Center(x, y).y(), 0.5f);
      }
    }
  }
  return v;
}

std::vector<SurfaceVoxel> FakeWorld::SurfaceVoxels() const {
  // Obstacle cells with a free 4-neighbour, facing the first one found.
  std::vector<SurfaceVoxel> v;
  const int dirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if (floor_.cells[floor_.Linear(x, y)] != FloorCell::kObstacle) continue;
      for (const auto& d : dirs) {
        const int nx = x + d[0], ny = y + d[1];
        if (floor_.Contains(nx, ny) && IsFree(floor_.cells[floor_.Linear(nx, ny)])) {
          SurfaceVoxel s;
          s.position = {Center(x, y).x(), Center(x, y).y(), 0.5f};
          s.normal = {float(d[0]), float(d[1]), 0.f};
          s.uncertainty = 0.5f;
          s.weight = 2.f;
          v.push_back(s);
          break;
        }
      }
    }
  }
  return v;
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

}  // namespace voxplan::test
