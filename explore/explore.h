#pragma once
// The closed exploration loop of `voxplan explore`: simulated robots drive the tasks a planner
// plugin gives them, the simulator renders each robot's frames, the engine fuses them at the
// true poses into one planning map, the floor map follows, and the planner is called on its
// events. One simulation clock advanced in fixed steps; within a step the robots act, render
// and fuse in robot-index order, so a run is deterministic for its seed.
//
// A robot's queue, per task: route over the *known* floor map (the plugin's dense path when it
// gave one, else GeodesicCache's shortest path, shortcut where the known raster allows), drive
// it in short segments at the mode's speed with Robot::DriveTo, which refuses segments that hit
// the *true* floor plan (a plugin path that does is replaced once by the host's route; then
// the task fails: kTaskFailed). A refused segment of the host's route is a bumper's contact:
// the plan cells it ran into become obstacles of the floor map (FloorMap::MarkContacts: beside
// a wall the map shows, at the second report), for the host's routes and the planner's raster
// alike. The camera looks along the motion unless the plugin gave a camera trajectory; at the
// view it turns base and camera to the task's angles, dwells and captures. Base turns, camera
// joints and driving take their time one after the other. A frame is fused whenever the
// FusionTrigger fires, and at every view. A continuous path (vp.motion) turns, aims and, on an
// arm mount, moves the camera to the trajectory's positions while it drives (Robot::DriveAlong).
// Events: kStart after an initial camera sweep, kInterval every planning interval without a
// call, kRobotIdle when a robot's queue empties, kTaskFailed. Robot collisions with each other
// are not simulated (as in Dong 2019).
//
// Termination: "done" when the planner says so, or when a call leaves every robot idle with no
// task twice in a row ("no_tasks"); "time_limit" at max_time_s of simulated time;
// "planner_crashed" / "planner_hung" when a plan call crashed or overran its hard limit
// (LoadedPlanner::fault()): the loop stops there and the result holds what it recorded so far.
#include <Eigen/Core>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.h"
#include "core/pose.h"
#include "core/status.h"
#include "core/volume.h"
#include "eval/eval_run.h"
#include "fusion/integrate.h"
#include "fusion/tracking.h"
#include "planning/floor_map.h"
#include "planning/planning_map.h"
#include "plugins/host/plugin_host.h"
#include "sim/detector.h"
#include "sim/floor_plan.h"
#include "sim/odometry.h"
#include "sim/robot.h"
#include "sim/world.h"

namespace voxplan {

struct ExploreParams {
  // Fusion into the planning map.
  float voxel_size_m = 0.05f;
  float trunc_vox = 3.0f;
  int image_width = 320, image_height = 240;  // 5 cm voxels need no more
  uint64_t max_memory_bytes = 0;              // the fused map's budget (VolumeParams); 0: none
  // > 0: a second, finer TSDF (e.g. 0.02 m, trunc_vox voxels) fused with the same frames, for
  // the final mesh and its metrics; the planners keep voxel_size_m. Its own max_memory_bytes.
  float recon_voxel_size_m = 0.f;
  // How the reconstruction volume weighs a frame's depth: 1/z² (Voxblox's default, which Guo 2022
  // fused with) lets a close scan outweigh far, noisier ones; the planning map stays constant.
  Weighting recon_weighting = Weighting::kConstant;
  bool noise = true;                   // Kinect noise on the rendered depth
  bool keep_planner_drawings = false;  // ExploreResult::planner_drawings (a picture of them)
  // Where frames are fused: at the true camera pose, or (kTracked, Xu 2017's registration) at
  // the pose FrameTracker estimates against the map from a noisy odometry prior, frames it loses
  // skipped. Each robot's start sweep anchors its map at the truth (a frame must overlap the map
  // to be tracked, and the sweep's pitch rows barely overlap); robots and planners still know
  // their true poses (only the maps see the estimates).
  enum class Poses { kTruth, kTracked };
  Poses poses = Poses::kTruth;
  OdometryNoiseParams odometry;
  // An exploring camera sees new space in most frames: a tenth of its pixels on the model is
  // enough to register it (the handheld default, a quarter, lost most frames past a doorway).
  TrackingParams tracking = [] {
    TrackingParams t;
    t.min_inlier_ratio = 0.1f;
    return t;
  }();
  // A frame in which the map shows no surface to register against (TrackingResult::no_model) is
  // fused at the odometry prior instead of skipped: skipped, the map would never grow where the
  // camera looks, and every later frame there would see no model either (a room beyond the start
  // sweep's range stayed unmapped for the rest of the run). Frames whose registration failed on
  // a surface the map does hold are still skipped.
  bool odometry_without_model = true;
  bool fuse_labels = true;  // instance labels into the object map
  // How the labels are detected before they are fused (sim/detector.h): noisy by default.
  DetectorParams detector;
  // Vertex colours of the final mesh only (no metric reads them): off saves rendering and
  // fusing colour, about a tenth of a frame's cost.
  bool fuse_color = true;
  // Depth beyond the camera's range is too noisy to fuse as surface but still shows the free
  // space in front of the range: cleared there. Without it, a short-range camera leaves open
  // floor unknown wherever the walls lie beyond its range.
  bool clear_beyond_range = true;
  FusionTriggerParams trigger = {0.25f, 15.0f};
  RobotParams robot;  // image size above overrides robot.image_*
  // The floor map's band reaches 0.6 m above the camera; beyond ~2.5 m the rays through its top
  // meet the ceiling past the sensor's range and carve only by clearing (clear_beyond_range), so
  // a column there is rarely 90 % observed. Free from 60 % on: the lower band, where furniture
  // stands, must be seen.
  FloorMapParams floor = {.min_free_fraction = 0.6f, .voxel_state = {}};

  // The loop.
  double step_s = 0.25;
  double planning_interval_s = 15.0;
  double plan_time_budget_s = 1.0;  // reported when exceeded, never enforced
  double max_time_s = 1800.0;
  uint64_t seed = 1;
  // Routing on the known map keeps this much clearance beyond the robot's radius, so grid
  // misalignment between the known and the true floor does not make segments collide.
  float route_margin_m = 0.05f;
  float drive_step_m = 0.2f;   // longest straight piece between two fusion checks
  float turn_step_deg = 20.f;  // largest base or camera turn between two fusion checks
  // The sweep every robot does at the start, before the first plan call: a full camera turn
  // at each of these pitches (degrees), in steps of sweep_step_deg. Looking down and up makes
  // the floor map free around the robots (its band reaches from the floor to above the camera).
  // -55 and +55 with the default camera's ~74° vertical field of view reach past straight down
  // and up, so only the cells under the robot stay unseen (ExploreWorld::MarkFootprint).
  std::vector<float> sweep_pitches_deg = {-55.f, 0.f, 55.f};
  float sweep_step_deg = 30.f;

  // Outputs over time.
  double series_interval_s = 5.0;         // time-series rows (coverage, distance)
  double completeness_interval_s = 30.0;  // completeness column (every k-th row)
  double progress_interval_s = 30.0;

  Status Validate() const;
};

// Where the robots start: without explicit positions, side by side `spacing_m` apart along x
// (or y) at the free spot nearest the centre of the largest room (of the free floor when the
// world has no rooms), every footprint free with `margin_m` to spare. Refuses explicit starts
// whose footprint is not free on the true plan.
Result<std::vector<Eigen::Vector2f>> ChooseStarts(const FloorPlan& plan,
                                                  const std::vector<Room>& rooms, int robots,
                                                  float radius_m, float spacing_m = 0.6f,
                                                  float margin_m = 0.05f);
Status CheckStarts(const FloorPlan& plan, const std::vector<Eigen::Vector2f>& starts,
                   float radius_m);

struct ExploreProgress {
  double t_s = 0.0;
  size_t frames_fused = 0;
  double coverage = 0.0;
  double distance_total_m = 0.0;
  size_t plan_calls = 0;
};

struct PlanCallRecord {
  uint32_t call_index = 0;
  double t_s = 0.0;
  PlanEvent event = PlanEvent::kStart;
  int32_t event_robot = -1;
  std::vector<size_t> tasks_per_robot;
  size_t rejections = 0;
  bool done = false;
  double elapsed_ms = 0.0;  // wall time: not deterministic
  bool over_budget = false;
  std::vector<std::pair<std::string, double>> diagnostics;  // the plugin's, in its order
};

struct ExploreTimings {  // wall milliseconds, summed over the run
  double render_ms = 0.0, detect_ms = 0.0, noise_ms = 0.0, fuse_ms = 0.0, floor_ms = 0.0,
         plan_ms = 0.0, series_ms = 0.0, total_ms = 0.0, track_ms = 0.0;
};

// A frame the loop fused: when and from where.
struct ExploreFrame {
  double t_s = 0.0;
  Pose3f T_W_C = Pose3f::Identity();
  Pose3f T_W_C_fused = Pose3f::Identity();  // where it was fused (the estimate when tracked)
  float residual_rms_m = 0.f;               // the tracker's, when tracked
  bool odometry = false;  // tracked poses: fused at the odometry prior (no model in view)
};

struct ExploreResult {
  std::string terminated;   // "done", "time_limit", "planner_crashed" or "planner_hung"
  std::string done_reason;  // "planner", "no_tasks" or "" (time limit)
  double time_s = 0.0;
  size_t frames_fused = 0;
  size_t frames_lost = 0;       // with tracked poses: frames the tracker lost, not fused
  size_t frames_odometry = 0;   // with tracked poses: fused at the odometry prior (no model)
  size_t objects_detected = 0;  // summed over frames, after the detector's noise
  size_t failed_tasks = 0;
  size_t rejected_tasks = 0;
  size_t over_budget_calls = 0;
  size_t blocks_dropped = 0;  // map blocks not allocated: the map was at max_memory_bytes
  size_t failed_plans = 0;    // plan calls the plugin failed (messages in plan_log)
  // Drives the true floor refused (a planner's path or the host's route ran into an obstacle;
  // Xu 2017's blocked paths): each leaves the path, re-routes or fails its task.
  size_t blocked_paths = 0;
  // Arm camera positions from a camera trajectory along a continuous path, moved into the arm's
  // workspace, and steps of the camera shortened by the arm's speed (pieces of motion; the first
  // of each in plan_log).
  size_t camera_position_clamped_workspace = 0, camera_position_clamped_speed = 0;
  std::vector<RobotTrack> tracks;                    // one per robot: r0, r1, ...
  std::vector<std::vector<ExploreFrame>> frames;     // per robot, every frame it fused
  std::vector<std::vector<PlannerTask>> task_views;  // per robot, views it reached, in order
  std::vector<PlanCallRecord> plan_calls;
  std::vector<std::string> plan_log;          // rejections, failures and the plugin's messages
  std::optional<PlannerFault> planner_fault;  // the call that ended the run, for planner_*
  std::vector<RunTimePoint> series;
  // With ExploreParams::keep_planner_drawings: per debug layer, the drawings of the last plan
  // call that sent that layer (the planner's field, skeleton, paths at the end of the run).
  std::map<std::string, std::vector<DebugDrawing>> planner_drawings;
  ExploreTimings timings;
  // The maps at the end.
  std::unique_ptr<TsdfVolume> volume;
  std::unique_ptr<TsdfVolume> recon_volume;  // with recon_voxel_size_m > 0, else null
  std::unique_ptr<FloorMap> floor;
};

using ExploreProgressFn = std::function<void(const ExploreProgress&)>;

// Runs the loop on `world` with the loaded planner. `starts` gives one position per robot.
// `completeness_probe` (may be empty) maps the volume to a completeness for the time series.
Result<ExploreResult> RunExplore(const World& world, const FloorPlan& plan,
                                 const std::vector<Eigen::Vector2f>& starts, LoadedPlanner& planner,
                                 const ExploreParams& params,
                                 const std::function<double(const TsdfVolume&)>& completeness_probe,
                                 const ExploreProgressFn& progress = {});

// Tracking quality over the frames of a run fused at tracked poses (the start sweeps' frames,
// anchored at the truth, have no residual and no error): the tracker's point-to-plane residual
// (mean and p90) and the absolute trajectory error, the RMS of |fused − true| camera positions.
struct TrackedPoseSummary {
  double residual_mean_m = 0.0, residual_p90_m = 0.0, ate_rms_m = 0.0;
  size_t frames = 0;
};
TrackedPoseSummary SummarizeTrackedPoses(const std::vector<std::vector<ExploreFrame>>& frames);

// A cheap completeness for the time series: the share of `samples_W` (ground-truth surface
// points) where the interpolated TSDF (all 8 voxels observed) is within threshold_m of zero.
// The final mesh's EvaluateMesh is the reference; this tracks it without meshing.
double VolumeCompleteness(const TsdfVolume& volume, const std::vector<Eigen::Vector3f>& samples_W,
                          float threshold_m = 0.05f);

// The floor map as the 2-D raster eval_run's FloorCoverage reads (any known cell counts).
ObservedRaster ObservedFromFloor(const FloorMap& floor);

const char* PlanEventName(PlanEvent event);

}  // namespace voxplan
