#pragma once
// A simulated ground robot carrying an RGB-D camera: an SE(2) base (x, y, θ) with a round
// footprint, a camera at fixed height on a yaw joint (Dong et al. 2019: the camera heading is
// independent of the direction of motion) with an optional pitch, and two scanning modes
// (Guo et al. 2022): a fast, far-seeing explorer and a slow, close, narrow reconstructor.
// Motion is checked against the world's true FloorPlan and timed on a simulation clock.
#include <Eigen/Core>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/pose.h"
#include "core/status.h"
#include "sim/floor_plan.h"

namespace voxplan {

inline float Deg2Rad(float deg) { return deg * std::numbers::pi_v<float> / 180.f; }

enum class RobotMode { kExplorer, kReconstructor };
const char* RobotModeName(RobotMode mode);  // "explorer", "reconstructor"

// Where a mode's camera sits. A head: over the base centre at RobotParams::camera_height_m,
// tilting within RobotParams::max_abs_pitch_deg. An arm (Guo 2022's reconstructor, a 7-DOF arm
// holding the camera): anywhere in ArmParams' workspace around the base.
enum class MountKind { kHead, kArm };
const char* MountKindName(MountKind mount);  // "head", "arm"

// The arm's workspace. Guo gives none ("within the reachable range of the robot's arm"); these
// are a Fetch-sized arm's: the camera 0.4-1.5 m above the floor, 0.3-0.8 m from the base centre
// at a bearing within +-90 deg of the heading, pitched anywhere in +-90 deg (the paper's phi).
struct ArmParams {
  float height_min_m = 0.4f, height_max_m = 1.5f;
  float reach_min_m = 0.3f, reach_max_m = 0.8f;
  float reach_half_angle_deg = 90.f;
  float max_abs_pitch_deg = 90.f;
  float speed_mps = 0.25f;  // the camera along the arm
};

// What a mode changes: speeds and the sensor's field of view and range.
struct ModeParams {
  float max_speed_mps = 0.5f;
  float max_turn_rate_radps = 1.0f;  // base, turning in place
  float horizontal_fov_deg = 90.0f;
  float max_range_m = 5.0f;
  // Frames per second on the run clock, while driving, turning and dwelling (a slow, close scan
  // gathers more); 0: captured by displacement (FusionTrigger) and once per view. At most
  // kMaxCaptureHz.
  float capture_hz = 0.0f;
  MountKind mount = MountKind::kHead;
  ArmParams arm;             // with mount kArm
  float min_range_m = 0.1f;  // nearer depth is not fused
  float switch_s = 0.f;      // switching into this mode (stowing or unstowing the arm)
};
inline constexpr float kMaxCaptureHz = 60.0f;
inline constexpr float kMaxSwitchS = 600.0f;
ModeParams DefaultModeParams(RobotMode mode);

struct RobotParams {
  float radius_m = 0.2f;         // round footprint
  float camera_height_m = 1.2f;  // optical centre above the floor (z = 0)
  float camera_yaw_rate_radps = 1.5f;
  float camera_pitch_rate_radps = 1.0f;
  float max_abs_pitch_deg = 60.0f;
  float dwell_s = 0.2f;  // standing still per captured view
  int image_width = 640, image_height = 480;
  ModeParams explorer = DefaultModeParams(RobotMode::kExplorer);
  ModeParams reconstructor = DefaultModeParams(RobotMode::kReconstructor);

  Status Validate() const;
  const ModeParams& mode(RobotMode m) const {
    return m == RobotMode::kExplorer ? explorer : reconstructor;
  }
};

struct RobotState {
  Eigen::Vector2f position_W = Eigen::Vector2f::Zero();  // base centre on the floor, metres
  float heading_rad = 0.f;                               // base θ, from world +x towards +y
  float camera_yaw_rad = 0.f;    // joint angle relative to the base (unwrapped)
  float camera_pitch_rad = 0.f;  // positive looks up
  // The optical centre's offset from the head position (the base centre at camera_height_m),
  // in the base frame (x forward, y left, z up); zero for a head mount.
  Eigen::Vector3f camera_offset_B = Eigen::Vector3f::Zero();
};

// Camera-to-world pose of the camera (OpenCV axes: x right, y down, z forward) for a state.
Pose3f CameraPoseFromState(const RobotState& state, float camera_height_m);

// The arm camera's place in the base frame for a height above the floor and a horizontal offset
// (forward, left) from the base centre, as RobotState::camera_offset_B; and whether it lies in
// the workspace (empty string) or why not.
Eigen::Vector3f ArmOffset(float camera_height_m, const Eigen::Vector2f& offset_m,
                          float head_height_m);
std::string ArmWorkspaceProblem(const ArmParams& arm, float camera_height_m,
                                const Eigen::Vector2f& offset_m);
// Moves a finite camera height and offset into the workspace, one coordinate at a time (it is a
// box in height, reach and bearing): the height into its range, the bearing within its half
// angle, the reach into its range (straight ahead from zero reach). Returns whether it moved
// them, i.e. whether ArmWorkspaceProblem had one; a place inside is left as it is.
bool ClampToArmWorkspace(const ArmParams& arm, float* camera_height_m, Eigen::Vector2f* offset_m);
// Where the arm camera gets from offset `from` towards `to` (RobotState::camera_offset_B) moving
// at most max_m along its path: height, reach and bearing each change linearly, as the joints
// move, so the path stays in the workspace when both ends are (a straight line could pass
// through the reach's inner limit). `to` itself when the path is no longer than max_m.
Eigen::Vector3f ArmStep(const Eigen::Vector3f& from, const Eigen::Vector3f& to, float max_m);
// Square-pixel camera with the given horizontal field of view, principal point at the centre.
PinholeCamera CameraWithFov(int width, int height, float horizontal_fov_deg);

// True when every plan cell whose centre lies within radius_m of p_W is free (cells outside the
// plan count as blocked).
bool FootprintFree(const FloorPlan& plan, const Eigen::Vector2f& p_W, float radius_m);
// True when the footprint is free at every point of the segment (sampled every quarter cell).
bool SegmentFree(const FloorPlan& plan, const Eigen::Vector2f& a_W, const Eigen::Vector2f& b_W,
                 float radius_m);
// What a bumper feels driving the footprint from a_W towards b_W: the centres of the plan cells
// that block it (obstacle or outside) at the first blocked point of the segment, sampled as
// SegmentFree does, in row-major order; empty when the segment is free.
std::vector<Eigen::Vector2f> FirstContact(const FloorPlan& plan, const Eigen::Vector2f& a_W,
                                          const Eigen::Vector2f& b_W, float radius_m);

class Robot {
 public:
  // Refuses invalid params and a start pose whose footprint is not free.
  static Result<Robot> Create(const RobotParams& params, FloorPlan plan, const RobotState& start,
                              RobotMode mode = RobotMode::kExplorer);

  const RobotState& state() const { return state_; }
  const RobotParams& params() const { return params_; }
  const FloorPlan& plan() const { return plan_; }
  RobotMode mode() const { return mode_; }
  const ModeParams& mode_params() const { return params_.mode(mode_); }
  double clock_s() const { return clock_s_; }
  double distance_m() const { return distance_m_; }

  // Switching into another mode costs its switch_s and puts the camera at the new mount's rest
  // pose (the arm: nearest reach straight ahead at the head's height, clamped to its range), its
  // pitch within the new limit. The same mode: nothing.
  void SetMode(RobotMode mode);
  // The arm camera to a height and horizontal offset (ArmOffset); costs the distance at the
  // arm's speed. Refused (state and clock unchanged) outside the workspace or on a head mount.
  Status SetArmCamera(float camera_height_m, const Eigen::Vector2f& offset_m);
  // The current mode's pitch limit.
  float max_abs_pitch_rad() const;
  // The current mode's camera at rest (RobotState::camera_offset_B).
  Eigen::Vector3f RestOffset() const;
  size_t switches() const { return switches_; }
  // Turns the base in place to `heading_rad` the short way; costs |Δθ| / turn rate.
  void TurnTo(float heading_rad);
  // Turns towards the goal, then drives straight at the mode's speed. Refuses (state and clock
  // unchanged) a goal whose straight segment the footprint cannot pass.
  Status DriveTo(const Eigen::Vector2f& goal_W);
  // One piece of continuous motion (a followed path, Xu 2017): drives straight to the goal while
  // the base turns to the piece's direction and the camera joints move to their targets, all at
  // once, so the piece takes the longest of length / speed (clamped to the mode's), the base's
  // turn at its rate and each joint's move at its rate. Refuses (state and clock unchanged) what
  // DriveTo refuses and a pitch beyond the limit.
  // With `arm_offset_B` (RobotState::camera_offset_B; an arm mount, inside its workspace, else
  // refused) the arm camera moves towards it during the piece too (ArmStep), by at most the arm's
  // speed times the piece's time: the piece takes no longer for it, so the base keeps its speed
  // profile and a camera trajectory timed along it its timing; a farther target is reached by
  // later pieces. The caller sees a step cut short as camera_offset_B differing from the target.
  Status DriveAlong(const Eigen::Vector2f& goal_W, float speed_mps, float camera_yaw_rad,
                    float camera_pitch_rad,
                    const std::optional<Eigen::Vector3f>& arm_offset_B = std::nullopt);
  // Camera joints; each costs |Δangle| / joint rate. Pitch beyond the limit is refused.
  void SetCameraYaw(float yaw_rad);
  Status SetCameraPitch(float pitch_rad);
  // The yaw joint turns without end: drops whole turns from its angle, taking no time.
  void WrapCameraYaw();
  // Stands still for the dwell time of one view.
  void Dwell() { clock_s_ += params_.dwell_s; }

  Pose3f T_W_C() const { return CameraPoseFromState(state_, params_.camera_height_m); }
  // The current mode's camera (field of view) at the robot's image size.
  PinholeCamera camera() const;

 private:
  Robot() = default;
  RobotParams params_;
  FloorPlan plan_;
  RobotState state_;
  RobotMode mode_ = RobotMode::kExplorer;
  double clock_s_ = 0.0;
  double distance_m_ = 0.0;
  size_t switches_ = 0;
};

// Fires for the first pose, then whenever the camera has moved more than min_translation_m or
// turned more than min_rotation_deg since the last pose it fired for.
struct FusionTriggerParams {
  float min_translation_m = 0.1f;
  float min_rotation_deg = 10.0f;
};

class FusionTrigger {
 public:
  explicit FusionTrigger(const FusionTriggerParams& params = {}) : params_(params) {}
  bool ShouldFuse(const Pose3f& T_W_C);  // true: the caller fuses this frame
  size_t fired() const { return fired_; }

 private:
  FusionTriggerParams params_;
  bool has_last_ = false;
  Pose3f last_T_W_C_ = Pose3f::Identity();
  size_t fired_ = 0;
};

}  // namespace voxplan
