#pragma once
// Top-down pictures of exploration runs: a 2-D floor raster (one class per cell) with each
// robot's path in its own colour, start and end marks, and the views it was sent to. Pure
// raster drawing into a ColorImage, so tests can read pixels back and runs write it as PNG.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

// A floor raster in world metres: cell (x, y) covers [origin + res * (x, y), + res), y rows.
struct TopDownRaster {
  Eigen::Vector2f origin_W = Eigen::Vector2f::Zero();
  float resolution_m = 0.05f;
  Image<uint8_t> classes;  // one class per cell, coloured through TopDownParams::class_colors
};

// Cell classes of the default palette (the floor map's own classes map onto these).
enum class TopDownClass : uint8_t { kUnknown = 0, kFree = 1, kObstacle = 2, kFrontier = 3 };

struct TopDownView {
  Eigen::Vector2f position_W = Eigen::Vector2f::Zero();
  float yaw_rad = 0.0f;  // camera heading in the floor plane, counter-clockwise from +x
};

struct TopDownPath {
  std::vector<Eigen::Vector2f> points_W;  // the path travelled, in order
  std::vector<TopDownView> views;         // task views it was sent to
};

// Drawings over the floor and under the paths: a planner's debug layers (its field, skeleton,
// points), world xy, packed RGB colours.
struct TopDownOverlay {
  struct Stroke {
    std::vector<Eigen::Vector2f> points_W;
    uint32_t color = 0;
    bool polyline = true;  // else separate dots
  };
  std::vector<Stroke> strokes;  // drawn in order
};

struct TopDownParams {
  int pixels_per_cell = 2;
  int line_width_px = 2;
  int mark_radius_px = 6;
  std::array<uint32_t, 8> class_colors = {
      PackRgb(200, 200, 200), PackRgb(250, 250, 250), PackRgb(40, 40, 40),
      PackRgb(120, 190, 240), PackRgb(255, 0, 255),   PackRgb(255, 0, 255),
      PackRgb(255, 0, 255),   PackRgb(255, 0, 255)};  // classes above 3: visible magenta
};

// The k-th colour of a categorical palette (Tableau 10), cycling.
uint32_t RobotColor(size_t k);

// Image rows run from +y (top) to -y, as on a map. Refuses an empty raster, a non-positive
// resolution, a scale that would make the picture larger than 16384 pixels a side, and
// non-finite path points.
Result<ColorImage> RenderTopDown(const TopDownRaster& raster, const std::vector<TopDownPath>& paths,
                                 const TopDownParams& params = {},
                                 const TopDownOverlay& overlay = {});

}  // namespace voxplan
