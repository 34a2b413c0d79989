#pragma once
// The ground-truth 2-D floor plan of a world: which cells of a horizontal raster a robot body
// could occupy. Robots check collisions and tours pick viewpoints on it; the generator and
// `voxplan sim scene` write it out as an image.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/status.h"
#include "sim/world.h"

namespace voxplan {

// A true-plan cell (not planning/floor_map.h's FloorCell, the robots' own map: explore uses both).
enum class PlanCell : uint8_t {
  kFree = 0,      // floor below, nothing in the height band above
  kObstacle = 1,  // a triangle crosses the height band over this cell
  kOutside = 2,   // no floor below (outside the building)
};

struct FloorPlanParams {
  float resolution_m = 0.05f;
  float min_z_m = 0.1f;  // height band that blocks a robot, above the floor at z = 0
  float max_z_m = 1.8f;
  // A floor triangle is a roughly horizontal one (|n_z| >= 0.7 |n|, either orientation) at a
  // height in [floor_min_z_m, min_z_m) over the cell centre.
  float floor_min_z_m = -0.5f;
  // Cells inside a closed solid that spans the whole band (a wall's core, a tall wardrobe) have
  // no triangle in the band; with fill_solids they are obstacles too: the upward ray from
  // (cell centre, min_z_m) first meets the back of a face (normal pointing up). Relies on
  // outward-facing normals: a single-sided surface facing up above the band (a roof without a
  // ceiling) would read as solid; turn it off for such scenes.
  bool fill_solids = true;
};

struct FloorPlan {
  Eigen::Vector2f origin_W = Eigen::Vector2f::Zero();  // world x, y of cell (0, 0)'s corner
  float resolution_m = 0.05f;
  int width = 0, height = 0;    // cells along x and y
  std::vector<PlanCell> cells;  // row-major, y rows

  bool Contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  PlanCell at(int x, int y) const { return cells[size_t(y) * width + x]; }
  Eigen::Vector2f CellCenter(int x, int y) const {
    return origin_W + resolution_m * Eigen::Vector2f(x + 0.5f, y + 0.5f);
  }
};

Result<FloorPlan> RasterizeFloorPlan(const World& world, const FloorPlanParams& params = {});

}  // namespace voxplan
