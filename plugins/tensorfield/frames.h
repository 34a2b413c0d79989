// The tensorfield planner's field over a window around the robot (plugins/tensorfield/README.md,
// "One plan call", steps 1-2): the floor raster cropped to a square window on the floor's own
// grid, the key-frame field of X eq. 3 with the zero-field gap filled by a second, wide blend, the
// previous key frame carried onto the new window, and the K + 1 frames between them (X eq. 4-5).
// Plain data; deterministic; prints nothing.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {

// Floor cell codes, the values of VP_FLOOR_* (plugins/planner_api.h).
enum FloorCode : std::uint8_t {
  kFloorUnknown = 0,
  kFloorFree = 1,
  kFloorFrontier = 2,
  kFloorObstacle = 3
};

// The host's surface voxels in the floor band, per floor cell (the gain's surface term): both
// empty when the planner does not read them.
struct SurfaceCells {
  std::vector<float> uncertainty;       // the cell's least-observed voxel, 0 none, 1 unobserved
  std::vector<Eigen::Vector2f> normal;  // unit xy of the voxels' summed normals; zero: unknown
  bool empty() const { return uncertainty.empty(); }
};

// The host's floor raster as plain data (row-major, cell (x, y) covers origin + [x, x+1) * res).
struct FloorInput {
  omt::RasterGeometry geometry;
  std::vector<std::uint8_t> cells;  // FloorCode per cell
  std::vector<float> clearance_m;   // the host's: cell centre to the nearest obstacle cell
  SurfaceCells surface;             // on the same cells, or empty
};

// A square crop of the floor on its own grid: window cell (x, y) is floor cell (x0 + x, y0 + y);
// cells outside the floor are unknown with clearance 0.
struct FloorWindow {
  omt::RasterGeometry geometry;
  int x0 = 0, y0 = 0;               // floor cell of window cell (0, 0)
  std::vector<std::uint8_t> codes;  // FloorCode
  omt::OccupancyRaster raster;      // obstacle -> occupied, free and frontier -> free
  omt::ClearanceRaster clearance;   // the host's clearance, cropped
  SurfaceCells surface;             // the floor's, cropped (empty when it has none)
};

// The window of half-width radius_m (rounded up to cells) centred on the floor cell holding
// centre_m.
FloorWindow CropFloor(const FloorInput& floor, const Eigen::Vector2d& centre_m, double radius_m);

// The key-frame field's zero gap (tensor_field.h: each basis field is cut at 3σ = 1.5 m, so room
// centres farther than that from every wall have an exactly zero field and no direction). Filled
// by a second blend of the same samples with a wider σ, on a coarser grid and bilinearly
// resampled, added with a small weight to every cell the first blend fills: near walls the first
// blend dominates (the paper's field), beyond about 1 m the wide one gives the direction.
struct FillParams {
  bool enabled = true;
  double sigma_factor = 4.0;  // σ₂ = this × σ (2 m)
  double weight = 0.01;       // of the wide blend against the first
  int coarse_factor = 4;      // the wide blend's grid is this many cells coarser
};

// What the key frame blends from the boundary samples: the paper's tensors, or the vector-field
// baselines' unit normals or tangents (X Fig. 2). A vector field is kept in TensorRaster's two
// components as (vx, vy): sampling, carry-over and both interpolations are component-wise, so the
// baselines share the whole frame pipeline; only advection reads the components differently
// (AdvectionParams::vector_field).
enum class FieldKind : std::uint8_t { kTensor, kVectorNormal, kVectorTangent };

// KeyFrameField (or the vector blend) on the window's raster (frontier counts as free) plus the
// fill. samples_out (optional) receives the boundary samples.
TensorRaster WindowKeyFrame(const FloorWindow& window, const KeyFrameParams& params,
                            const FillParams& fill,
                            std::vector<BoundarySample>* samples_out = nullptr,
                            FieldKind kind = FieldKind::kTensor);

// `field` on `geometry` (same resolution, origin on the same grid): cells both cover keep their
// values and domain; the others take `fallback`'s (which must be on `geometry`).
TensorRaster Reindex(const TensorRaster& field, const TensorRaster& fallback);

}  // namespace voxplan::tensorfield
