#pragma once
// The 2-D planning map on the floor (Z-up world, planar floor at floor_z_m): the voxel columns
// of a height band above the floor that a ground robot sweeps, projected to a raster of cells
// that are unknown, free, frontier (free and 8-adjacent to unknown) or obstacle. Kept up to date
// from the blocks each frame touched; clearance and geodesic distances over it are in
// planning/geodesic.h. Voxel states come from ClassifyVoxel (core/voxel_state.h) only.
//
// Cell rule, over the band voxels of the cell's columns (voxels whose centre z lies in
// [floor_z_m + band_min_m, floor_z_m + band_max_m]; unallocated voxels are unobserved):
//   obstacle  any band voxel is occupied;
//   free      none is occupied and at least min_free_fraction of them are observed free;
//   unknown   otherwise.
// The floor itself is not checked (a planar world without stairs or holes, as in Dong 2019).
#include <Eigen/Core>
#include <cstdint>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "core/floor_cell.h"
#include "core/image.h"
#include "core/index.h"
#include "core/status.h"
#include "core/voxel_state.h"

namespace voxplan {

class TsdfVolume;

struct FloorMapParams {
  float floor_z_m = 0.0f;
  float band_min_m = 0.1f;  // above the floor: lower than this is floor clutter the robot crosses
  float band_max_m = 1.8f;  // above the floor: the robot's height
  int cell_voxels = 1;      // cell side in voxels: 1, 2, 4 or 8, so a cell never straddles blocks
  // Below 1 a column may keep a few unseen voxels (the sensor rarely sees every band voxel of
  // a column close to the robot) and still be free; 1 demands every one observed.
  float min_free_fraction = 0.9f;
  VoxelStateParams voxel_state;
};

// Where the raster lies: raster cell (ix, iy), 0 <= ix < width, covers world xy
// [(origin_cell + (ix, iy)) * cell_size_m, + cell_size_m); global cell c covers voxel columns
// [c * cell_voxels, (c + 1) * cell_voxels).
struct FloorGeometry {
  Eigen::Vector2i origin_cell = Eigen::Vector2i::Zero();
  int width = 0;
  int height = 0;
  float cell_size_m = 0.0f;

  bool Contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
  size_t Linear(int ix, int iy) const { return size_t(iy) * size_t(width) + size_t(ix); }
  Eigen::Vector2f CellCenter(int ix, int iy) const {
    return {(float(origin_cell.x() + ix) + 0.5f) * cell_size_m,
            (float(origin_cell.y() + iy) + 0.5f) * cell_size_m};
  }
  // Raster coordinates of the cell holding p_W; may lie outside the raster.
  Eigen::Vector2i CellOf(const Eigen::Vector2f& p_W) const {
    return {FloorToInt(p_W.x() / cell_size_m) - origin_cell.x(),
            FloorToInt(p_W.y() / cell_size_m) - origin_cell.y()};
  }
  friend bool operator==(const FloorGeometry&, const FloorGeometry&) = default;
};

class FloorMap {
 public:
  // Throws std::invalid_argument for a non-positive voxel size, a cell side that does not
  // divide a block, a band holding no voxel centre, or a fraction outside (0, 1].
  FloorMap(float voxel_size_m, const FloorMapParams& params);

  // Recomputes the cells over the block columns of `touched_blocks` (any order) that reach into
  // the band, growing the raster to cover them. The result depends only on the volume and the
  // blocks ever passed, never on the thread count; it equals Rebuild() as long as every block
  // changed since was passed. InvalidArgument when the volume's voxel size differs.
  Status Update(const TsdfVolume& volume, std::span<const BlockIndex> touched_blocks);
  // Forgets everything but the marked obstacles and projects every block of the volume.
  Status Rebuild(const TsdfVolume& volume);
  // The cells holding these points (world xy) are obstacles from now on, whatever the volume
  // says: what a robot's bumper ran into, which its camera may never see (too low, or in the
  // blind zone in front of it). Grows the raster to cover them; true when a cell changed.
  bool MarkObstacles(std::span<const Eigen::Vector2f> points_W);
  // A bumper's contacts (world xy) go on the map as MarkObstacles puts them, except one within
  // two cells of an obstacle the volume put there: that is mostly the same obstacle a cell off on
  // the map's grid, and marking it at once narrows doorways, so it goes on the map when it is
  // reported a second time. Returns the contacts that changed the map (empty when none did).
  std::vector<Eigen::Vector2f> MarkContacts(std::span<const Eigen::Vector2f> contacts_W);

  const FloorMapParams& params() const { return params_; }
  const FloorGeometry& geometry() const { return geometry_; }
  int width() const { return geometry_.width; }
  int height() const { return geometry_.height; }
  float cell_size_m() const { return geometry_.cell_size_m; }
  // A stamp of the contents, renewed by every Update / Rebuild that changes a cell or the
  // raster's extent; derived maps (clearance, geodesic fields) are valid for one revision.
  // Stamps increase and are unique in the process (a copy shares its original's until either
  // changes), so a cache keyed on the stamp alone cannot mistake one map for another.
  uint64_t revision() const { return revision_; }

  FloorCell At(int ix, int iy) const {  // kUnknown outside the raster
    return geometry_.Contains(ix, iy) ? cells_[geometry_.Linear(ix, iy)] : FloorCell::kUnknown;
  }
  FloorCell AtPoint(const Eigen::Vector2f& p_W) const {
    const Eigen::Vector2i c = geometry_.CellOf(p_W);
    return At(c.x(), c.y());
  }
  const std::vector<FloorCell>& cells() const { return cells_; }  // row-major, iy then ix
  size_t Count(FloorCell c) const;

 private:
  bool GrowToCover(const std::vector<Eigen::Vector2i>& block_columns);
  bool ProjectBlockColumn(const TsdfVolume& volume, Eigen::Vector2i block_column, float trunc_vox);
  bool UpdateFrontier(const std::vector<Eigen::Vector2i>& block_columns);
  // The global cell (x, y) holding a world point, the key of the marks.
  std::pair<int, int> GlobalCell(const Eigen::Vector2f& p_W) const;
  // Sets the marked global cells to obstacle (growing the raster), then their frontier rings.
  bool ApplyMarks(const std::vector<std::pair<int, int>>& cells);

  float voxel_size_m_;
  FloorMapParams params_;
  int band_z0_ = 0, band_z1_ = 0;  // global voxel z of the band, inclusive
  int required_free_ = 0;          // observed-free band voxels a cell needs
  FloorGeometry geometry_;
  std::vector<FloorCell> cells_;
  std::set<std::pair<int, int>> marked_;                // global cells (x, y) of MarkObstacles
  std::set<std::pair<int, int>> contacts_beside_seen_;  // MarkContacts' first reports there
  uint64_t revision_ = 0;
};

// A from-scratch projection of the whole volume (throws like the FloorMap constructor).
FloorMap ProjectFloor(const TsdfVolume& volume, const FloorMapParams& params);

// The raster as an 8-bit image for writing out: at(ix, iy) holds one of the values below
// (row iy grows with world y, so flip rows for a north-up picture).
inline constexpr uint8_t kFloorPixelObstacle = 0;
inline constexpr uint8_t kFloorPixelUnknown = 128;
inline constexpr uint8_t kFloorPixelFrontier = 200;
inline constexpr uint8_t kFloorPixelFree = 255;
Image<uint8_t> FloorImage(const FloorMap& map);

}  // namespace voxplan
