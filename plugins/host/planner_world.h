#pragma once
// What the engine shows a planner plugin, as a C++ interface: `voxplan explore` implements it
// over the real maps (TSDF volume, floor map, objects, simulated robots); tests implement it over
// a small grid. The plugin host adapts it to the C table of plugins/planner_api.h, so a plugin
// never sees these types. Geodesic queries have no default: a world answers them from its own
// distance fields, so the host never runs a second geodesic engine beside the world's.
//
// Frames and units as in planner_api.h: world Z up, metres, radians; yaw from +x towards +y.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "core/floor_cell.h"
#include "core/status.h"
#include "core/voxel_state.h"

namespace voxplan {

struct PlannerMapInfo {
  uint64_t revision = 0;  // changes whenever the maps change
  float voxel_size_m = 0.f;
  float floor_z_m = 0.f;
  Eigen::Vector3f bounds_min = Eigen::Vector3f::Zero();  // where tasks may lie
  Eigen::Vector3f bounds_max = Eigen::Vector3f::Zero();
};

struct PlannerRay {
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();  // unit length
  float max_range_m = 0.f;
};
enum class RayResult : int32_t { kMaxRange = 0, kSurface = 1, kLeftMap = 2 };
struct PlannerRayHit {
  float distance_m = 0.f;    // to the first occupied voxel, or where the ray stopped
  float unobserved_m = 0.f;  // unobserved length crossed before distance_m
  RayResult result = RayResult::kMaxRange;
};

struct SurfaceVoxel {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // outward unit, zero when unknown
  float uncertainty = 1.f;                           // 0 well observed .. 1 barely
  float weight = 0.f;
  int32_t instance = -1;
};

struct ObjectInstance {
  uint32_t id = 0;
  int32_t class_id = -1;
  std::string label;
  Eigen::Vector3f bbox_min = Eigen::Vector3f::Zero();
  Eigen::Vector3f bbox_max = Eigen::Vector3f::Zero();
  float completeness = -1.f;  // 0..1, < 0 unknown
};

// The floor raster with clearance. Cell (ix, iy) covers world xy [origin_m + (ix, iy) *
// cell_size_m, + cell_size_m); arrays are row-major, iy then ix.
struct PlannerFloor {
  Eigen::Vector2f origin_m = Eigen::Vector2f::Zero();
  float cell_size_m = 0.f;
  int width = 0, height = 0;
  uint64_t revision = 0;
  std::vector<FloorCell> cells;
  std::vector<float> clearance_m;  // cell centre to the nearest obstacle

  bool Contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
  size_t Linear(int ix, int iy) const { return size_t(iy) * size_t(width) + size_t(ix); }
  Eigen::Vector2i CellOf(const Eigen::Vector2f& p_W) const;  // may lie outside
  Eigen::Vector2f CellCenter(int ix, int iy) const {
    return origin_m + cell_size_m * Eigen::Vector2f(float(ix) + 0.5f, float(iy) + 0.5f);
  }
  // Free (or frontier) with at least min_clearance_m; false outside.
  bool Traversable(int ix, int iy, float min_clearance_m) const;
};

enum class TaskPolicy : int32_t { kAppend = 0, kReplace = 1 };
enum class PlanEvent : int32_t {
  kStart = 0,
  kInterval = 1,
  kRobotIdle = 2,
  kTaskFailed = 3,
  kWakeup = 4
};

// Where the camera is at a task (vp_task_ext, extension vp.task); the defaults leave it where
// the mount puts it.
struct TaskCamera {
  float height_m = std::numeric_limits<float>::quiet_NaN();  // arm: above the floor; NaN rest
  Eigen::Vector2f offset_m = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  bool look_at = false;
  Eigen::Vector3f look_at_W = Eigen::Vector3f::Zero();
  float sweep_pitch_min_rad = 0.f, sweep_pitch_max_rad = 0.f, sweep_pitch_step_rad = 0.f;
  int32_t object_id = -1;

  // Anything but NaN counts as given (and infinities are then refused).
  bool HeightSet() const { return !std::isnan(height_m); }
  bool OffsetSet() const { return !std::isnan(offset_m.x()) || !std::isnan(offset_m.y()); }
  bool ArmSet() const { return HeightSet() || OffsetSet(); }
  bool Sweeps() const { return sweep_pitch_step_rad > 0.f; }
};

// A view to drive to and scan from (mode and dwell as in sim/robot.h).
struct PlannerTask {
  Eigen::Vector2f position_m = Eigen::Vector2f::Zero();
  float theta_rad = 0.f;
  float camera_yaw_rad = 0.f;  // relative to the base
  float camera_pitch_rad = 0.f;
  float dwell_s = 0.f;
  int32_t mode = 0;
  uint32_t tag = 0;  // the plugin's own id
  TaskCamera camera;
};

// Where a mode's camera sits (VP_MOUNT_*): the base centre, a head at a fixed height with a tilt,
// or an arm that sets the camera's height and offset.
enum class CameraMount : int32_t { kBase = 0, kHead = 1, kArm = 2 };

// One scanning mode (Guo 2022): speed and the camera's view.
struct ScanMode {
  float max_speed_mps = 0.5f;
  float max_turn_rate_radps = 1.f;
  float horizontal_fov_rad = 1.57f, vertical_fov_rad = 1.2f;
  float min_range_m = 0.1f, max_range_m = 5.f;
  int image_width = 640, image_height = 480;
  float fx = 320.f, fy = 320.f, cx = 320.f, cy = 240.f;
  // The camera's mount and timing (vp_mode_params' 1.1 fields).
  CameraMount mount = CameraMount::kHead;
  float camera_height_min_m = 1.2f, camera_height_max_m = 1.2f;
  float reach_min_m = 0.f, reach_max_m = 0.f, reach_half_angle_rad = 0.f;
  float min_pitch_rad = -1.f, max_pitch_rad = 1.f;
  float camera_speed_mps = 0.f, camera_turn_rate_radps = 1.5f;
  float capture_hz = 0.f;  // 0: captured by displacement
  float switch_s = 0.f;
};

struct PlannerRobot {
  uint32_t id = 0;
  Eigen::Vector2f position_m = Eigen::Vector2f::Zero();
  float theta_rad = 0.f;
  float camera_yaw_rad = 0.f, camera_pitch_rad = 0.f;
  int32_t mode = 0;
  bool executing = false;
  std::vector<PlannerTask> queue;  // unfinished tasks, current first
  float radius_m = 0.2f;
  float camera_height_m = 1.2f;
  float min_pitch_rad = -1.f, max_pitch_rad = 1.f;
  float camera_yaw_rate_radps = 1.5f, camera_pitch_rate_radps = 1.f;
  std::vector<ScanMode> modes;  // indexed by mode
  // This run so far.
  float distance_m = 0.f;
  float busy_s = 0.f, idle_s = 0.f;
};

class PlannerWorld {
 public:
  virtual ~PlannerWorld() = default;

  virtual PlannerMapInfo MapInfo() const = 0;
  // out.size() == points.size(); points outside the map are unobserved.
  virtual void VoxelStates(std::span<const Eigen::Vector3f> points,
                           std::span<VoxelState> out) const = 0;
  virtual void Raycast(std::span<const PlannerRay> rays, std::span<PlannerRayHit> out) const = 0;
  virtual std::vector<Eigen::Vector3f> FrontierVoxels() const = 0;
  virtual std::vector<SurfaceVoxel> SurfaceVoxels() const = 0;
  // Must stay valid and unchanged during one plan call.
  virtual const PlannerFloor& Floor() const = 0;
  virtual std::vector<ObjectInstance> Instances() const { return {}; }
  virtual std::vector<PlannerRobot> Robots() const = 0;

  // Geodesic distance from source to every floor cell over cells traversable with
  // min_clearance_m (the source cell is always entered); +inf where unreachable.
  virtual Result<std::vector<float>> GeodesicField(const Eigen::Vector2f& source_m,
                                                   float min_clearance_m) const = 0;
  // Row-major n x n geodesic distances between the points.
  virtual Result<std::vector<float>> DistanceMatrix(std::span<const Eigen::Vector2f> points_m,
                                                    float min_clearance_m) const = 0;
  // Polyline from -> to through cell centres; NotFound when unreachable.
  virtual Result<std::vector<Eigen::Vector2f>> ShortestPath(const Eigen::Vector2f& from_m,
                                                            const Eigen::Vector2f& to_m,
                                                            float min_clearance_m) const = 0;
};

}  // namespace voxplan
