// Plugin-side glue shared by the omt, greedy and voronoi planners: the host's world, read
// through vp::WorldView only, as the OMT algorithms' inputs (plugins/omt/algorithms/types.h); their
// JSON options; tasks and paths for the output. Links no voxplan library, like every plugin.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "plugins/omt/algorithms/planner.h"
#include "plugins/planner_cpp.h"

namespace voxplan::planners {

// A planner's JSON options: typed reads with defaults and ranges. Invalid JSON, a wrong type, a
// value out of range and a key no read asked for are refused with a vp::Error naming the planner
// and the key, so a typo in a config never passes silently.
class JsonOptions {
 public:
  JsonOptions(std::string planner, const std::string& json_text);
  double Number(const std::string& key, double fallback, double min, double max);
  int Integer(const std::string& key, int fallback, int min, int max);
  bool Flag(const std::string& key, bool fallback);
  std::string Choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& allowed);
  // Throws for keys none of the reads above asked for; call after the last read.
  void RejectUnknownKeys() const;

 private:
  [[noreturn]] void Fail(const std::string& key, const std::string& why) const;
  const nlohmann::json* Find(const std::string& key);

  std::string planner_;
  nlohmann::json json_;
  std::set<std::string> read_;
};

// Options all three planners share; JSON keys are the member names.
struct CommonOptions {
  // kappa, importance_threshold, geodesic_cell_m, num_threads (and, for omt, the ablations).
  omt::PlannerOptions omt;
  double robot_radius_m = 0.0;  // <= 0: the largest robot radius of the world
  // Added to the radius for the host's geodesic queries and omt's smoothed paths: the host's own
  // routes keep as much (ExploreParams::route_margin_m), and a path that grazes a known wall on the
  // offset grid of the true floor collides there.
  double clearance_margin_m = 0.05;
  double dwell_s = 0.5;               // standing time at a view, so the sensor takes it in
  double surface_min_height_m = 0.1;  // surface voxels lower than this above the floor are floor
  // Geodesics of the omt pass: "host" (distance_matrix / shortest_path, the distances the host
  // validates with) or "internal" (the algorithms' own coarse grid, faster on big floors).
  std::string geodesics = "host";
  // Views' field of view: the robots' current scanning mode's (the narrowest) instead of the
  // paper's 58° Kinect.
  bool fov_from_robot = false;
};
CommonOptions ReadCommonOptions(JsonOptions& json);

struct WorldInput {
  vp_map_info map{};
  std::vector<vp_robot> robots;
  std::vector<omt::RobotState> states;  // position, camera world yaw, speed of the current mode
  // The floor raster: obstacle -> occupied, free and frontier -> free, unknown -> unknown; per
  // obstacle cell the mean TSDF weight of the surface voxels above it (the §3.2 uncertainty
  // 1 / (1 + w) of the slice the robot sees; 0, i.e. unscanned, when it has none).
  omt::OccupancyRaster raster;
  omt::ClearanceRaster clearance;  // the host's: distance to the nearest obstacle cell
  double robot_radius_m = 0.0;     // views, paths and the internal grid keep this
  float min_clearance_m = 0.f;     // for host geodesic queries: robot_radius_m + margin
  double surface_voxels_ms = 0.0;  // spent in the host's surface voxel query
  double fov_rad = 0.0;            // narrowest horizontal FOV of the robots' modes; 0: unknown
  double vfov_rad = 0.0;           // narrowest vertical FOV of the robots' modes; 0: unknown
  double range_m = 0.0;            // shortest depth range of the robots' modes; 0: unknown
  // ReadHostReach: per robot the host's geodesic field (min_clearance_m; host memory, valid
  // during the plan call), the cells any of them reaches, and how many robots reach any cell (a
  // robot the host cannot place reaches none).
  std::vector<std::span<const float>> robot_fields;
  std::vector<uint8_t> accessible;
  int anchored_robots = 0;
};
// vp::Error for a floor raster without cells.
WorldInput ReadWorld(const vp::WorldView& world, const CommonOptions& options);

// Fills input->robot_fields, accessible and anchored_robots from the host's geodesic fields, the
// traversability the host validates tasks with (known free cells, 16-connected, snapped robots).
void ReadHostReach(const vp::WorldView& world, WorldInput* input);

// Cells the robots looked at from their views and the map did not resolve, kept across calls
// (a planner's state). The floor raster's 2-D model overrates some cells: a column counts as
// free only once most of its height band is observed, and a level camera with a 3 m depth limit
// never sees all of it in a long corridor or right in front of the robot. Such a cell would keep
// a view important forever and the robot would take it again and again; once an idle robot has
// looked at it (dwelled at its view, captured) and it is still unknown, or a surface still
// unscanned, it is settled: never queued nor counted again (omt::OccupancyRaster::settled).
class SettledCells {
 public:
  // Adds the unresolved cells of every idle robot's camera fan (between the sensor's near and
  // far range, up to the first surface on each ray; unknown floor only where the camera, at its
  // pitch, saw the floor: VisibleFloor). Only a robot that took its view counts: one
  // standing at the last task it was sent to (or never sent anywhere, or told to stop). A robot
  // whose task failed adds nothing until it has reached a task sent after the failure: it
  // stopped where a drive was refused, often facing the very space it could not get to.
  void Update(const vp::WorldView& world, const WorldInput& input, const omt::SensorParams& sensor,
              const omt::UncertaintyParams& uncertainty);
  // Update, then input->raster.settled = Mask(its geometry).
  void Apply(const vp::WorldView& world, const omt::PlannerOptions& options, WorldInput* input);
  // The settled flags over this call's raster (its origin moves as the map grows).
  std::vector<uint8_t> Mask(const omt::RasterGeometry& g) const;
  size_t size() const { return cells_.size(); }

  // Robot r's queue was just replaced by `tasks` (none: told to stop where it is), the task
  // views views[ids] over raster g. When r is next idle at the last of them it has taken their
  // targets: a target taken kRepeatLimit times whose view still comes back is settled, with
  // every cell of r's fan up to the first surface, whatever its uncertainty (a surface whose
  // weight never rises would otherwise hold its view forever).
  void Sent(uint32_t r, std::span<const vp_task> tasks, const omt::RasterGeometry& g,
            const std::vector<omt::TaskView>& views, const std::vector<int>& ids);
  static constexpr int kRepeatLimit = 2;

 private:
  using Key = std::pair<long, long>;  // global cell (floor(x / res), floor(y / res))
  Key KeyOf(const omt::RasterGeometry& g, int cell) const;
  bool TookItsView(uint32_t r, const vp_robot& robot) const;
  std::set<Key> cells_;
  std::map<uint32_t, std::vector<Key>> given_;  // per robot: targets of its last tasks
  std::map<Key, int> taken_;                    // per target: views of it taken so far
  std::map<uint32_t, Eigen::Vector2f> goal_;    // per robot: where its queue ends
  std::set<uint32_t> stalled_;                  // robots whose task failed since they were sent
};

// options.omt for this world: its robot radius; views (and settled fans) no wider and no longer
// than the robots' camera sees (fov_from_robot: exactly as wide); the importance threshold
// scaled by what such a view can see against the sensor it was set for (ViewCapacity), so it
// asks the same share of a full view of any camera. Unchanged for a camera at least as wide and
// long as the paper's sensor.
omt::PlannerOptions PassOptions(const CommonOptions& options, const WorldInput& input);

// The host's distance_matrix / shortest_path as the OMT pass's geodesics; *host_ms accumulates
// the milliseconds spent inside those host calls.
omt::GeodesicProvider HostGeodesics(const vp::WorldView& world, float min_clearance_m,
                                    double* host_ms);

// Base heading into each polyline point: the direction of the segment arriving there (the first
// point, and points after a zero-length step, keep the previous heading, starting from
// start_theta_rad).
std::vector<vp_path_point> PathWithHeadings(const std::vector<Eigen::Vector2d>& points_m,
                                            double start_theta_rad);

// The floor a camera camera_height_m up, pitched by pitch_rad (positive up), sees within its
// vertical field of view vfov_rad and range_m, as horizontal distances [near_m, far_m]: from
// h / tan(vfov / 2 - pitch) (0 when it sees straight down) to range_m, or nearer when the whole
// field looks below the horizon. A level 45° camera 1.2 m up sees no floor nearer than 2.9 m.
// An unknown field (0) or height: [0, range_m].
struct FloorBand {
  double near_m = 0.0, far_m = 0.0;
};
FloorBand VisibleFloor(double camera_height_m, double vfov_rad, double pitch_rad, double range_m);

// The camera pitch for `view`: level, unless its target is unknown floor that a level camera
// would not see (nearer than VisibleFloor's near_m); then tilted down just enough to bring the
// target cell's near edge into the field of view. Within the robot's pitch limits.
float ViewPitch(const omt::TaskView& view, const vp_robot& robot, double vfov_rad);

// The task of standing at `view` with the base at theta_rad (the direction of travel), the
// camera turned so it looks at the view's target, pitched by ViewPitch, in the robot's current
// mode. tag = the view's target cell, so a later call can recognise it.
vp_task TaskFromView(const omt::TaskView& view, double theta_rad, const vp_robot& robot,
                     double vfov_rad, double dwell_s);

// Points of a view layer for the debug drawing: view positions at the robot's camera height.
std::vector<float> ViewPointsXyz(const std::vector<omt::TaskView>& views, float z_m);

}  // namespace voxplan::planners
