#pragma once
// The PlannerWorld `voxplan explore` shows a planner plugin: the run's planning map (TSDF with
// free-space carving), its floor map with clearance, and the simulated robots. Geodesic queries
// go through GeodesicCache (one per clearance asked for), so fields computed for the host's
// validation and the robots' own routing are shared with the plugin's queries of the same
// floor-map revision; the first field asked for from a robot's position brings every robot's,
// computed in parallel.
#include <map>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "planning/floor_map.h"
#include "planning/geodesic.h"
#include "planning/planning_map.h"
#include "plugins/host/planner_world.h"

namespace voxplan {

struct ExploreWorldParams {
  float wall_height_m = 2.5f;  // top of MapInfo's bounds above the floor
  // A robot standing on cells its camera never saw (right under it) is routed from the nearest
  // traversable cell within this radius.
  float snap_radius_m = 0.5f;
  // The floor map's raster ends where observations end; the world goes on, unknown. The
  // planner's raster adds this much unknown around it, so views at the edge of the known map
  // see unknown space beyond (what frontier views are worth).
  float unknown_margin_m = 3.0f;
};

class ExploreWorld : public PlannerWorld {
 public:
  // The maps must outlive the world; Refresh() after they change and before a plan call.
  ExploreWorld(const PlanningMap& map, const FloorMap& floor, const ExploreWorldParams& params);

  // Rebuilds the planner's floor raster and clearance when the floor map or the robots'
  // footprints changed.
  void Refresh();
  // A robot stood here: the cells under its footprint are free, though its camera never sees
  // them (they are unknown in the floor map, and their neighbours frontier, for good).
  void MarkFootprint(const Eigen::Vector2f& p_W, float radius_m);
  void SetRobots(std::vector<PlannerRobot> robots) { robots_ = std::move(robots); }

  PlannerMapInfo MapInfo() const override;
  void VoxelStates(std::span<const Eigen::Vector3f> points,
                   std::span<VoxelState> out) const override;
  void Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const override;
  std::vector<Eigen::Vector3f> FrontierVoxels() const override;
  std::vector<SurfaceVoxel> SurfaceVoxels() const override;
  const PlannerFloor& Floor() const override { return floor_; }
  std::vector<ObjectInstance> Instances() const override;
  std::vector<PlannerRobot> Robots() const override { return robots_; }

  Result<std::vector<float>> GeodesicField(const Eigen::Vector2f& source_m,
                                           float min_clearance_m) const override;
  Result<std::vector<float>> DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
                                            float min_clearance_m) const override;
  Result<std::vector<Eigen::Vector2f>> ShortestPath(const Eigen::Vector2f& from_m,
                                                    const Eigen::Vector2f& to_m,
                                                    float min_clearance_m) const override;

  // The geodesic settings used for a clearance (known free cells only, snapped sources).
  GeodesicParams Geodesic(float min_clearance_m) const;

 private:
  GeodesicCache& CacheFor(float min_clearance_m) const;

  const PlanningMap* map_;
  const FloorMap* floor_map_;
  ExploreWorldParams params_;
  PlannerFloor floor_;
  int pad_ = 0;  // cells of unknown margin on each side of the floor map's raster
  bool have_floor_ = false;
  uint64_t floor_revision_ = 0;
  std::set<std::pair<int, int>> footprint_cells_;  // global floor cells (x, y), sorted
  bool footprint_changed_ = false;
  std::vector<PlannerRobot> robots_;
  // Keyed by clearance: one cache per robot radius (plus margins) in use, so queries with
  // different clearances do not evict each other's fields.
  mutable std::map<float, GeodesicCache> caches_;
};

}  // namespace voxplan
