// The tensorfield planner's logic for one robot over plain data (Xu et al. 2017, Alg. 1 mapped
// onto the exploration loop's calls; plugins/tensorfield/README.md): key frames over a window
// around the robot, the space-time frames between them stepped through one sub-step at a time,
// a pathline advected over them and sent as a continuous path, wedge and trisector stops with
// routing over the topological skeleton, the frontier fallback, the camera trajectory of X eq.
// 7-8 and termination. The plugin (plugin.cpp) only reads the host's world into these structs
// and writes the step back. Deterministic; prints nothing.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "plugins/tensorfield/algorithms/advection.h"
#include "plugins/tensorfield/algorithms/camera_path.h"
#include "plugins/tensorfield/algorithms/skeleton.h"
#include "plugins/tensorfield/algorithms/tensor_field.h"
#include "plugins/tensorfield/algorithms/topology_control.h"
#include "plugins/tensorfield/frames.h"

namespace voxplan::tensorfield {

class ViewGain;  // gain.h

// "tensor": the paper's planner; X T3's baselines, with the same camera, fallback and
// termination: "harmonic", Shade & Newman 2011's gradient of a harmonic function (harmonic.h);
// "potential", a potential information field with wall repulsion in Vallvé's style
// (potential_info.h).
enum class Method : std::uint8_t { kTensor = 0, kHarmonic = 1, kPotential = 2 };

// The camera views' pitch (PlannerOptions::pitch): level (X's figures show a level camera), or
// aimed at the middle of the floor band at the distance of what the view sees [ours; gain.h
// AimPitch].
enum class CameraPitch : std::uint8_t { kLevel = 0, kAim = 1 };

// How a new camera trajectory starts (PlannerOptions::connect).
enum class CameraConnect : std::uint8_t { kOff = 0, kSpline = 1, kInSelection = 2 };

struct PlannerOptions {
  Method method = Method::kTensor;
  // With kTensor: the paper's tensor field, or a vector-field baseline from the same constraints
  // (X Fig. 2), advected with its sign and without degenerate points, skeleton or routing.
  FieldKind field = FieldKind::kTensor;
  double substep_s = 0.4;         // X§6: 0.4 s sub-steps
  int substeps_per_keyframe = 5;  // Alg. 1 drives sub-steps K/2 .. K-1 of each key frame
  int frames_k = 10;              // K (X§6, Fig. 15)
  double speed_mps = 0.3;         // X L304
  double window_m = 6.0;          // half-width of the key frame's window
  double interp_window_m = 3.0;   // the space-time solve's disc around the robot
  InterpolationMode interp = InterpolationMode::kSpaceTime;
  bool topology_routing = true;
  // X8 in every key frame before interpolation: (d) cancel wedge-trisector pairs meeting eq. 6,
  // then (a) move corner wedges into their corners, (b) retract exhausted end wedges, (c) move
  // trisectors off obstacles (topology_control.h).
  bool topology_control = false;
  CameraMode camera = CameraMode::kOptimized;
  // X12 (X L310): where the path ahead runs into unknown space (the robot's body, radius +
  // clearance_margin_m around it, meets unknown cells), a look-at view towards it at the camera
  // samples within lookat_m of it, and eq. 8's look-at term with weight lookat_weight (ω_U).
  bool lookat = true;
  double lookat_m = 2.0;
  double lookat_weight = 1.0;
  // X5 (X L194): kSpline, every camera trajectory starts where the camera is and is joined to the
  // optimised one by a connecting stretch under the camera's speed limits
  // (ConnectCameraTrajectory); kInSelection [ours], eq. 8 itself starts from the camera's pose
  // (CameraPathParams::start_from_camera), then the same connection; kOff, it starts at the
  // optimised trajectory's first view and the host turns the camera there at its joints' rate.
  CameraConnect connect = CameraConnect::kSpline;
  CameraPitch pitch = CameraPitch::kLevel;
  double gain_threshold = 0.01;  // X L229
  // The camera views' surface term (gain.h GainParams::surface_depth_m; 0 off) over the host's
  // surface voxels from the floor up to band_m. The routing and termination gains leave
  // it out: a surface the sensor cannot resolve from the floor would hold the run open.
  double surface_depth_m = 0.0;
  // The floor band (planning/floor_map.h's: the robot's height): the surface term's voxels, the
  // aimed pitch's middle.
  double band_m = 1.8;
  double clearance_margin_m = 0.05;  // beyond the robot radius, as the host's own routes keep
  double lookahead_m = 2.0;          // the pathline the camera is planned along
  double camera_sample_m = 0.3;      // its samples
  int sent_substeps = 3;             // X4: a pathline of three sub-steps is sent
  FillParams fill;
  // Stuck: less progress than stuck_m over the last stuck_calls calls.
  double stuck_m = 0.05;
  int stuck_calls = 6;
  // No gain: the best view along the lookahead below gain_threshold this many calls in a row.
  int no_gain_calls = 4;
};

// The robot and its camera as the plugin read them.
struct RobotInput {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  double radius_m = 0.2;
  double camera_height_m = 1.2;
  double fov_rad = 1.5707963;
  double min_range_m = 0.3;
  double max_range_m = 5.0;
  double max_speed_mps = 0.5;
  double floor_z_m = 0.0;
  bool arm = false;  // camera on an arm (its workspace below), else a head over the base
  CameraWorkspace workspace;
  double min_pitch_rad = -0.5, max_pitch_rad = 0.5;
  // Where the camera looks now (world yaw: the base's heading plus the camera joint's yaw).
  double camera_yaw_rad = 0.0, camera_pitch_rad = 0.0;
  // The camera's speed limits on its mount (v_m, a_m: the arm's speed, the slower camera joint)
  // and the base's turn rate in place.
  CameraSpeedLimits camera_limits;
  double turn_rate_radps = 1.0;
};

// The host's geodesic queries (empty functions in unit tests: every frontier counts as
// reachable and no fallback route is found).
struct RouteServices {
  // Geodesic distance from `from` to every floor cell over cells with that clearance (+inf:
  // unreachable), row-major over FloorInput's geometry.
  std::function<std::vector<float>(const Eigen::Vector2d& from, double clearance_m)> geodesic;
  std::function<std::optional<std::vector<Eigen::Vector2d>>(
      const Eigen::Vector2d& from, const Eigen::Vector2d& to, double clearance_m)>
      shortest_path;
};

struct CameraOut {
  float t_s = 0.f;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  float yaw_rad = 0.f, pitch_rad = 0.f;
};

// What drove the path sent (diagnostic "mode").
enum class StepMode : std::uint8_t {
  kAdvect = 0,
  kSeparatrix = 1,
  kFrontier = 2,
  kNone = 3,
  kSkeleton = 4  // global routing to the skeleton edge with the most gain (X L136)
};

struct StepDiagnostics {
  double field_ms = -1.0, interp_ms = -1.0;  // only on a key-frame call; -1 otherwise
  double topology_ms = 0.0, advect_ms = 0.0, traj_ms = 0.0;
  int degenerate_points = 0, wedges = 0, trisectors = 0, skeleton_edges = 0;
  double max_edge_gain = 0.0;
  double lookahead_gain = 0.0;
  int fallback_routes = 0;  // cumulative
  int blocked = 0;          // cumulative blocked pathlines
  int pathlines = 0;        // cumulative
  int branch_choices = 0;   // cumulative
  int skeleton_routes = 0;  // cumulative: global routes over the skeleton
  int cancelled_pairs = 0;  // cumulative: wedge-trisector pairs cancelled (topology_control)
  int corner_wedges = 0;    // cumulative, topology_control: X8 (a), (b) and (c) moves
  int retracted_wedges = 0;
  int moved_trisectors = 0;
  int substep = 0;
  bool keyframe = false;
  StepMode mode = StepMode::kNone;
  int stop = -1;  // AdvectionStop of this call's pathline, -1 when none was advected
  int settled_goals = 0;
  // Key-frame calls only (-1 otherwise): CountFieldCensus of the key frame's constraints; with
  // topology_control, the key frame's degenerate points before and after it.
  int census_degenerate = -1, census_vector = -1;
  int control_points_before = -1, control_points_after = -1;
  double census_ms = -1.0;
  double control_ms = -1.0;  // key-frame calls: topology control (0 when off)
  // X12 (this call): camera samples with a look-at target, those whose selected view sees it,
  // those whose view the look-at changed; the robot's distance to the nearest target (-1: none).
  int lookat_samples = 0, lookat_seen = 0, lookat_changed = 0;
  double lookat_m = -1.0;
  // X5: this call is a stop (a new kind of path, a re-advection at a wedge, trisector or
  // obstacle, a route started, a first piece the base turns in place for, or a path after none);
  // the stops so far; the camera's jump to the optimised trajectory's start (degrees); the
  // camera's largest angular speed over the connecting stretch without and with the connection
  // (rad/s; without: the jump taken in the first step); the stretch (s, 0 when not connected).
  bool camera_stop = false;
  int camera_stops = 0;
  double camera_jump_deg = 0.0, camera_radps_before = 0.0, camera_radps_after = 0.0;
  double camera_connect_s = 0.0;
};

struct StepOutput {
  std::vector<Eigen::Vector2d> path;  // starts at the robot; empty: nothing sent
  std::vector<double> headings_rad;
  std::vector<float> speeds_mps;
  std::vector<CameraOut> camera;
  double wakeup_t_s = 0.0;
  bool done = false;  // X7 and no reachable frontier
  StepDiagnostics diag;
  // Debug drawings, world xy.
  std::vector<Eigen::Vector2d> lookahead;
  std::vector<Eigen::Vector2d> degenerate_xy;
  std::vector<std::vector<Eigen::Vector2d>> skeleton_edges;
  // At a key frame: the field as glyphs, a short segment along the major eigenvector every
  // 0.4 m of the window where the field is not flat (for the run's picture).
  std::vector<std::array<Eigen::Vector2d, 2>> field_glyphs;
};

// One robot's planner state across calls.
class RobotPlanner {
 public:
  explicit RobotPlanner(const PlannerOptions& options) : options_(options) {}
  StepOutput Step(const FloorInput& floor, const RobotInput& robot, double sim_time_s,
                  const RouteServices& services);

 private:
  struct Route {
    StepMode kind = StepMode::kNone;
    std::vector<Eigen::Vector2d> polyline;
    Eigen::Vector2d goal = Eigen::Vector2d::Zero();
    double deadline_s = 0.0;
  };
  using Key = std::pair<long, long>;

  void BuildKeyFrame(const FloorInput& floor, const RobotInput& robot, double t_s, StepOutput* out);
  void BuildTopology(const RobotInput& robot, const ViewGain& gain, StepOutput* out);
  void AddGlyphs(const TensorRaster& frame, StepOutput* out) const;
  SkeletonParams SkeletonFor(const RobotInput& robot) const;
  // with_surface: the surface term too (when the options ask for it).
  ViewGain GainModel(const RobotInput& robot, bool with_surface = false) const;
  Pathline Advect(const RobotInput& robot, double heading_rad, double length_m,
                  const std::vector<DegeneratePoint>& points) const;
  bool Traversable(const Eigen::Vector2d& p, double radius_m) const;
  std::vector<Eigen::Vector2d> TraversablePrefix(const std::vector<Eigen::Vector2d>& line,
                                                 double radius_m) const;
  std::optional<Route> SeparatrixRoute(const RobotInput& robot, double t_s);
  // The host's shortest path from `from` to `goal` as a route of that kind; none without one.
  std::optional<Route> RouteOverMap(StepMode kind, const Eigen::Vector2d& from,
                                    const Eigen::Vector2d& goal, double clearance_m, double t_s,
                                    const RouteServices& services) const;
  std::optional<Route> SkeletonRoute(const FloorInput& floor, const RobotInput& robot, double t_s,
                                     const RouteServices& services);
  void SettleAround(const FloorInput& floor, const Eigen::Vector2d& goal);
  std::optional<Route> FrontierRoute(const FloorInput& floor, const RobotInput& robot, double t_s,
                                     const RouteServices& services);
  bool FrontierReachable(const FloorInput& floor, const RobotInput& robot,
                         const RouteServices& services) const;
  bool Settled(const FloorInput& floor, int cell) const;
  Key KeyOf(const omt::RasterGeometry& g, int cell) const;
  bool Stuck() const;
  // stop: the caller knows this call is a stop (a route or a re-advection starts); EmitLine adds
  // the other kinds (StepDiagnostics::camera_stop).
  void EmitLine(const std::vector<Eigen::Vector2d>& line, const std::vector<float>& speeds,
                const RobotInput& robot, const ViewGain& route_gain, bool stop, StepOutput* out);
  std::vector<CameraLookAtTarget> LookAtTargets(const std::vector<Eigen::Vector2d>& line,
                                                const RobotInput& robot) const;
  // Where the arm camera is now by the last trajectory sent (NaN: not known).
  Eigen::Vector3f ArmCameraNow(const RobotInput& robot) const;

  PlannerOptions options_;
  // Key frames and the frames between them.
  bool have_key_ = false;
  TensorRaster key_;
  double key_t_s_ = 0.0;
  Eigen::Vector2d key_centre_ = Eigen::Vector2d::Zero();
  FloorWindow window_;
  std::vector<TensorRaster> frames_;
  int sub_ = 0;  // the current sub-step's frame
  double min_magnitude_ = 0.0;
  // The skeleton of the key frame's first driven frame, its edges' gains and accessibility.
  std::vector<DegeneratePoint> key_points_;
  Skeleton skeleton_;
  std::vector<double> edge_gain_;
  std::vector<std::uint8_t> edge_access_;
  // Motion.
  std::optional<Route> route_;
  std::vector<Eigen::Vector2d> history_;  // robot positions at the last calls
  int no_gain_streak_ = 0;
  Eigen::Vector2d last_branch_root_ = Eigen::Vector2d::Constant(1e9);
  double last_branch_t_s_ = -1e9;
  std::set<Key> settled_;  // frontier cells near goals the robot reached and did not resolve
  std::vector<Eigen::Vector2d> visited_goals_;
  BlockedPathCounter blocked_;
  int fallback_routes_ = 0;
  int branch_choices_ = 0;
  int skeleton_routes_ = 0;
  int cancelled_pairs_ = 0;
  int corner_wedges_ = 0, retracted_wedges_ = 0, moved_trisectors_ = 0;
  // topology_control: the robot's positions at least kTrailSpacingM apart, for (b)'s visits.
  static constexpr double kTrailSpacingM = 0.25, kVisitRadiusM = 1.0;
  std::vector<Eigen::Vector2d> trail_;
  std::vector<Eigen::Vector2d> skeleton_goals_;  // edge points routed to: not targets again
  // X5: what the last call emitted (kNone: nothing) and this call's; the stops so far; the path
  // and camera trajectory last sent (the path's arc length and time at each point), for where
  // the arm camera is now.
  StepMode prev_mode_ = StepMode::kNone, emitted_mode_ = StepMode::kNone;
  int camera_stops_ = 0;
  std::vector<Eigen::Vector2d> sent_path_;
  std::vector<double> sent_arc_, sent_time_;
  std::vector<CameraOut> sent_camera_;
};

}  // namespace voxplan::tensorfield
