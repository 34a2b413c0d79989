// The arm camera trajectory along a base path, Xu et al. 2017 §5 (X eq. 7-8, X L286-294;
// planner-wave.md X9-X11, §2.4, G.2.6): C candidate camera positions in the arm workspace Ψ at
// every base path sample, each with its best viewing direction and gain from the planner; one
// candidate per sample chosen by minimising eq. 8 (gain against second-difference smoothness of
// position and viewing angles, under linear and angular speed limits); and a dense trajectory
// through the chosen views (cubic Hermite positions, minimal-rotation viewing angles) clamped to Ψ
// and the speed limits. The paper solves eq. 8 as a 0-1 ILP with Gurobi; its couplings form a
// chain over (s-1, s, s+1), so a dynamic programme over candidate pairs (x_{s-1}, x_s) solves it
// exactly in O(S·C³). Plain data and callbacks (free space, view scoring): the map is the
// planner's. Deterministic; nothing is printed.
//
// Two parts of the paper outside eq. 8 are here too. X12 (X L310): where the path runs into
// unknown space, a look-at view towards it is added to the path samples within 2 m of it, and a
// view that sees it earns eq. 8 a unary term (FindLookAtTargets, PlanCameraPath's CameraLookAt).
// X5 (X L194): a new trajectory starts from where the camera is, joined to the optimised one by
// a connecting stretch under the speed limits (ConnectCameraTrajectory).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <vector>

namespace voxplan::tensorfield {

// One sample of the base path (the advected pathline, every ~0.3 m), world frame.
struct CameraBaseSample {
  Eigen::Vector2f xy_m = Eigen::Vector2f::Zero();
  float heading_rad = 0.0f;   // the base's forward direction
  float arc_length_m = 0.0f;  // along the path from its start; non-decreasing
};

// Ψ(p): where the arm can put the camera relative to the base pose p (planner-wave.md §2.4
// defaults [ours]; the paper only cites the Fetch arm spec, X L270).
struct CameraWorkspace {
  float height_min_m = 0.4f;  // optical centre above the floor
  float height_max_m = 1.4f;
  float reach_min_m = 0.4f;  // horizontal distance of the camera from the base centre
  float reach_max_m = 0.9f;
  float bearing_half_angle_rad = 1.5707963f;  // camera bearing within ± this of the heading
};

// X L306: v_m = 0.5 m/s and a_m = 40°/s (the text's second "v_m" is a typo for a_m).
struct CameraSpeedLimits {
  float linear_mps = 0.5f;           // camera position, world frame
  float angular_radps = 0.6981317f;  // ‖(Δyaw, Δpitch)‖ per second
};

// The planner's view model at one camera position: its best viewing direction and the gain V of
// that view (X eq. 7's V(q, α); the gain model is the planner's, planner-wave.md §2.4).
struct CameraViewScore {
  float yaw_rad = 0.0f;    // world yaw of the viewing direction
  float pitch_rad = 0.0f;  // positive looks up
  float gain = 0.0f;       // non-negative
};

// True when the camera may be at camera_W (the planner: a free voxel of the map, X L310).
// An empty function accepts every position.
using CameraFreeFn = std::function<bool(const Eigen::Vector3f& camera_W)>;
// Best view and gain at camera_W, with the base sample it belongs to. An empty function looks
// along the heading with gain 0.
using CameraScoreFn =
    std::function<CameraViewScore(const Eigen::Vector3f& camera_W, const CameraBaseSample& base)>;
// The gain V of the view from camera_W along a given direction (X12's added look-at view, whose
// direction is set by its target rather than by the gain). An empty function gives 0.
using CameraDirectionGainFn = std::function<float(const Eigen::Vector3f& camera_W, float yaw_rad,
                                                  float pitch_rad, const CameraBaseSample& base)>;

// "fixed": camera rigidly forward at a set height, nothing optimised (the baselines' setting,
// X L429); "no_linear" / "no_angular": ω_L = 0 / ω_A = 0 (the camera ablations, Fig. 12, 18).
enum class CameraMode { kOptimized, kFixed, kNoLinear, kNoAngular };

struct CameraCandidateParams {
  CameraWorkspace workspace;
  float floor_z_m = 0.0f;
  // X L306: 10 candidates per path sample. Candidate i sits at point i of a Halton sequence
  // (bases 2, 3, 5 for bearing, height, reach) over Ψ(p_s), the same pattern at every sample;
  // points the free-space callback rejects are replaced by the next points of the sequence, at
  // most max_tries points in all per sample.
  int candidates_per_sample = 10;
  int max_tries = 40;
};

struct CameraSelectionParams {
  CameraSpeedLimits limits;
  float base_speed_mps = 0.3f;  // X L304: 0.3 m/s; the time between samples is Δs / base speed
  // X12's look-at term [ours: the paper adds the view and says it "ensures that the robot looks
  // into that region", X L310, without a weight]: −ω_U Σ U, U the candidate's lookat (1 when its
  // view sees the sample's look-at target). With ω_U = ω_V a view that sees the target never
  // scores below one that does not on the unary terms alone; smoothness and the speed limits can
  // still keep the camera away. No effect where no candidate has U > 0.
  double weight_lookat = 1.0;
  // Eq. 8's weights (silent in the paper; planner-wave.md §2.4 [ours]). Each term is normalised
  // per sample so the weights compare O(1) quantities: a gain is divided by the largest candidate
  // gain on the path (V̂ in [0, 1]); a position second difference ‖q_{s-1} − 2q_s + q_{s+1}‖ by
  // v_m·Δt̄ and an angle one by a_m·Δt̄ (Δt̄ the mean time between samples), so a second
  // difference as large as one full-speed step costs ω_L (resp. ω_A), and a view of the path's
  // best gain earns ω_V.
  double weight_gain = 1.0;
  double weight_linear = 0.5;
  double weight_angular = 0.5;
  // Eq. 8 bounds the central differences ‖q_{s+1} − q_{s−1}‖ ≤ 2·v_m·Δt (and likewise the angles).
  // Also bounding each adjacent step (s, s+1), the discretisation of q' < v_m between samples,
  // keeps the interpolated path near the limits [ours].
  bool limit_adjacent_steps = true;
  // The speed limits are hard constraints. When no selection satisfies them all the programme is
  // solved again with each violation costing violation_penalty × (speed / limit − 1) and the
  // violations are counted.
  double violation_penalty = 1.0e3;
};

struct CameraInterpolationParams {
  CameraWorkspace workspace;
  CameraSpeedLimits limits;
  float floor_z_m = 0.0f;
  float base_speed_mps = 0.3f;
  // Dense samples: every base path sample plus equal subdivisions of each interval no longer than
  // this (base arc length).
  float output_step_m = 0.05f;
};

struct CameraPathParams {
  CameraMode mode = CameraMode::kOptimized;
  CameraCandidateParams candidates;
  CameraSelectionParams selection;
  float output_step_m = 0.05f;
  // Mode "fixed": the camera this far ahead of the base centre, at this height, looking along the
  // heading with this pitch. A rigid mount: neither clamped (keep it inside Ψ) nor speed-limited;
  // the trajectory's speed_violations count where the base's own motion breaks the limits.
  float fixed_forward_m = 0.5f;
  float fixed_height_m = 0.9f;
  float fixed_pitch_rad = 0.0f;
  // X5 inside eq. 8 [ours]: the first path sample's only candidate is the camera's pose now (its
  // position where known, else that of the sample's first candidate), so the selection's speed
  // limits and smoothness run on from where the camera is. Not in "fixed".
  bool start_from_camera = false;
  Eigen::Vector3f start_position_W =
      Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  float start_yaw_rad = 0.0f;
  float start_pitch_rad = 0.0f;
};

struct CameraCandidate {
  Eigen::Vector3f position_W = Eigen::Vector3f::Zero();
  float yaw_rad = 0.0f;  // best viewing direction at position_W (the score callback)
  float pitch_rad = 0.0f;
  float gain = 0.0f;
  // Where in Ψ(p_s): base-frame polar offset and height above the floor.
  float reach_m = 0.0f;
  float bearing_rad = 0.0f;  // relative to the heading, positive to the left
  float height_m = 0.0f;
  // X12: U in [0, 1], 1 when the view sees its sample's look-at target (LookAtScore); 0 where
  // the sample has none. lookat_view: the view X12 added, aimed at the target.
  float lookat = 0.0f;
  bool lookat_view = false;
};

// Eq. 8's terms for a selection, as weighted and normalised (CameraSelectionParams).
struct CameraSelectionEnergy {
  double gain = 0.0;     // −ω_V Σ V̂
  double linear = 0.0;   // ω_L Σ ‖Δ²q‖² / (v_m Δt̄)²
  double angular = 0.0;  // ω_A Σ ‖Δ²α‖² / (a_m Δt̄)², yaw differences wrapped
  double lookat = 0.0;   // −ω_U Σ U (X12)
  double total = 0.0;    // gain + linear + angular + lookat
  double penalty = 0.0;  // speed violations (0 when feasible)
};

struct CameraSelection {
  // Per path sample: index into its candidates, −1 for a sample without any (skipped: the chain
  // of eq. 8 runs over the samples that have candidates).
  std::vector<int> selected;
  CameraSelectionEnergy energy;
  bool feasible = true;       // every speed constraint holds
  int linear_violations = 0;  // speed constraints the selection breaks (after the penalty pass)
  int angular_violations = 0;
  int samples_without_candidates = 0;
};

// A dense camera pose keyed by base arc length.
struct CameraPathSample {
  float arc_length_m = 0.0f;
  float time_s = 0.0f;  // from the path start at base_speed_mps
  Eigen::Vector3f position_W = Eigen::Vector3f::Zero();
  float yaw_rad = 0.0f;  // wrapped to [−π, π]
  float pitch_rad = 0.0f;
  CameraBaseSample base;  // the base pose at this arc length (interpolated between samples)
};

struct CameraTrajectory {
  std::vector<CameraPathSample> samples;
  int workspace_clamps = 0;      // samples moved back into Ψ of their base pose
  int linear_speed_clamps = 0;   // steps shortened to v_m
  int angular_speed_clamps = 0;  // turns shortened to a_m
  int speed_violations = 0;      // steps still over a limit after clamping (Ψ wins over speed)
};

// X12 (X L308-310): "a path may stretch into an unknown region in which an obstacle could block
// the path. If such a case is detected, we add a look-at view pointing towards the unknown
// region, to the path samples near that region (< 2m), during the camera trajectory
// optimization. This ensures that the robot looks into that region before rushing into it."
struct CameraLookAtTarget {
  Eigen::Vector3f point_W = Eigen::Vector3f::Zero();  // a point of the unknown region
  float arc_length_m = 0.0f;                          // where along the base path the path meets it
};

struct CameraLookAtParams {
  float range_m = 2.0f;  // X L310: the samples nearer than this (horizontally) to the target
  // A view sees a target whose horizontal bearing from the camera lies within this of its yaw:
  // half the horizontal field of view (29°, half a Kinect v1's 58°; the planner passes its mode's).
  float half_fov_rad = 0.5061455f;
};

struct CameraLookAt {
  std::vector<CameraLookAtTarget> targets;  // by non-decreasing arc length; empty: X12 is off
  CameraLookAtParams params;
  CameraDirectionGainFn gain;  // the added view's V
};

struct CameraPathResult {
  CameraMode mode = CameraMode::kOptimized;
  // Per path sample; in "fixed" the one rigid pose (free space not asked, gain 0).
  std::vector<std::vector<CameraCandidate>> candidates;
  CameraSelection selection;
  CameraTrajectory trajectory;
  // X12, per path sample: the index of its look-at target (−1 none); and the counts: samples
  // with a target (and candidates), those whose selected view sees it, and those whose selected
  // view differs from the selection eq. 8 makes without the look-at views and term.
  std::vector<int> lookat_target;
  int lookat_samples = 0;
  int lookat_seen = 0;
  int lookat_changed = 0;
};

// X12's detection along a base path (world xy polyline), walked every step_m: each point where
// the robot's body, touch_m around the path, meets unknown space (nearest_unknown(p, touch_m):
// the nearest unknown point within touch_m of p, nullopt for none) gives a target there at
// height_m, keyed by the point's arc length; a target equal to the one before is not repeated.
using NearestUnknownFn =
    std::function<std::optional<Eigen::Vector2f>(const Eigen::Vector2f& p, float within_m)>;
std::vector<CameraLookAtTarget> FindLookAtTargets(std::span<const Eigen::Vector2f> line,
                                                  float touch_m, float step_m, float height_m,
                                                  const NearestUnknownFn& nearest_unknown);

// Per path sample: the first target at or ahead of its arc length (the region it is about to
// rush into) that lies within range_m of its base position, horizontally; −1 for none.
std::vector<int> AssignLookAtTargets(std::span<const CameraBaseSample> path,
                                     std::span<const CameraLookAtTarget> targets, float range_m);

// X12's U: 1 when the view from camera_W along yaw_rad sees target_W (its horizontal bearing
// within half_fov_rad of the yaw; a target at the camera counts as seen), else 0.
float LookAtScore(const Eigen::Vector3f& camera_W, float yaw_rad, const Eigen::Vector3f& target_W,
                  float half_fov_rad);

// X12 on sampled candidates: at every sample with a target (target_of_sample, −1 none) and at
// least one candidate, U of each candidate, and one more view appended, the look-at view: at the
// position of the sample's candidate nearest the target (in Ψ and free), looking at it level
// (pitch 0), its gain from lookat.gain.
void AddLookAtViews(std::span<const CameraBaseSample> path, const CameraLookAt& lookat,
                    std::span<const int> target_of_sample,
                    std::vector<std::vector<CameraCandidate>>* candidates);

// X5 (X L194): "At the wedge, both robot path and camera trajectory are replanned, thus
// splitting the path and trajectory at the point. During the stop, the robot computes a smooth
// connecting trajectory, to smoothly transit between the two separate camera trajectories."
// Where the camera is when a new trajectory starts.
struct CameraPose {
  // NaN: not known (a head, whose position is the base's; no earlier trajectory): the
  // trajectory's positions are kept.
  Eigen::Vector3f position_W = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  float yaw_rad = 0.0f;  // world
  float pitch_rad = 0.0f;
};

struct CameraConnectParams {
  CameraWorkspace workspace;
  CameraSpeedLimits limits;
  float floor_z_m = 0.0f;
  // The camera holds its pose for hold_s first (the host turning the base in place, the camera
  // carried round with it), then blends into the trajectory over a stretch at least min_s long,
  // and long enough that the blend alone turns and moves the camera at most at rate_share of each
  // limit (the rest is the trajectory's own motion).
  float hold_s = 0.0f;
  float min_s = 1.0f;
  float rate_share = 0.5f;
};

struct CameraConnection {
  bool connected = false;   // the trajectory was changed
  float jump_rad = 0.0f;    // ‖(Δyaw, Δpitch)‖ from the pose to the trajectory's start
  float jump_m = 0.0f;      // from the pose's position (0 when not known)
  float duration_s = 0.0f;  // hold + blend
  // The largest angular (linear) step speed over the connecting stretch: before, of the
  // trajectory as given with the jump from the pose taken in its first step; after, as connected.
  float max_radps_before = 0.0f, max_radps_after = 0.0f;
  float max_mps_before = 0.0f, max_mps_after = 0.0f;
  int speed_clamps = 0;      // connected steps shortened to a limit
  int workspace_clamps = 0;  // connected positions moved back into Ψ
};

// X5 on a dense trajectory (time_s from its first sample, in the time the host executes it):
// from `from` at the first sample to the trajectory, by the minimal rotation in (yaw, pitch)
// and a cubic blend in position. Over the stretch the difference between the pose and the
// trajectory (taken where the hold ends) is faded out with the smoothstep 3x² − 2x³, so the
// camera starts at the pose, leaves it at rest relative to the trajectory and joins the
// trajectory with its own velocity; positions are then clamped into Ψ of their base poses, and
// one forward pass keeps every step within the speed limits (Ψ wins over speed, as in
// InterpolateCameraPath). A trajectory already starting at the pose is left as it is.
CameraConnection ConnectCameraTrajectory(const CameraPose& from, const CameraConnectParams& params,
                                         CameraTrajectory* trajectory);

// Times of the samples from the path start: arc length / base speed.
std::vector<double> CameraSampleTimes(std::span<const CameraBaseSample> path, float base_speed_mps);

// The camera position for a base-frame offset in Ψ(base).
Eigen::Vector3f CameraPositionInWorkspace(const CameraBaseSample& base, float reach_m,
                                          float bearing_rad, float height_m, float floor_z_m);
// camera_W in the base frame: (forward, left, height above the floor).
Eigen::Vector3f CameraOffsetInBase(const Eigen::Vector3f& camera_W, const CameraBaseSample& base,
                                   float floor_z_m);
// True when camera_W lies in Ψ(base), within tol_m (and tol_m radians of bearing).
bool InCameraWorkspace(const Eigen::Vector3f& camera_W, const CameraBaseSample& base,
                       const CameraWorkspace& workspace, float floor_z_m, float tol_m = 1e-4f);
// camera_W moved into Ψ(base): height, reach and bearing clamped in the base's polar frame.
Eigen::Vector3f ClampToCameraWorkspace(const Eigen::Vector3f& camera_W,
                                       const CameraBaseSample& base,
                                       const CameraWorkspace& workspace, float floor_z_m);

// X L288: up to C free candidates in Ψ(p_s) per sample, each with its best view.
std::vector<std::vector<CameraCandidate>> SampleCameraCandidates(
    std::span<const CameraBaseSample> path, const CameraCandidateParams& params,
    const CameraFreeFn& free, const CameraScoreFn& score);

// Eq. 8, exactly, by dynamic programming over candidate pairs (x_{s−1}, x_s). times_s parallel to
// candidates (CameraSampleTimes). Ties go to the lowest candidate indices.
CameraSelection SelectCameraViews(std::span<const double> times_s,
                                  const std::vector<std::vector<CameraCandidate>>& candidates,
                                  const CameraSelectionParams& params);

// Eq. 8's terms and the speed constraints for any selection (one index per sample, −1 only for a
// sample without candidates; indices are clamped into range): the DP's objective, for tests and
// diagnostics. The penalty term is always reported as if the penalty pass had run.
CameraSelection EvaluateCameraSelection(std::span<const double> times_s,
                                        const std::vector<std::vector<CameraCandidate>>& candidates,
                                        std::span<const int> selected,
                                        const CameraSelectionParams& params);

// X L294: a cubic Hermite spline (Catmull-Rom tangents over base arc length) through the views
// (one per path sample, nullptr where none), viewing angles interpolated along the minimal
// rotation between adjacent views, clamped to Ψ and the speed limits in one forward pass (a clamped
// sample lags and the next ones catch up). Before the first and after the last view the view is
// held.
CameraTrajectory InterpolateCameraPath(std::span<const CameraBaseSample> path,
                                       std::span<const CameraCandidate* const> views,
                                       const CameraInterpolationParams& params);

// The whole of §5 in the given mode: candidates, selection and dense trajectory. With look-at
// targets (X12, not in "fixed": a rigid mount has nothing to choose) the candidates get their U
// and the look-at views before the selection.
CameraPathResult PlanCameraPath(std::span<const CameraBaseSample> path,
                                const CameraPathParams& params, const CameraFreeFn& free,
                                const CameraScoreFn& score);
CameraPathResult PlanCameraPath(std::span<const CameraBaseSample> path,
                                const CameraPathParams& params, const CameraFreeFn& free,
                                const CameraScoreFn& score, const CameraLookAt& lookat);

}  // namespace voxplan::tensorfield
