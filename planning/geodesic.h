#pragma once
// Distances over the floor map (planning/floor_map.h): clearance to obstacles by an exact Euclidean
// distance transform, geodesic distance fields by Dijkstra on the grid, paths by descending a
// field, and cached geodesic distance matrices between many points (Dong 2019 routes robots by
// such shortest distances on the floor). All distances in metres, between cell centres;
// unreachable is +inf.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "planning/floor_map.h"

namespace voxplan {

// Squared Euclidean distance, in cells^2, from each cell to the nearest cell with
// sites.at(x, y) != 0; +inf when there is none. Exact (Felzenszwalb & Huttenlocher 2012).
Image<float> SquaredDistanceTransform(const Image<uint8_t>& sites);

// Distance in metres from each cell centre to the nearest obstacle cell centre, indexed like
// the raster (at(ix, iy)): 0 on obstacles, +inf when there are none. With
// `unknown_is_obstacle`, unknown cells and everything outside the raster count as obstacles.
Image<float> ComputeClearance(const FloorMap& map, bool unknown_is_obstacle = false);

// Grid moves: 8 = unit and diagonal steps (at most 8.3 % longer than the straight line);
// 16 adds the (1, 2) knight steps (at most 2.8 % longer). No move cuts a corner: every cell
// the straight step passes through must be traversable.
enum class GridConnectivity : uint8_t { k8 = 8, k16 = 16 };

struct GeodesicParams {
  float robot_radius_m = 0.2f;  // traversable cells keep at least this clearance
  bool unknown_traversable = false;
  bool clearance_from_unknown = false;  // clearance also measured to unknown cells
  GridConnectivity connectivity = GridConnectivity::k16;
  // A point off the traversable cells is moved to the nearest one within this radius (the
  // straight-line offset is added to its distances); 0 disables it.
  float snap_radius_m = 0.0f;
  friend bool operator==(const GeodesicParams&, const GeodesicParams&) = default;
};

// 1 where a robot may stand: a free (or, if allowed, unknown) cell with enough clearance.
Image<uint8_t> TraversableCells(const FloorMap& map, const GeodesicParams& params);

struct DistanceField {
  FloorGeometry geometry;
  GridConnectivity connectivity = GridConnectivity::k16;
  Eigen::Vector2i source_cell{-1, -1};  // raster cell at distance 0; outside when none
  Image<float> distance_m;              // at(ix, iy); +inf where unreachable

  bool has_source() const { return geometry.Contains(source_cell.x(), source_cell.y()); }
  float At(int ix, int iy) const;  // +inf outside the raster
};

// The field from one raster cell over a traversable mask; every cell is +inf when the source is
// outside the raster or not traversable.
DistanceField GeodesicField(const Image<uint8_t>& traversable, const FloorGeometry& geometry,
                            Eigen::Vector2i source_cell, GridConnectivity connectivity);

// Nearest traversable raster cell to p_W within `snap_radius_m` (its own cell first; ties in
// row-major order); nullopt when none.
std::optional<Eigen::Vector2i> SnapToTraversable(const Image<uint8_t>& traversable,
                                                 const FloorGeometry& geometry,
                                                 const Eigen::Vector2f& p_W, float snap_radius_m);

// Cell centres from the field's source to target_W (both included) along steepest descent of
// the field; NotFound when the target's cell is outside the raster or unreachable.
Result<std::vector<Eigen::Vector2f>> ExtractPath(const DistanceField& field,
                                                 const Eigen::Vector2f& target_W);

// Geodesic fields and distance matrices, computed once per (map revision, params) and dropped
// when either changes. Not thread-safe; its own work runs in parallel.
class GeodesicCache {
 public:
  // The field from the cell of source_W; a snapped source is the field's source_cell and the
  // field leaves out its offset. Shared, so it outlives an invalidation.
  std::shared_ptr<const DistanceField> Field(const FloorMap& map, const Eigen::Vector2f& source_W,
                                             const GeodesicParams& params);
  // Computes the fields of the sources not cached yet, in parallel (one per source cell).
  void Prefetch(const FloorMap& map, std::span<const Eigen::Vector2f> sources_W,
                const GeodesicParams& params);
  // n x n matrix, row i = distances from points_W[i]; the diagonal is 0. Fields of sources not
  // yet cached are computed in parallel, one per source cell.
  Eigen::MatrixXf DistanceMatrix(const FloorMap& map, std::span<const Eigen::Vector2f> points_W,
                                 const GeodesicParams& params);

  // Cell centres from source_W's cell to target_W's (both snapped per params) over the
  // source's cached field; NotFound when no traversable cell connects them.
  Result<std::vector<Eigen::Vector2f>> Path(const FloorMap& map, const Eigen::Vector2f& source_W,
                                            const Eigen::Vector2f& target_W,
                                            const GeodesicParams& params);

  size_t num_cached_fields() const { return fields_.size(); }
  size_t fields_computed() const { return fields_computed_; }  // since construction
  void Clear();

 private:
  struct Snapped {
    std::optional<Eigen::Vector2i> cell;
    float offset_m = 0.0f;
  };
  void Sync(const FloorMap& map, const GeodesicParams& params);
  Snapped Snap(const Eigen::Vector2f& p_W) const;
  static uint64_t Key(Eigen::Vector2i cell) {
    return (uint64_t(uint32_t(cell.y())) << 32) | uint32_t(cell.x());
  }

  bool synced_ = false;
  uint64_t revision_ = 0;
  GeodesicParams params_;
  FloorGeometry geometry_;
  Image<uint8_t> traversable_;
  std::vector<uint32_t> moves_;  // per cell, the moves that stay on traversable cells
  std::map<uint64_t, std::shared_ptr<const DistanceField>> fields_;
  size_t fields_computed_ = 0;
};

}  // namespace voxplan
