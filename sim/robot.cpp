#include "sim/robot.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

namespace voxplan {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Wraps an angle difference into (-π, π].
float WrapAngle(float a) {
  a = std::remainder(a, 2.f * kPi);
  return a <= -kPi ? a + 2.f * kPi : a;
}

std::string Point(const Eigen::Vector2f& p) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

Status ValidateMode(const ModeParams& m, const char* name) {
  if (!(m.max_speed_mps > 0.f) || !(m.max_turn_rate_radps > 0.f))
    return InvalidArgument(std::string("RobotParams: ") + name + " speeds must be > 0");
  if (!(m.horizontal_fov_deg > 1.f && m.horizontal_fov_deg < 179.f))
    return InvalidArgument(std::string("RobotParams: ") + name +
                           " horizontal_fov_deg must be in (1, 179)");
  if (!(m.max_range_m > 0.f))
    return InvalidArgument(std::string("RobotParams: ") + name + " max_range_m must be > 0");
  if (!(m.min_range_m > 0.f && m.min_range_m < m.max_range_m))
    return InvalidArgument(std::string("RobotParams: ") + name +
                           " min_range_m must be > 0 and below max_range_m");
  if (!(m.switch_s >= 0.f && m.switch_s <= kMaxSwitchS))
    return InvalidArgument(std::string("RobotParams: ") + name + " switch_s must be in [0, " +
                           std::to_string(int(kMaxSwitchS)) + "] s");
  if (m.mount == MountKind::kArm) {
    const ArmParams& a = m.arm;
    if (!(a.height_min_m > 0.f && a.height_min_m <= a.height_max_m && a.height_max_m <= 3.f))
      return InvalidArgument(std::string("RobotParams: ") + name +
                             " arm heights must satisfy 0 < min <= max <= 3 m");
    if (!(a.reach_min_m >= 0.f && a.reach_min_m <= a.reach_max_m && a.reach_max_m <= 3.f))
      return InvalidArgument(std::string("RobotParams: ") + name +
                             " arm reach must satisfy 0 <= min <= max <= 3 m");
    if (!(a.reach_half_angle_deg >= 0.f && a.reach_half_angle_deg <= 180.f))
      return InvalidArgument(std::string("RobotParams: ") + name +
                             " arm reach_half_angle_deg must be in [0, 180]");
    if (!(a.max_abs_pitch_deg >= 0.f && a.max_abs_pitch_deg <= 90.f))
      return InvalidArgument(std::string("RobotParams: ") + name +
                             " arm max_abs_pitch_deg must be in [0, 90]");
    if (!(a.speed_mps > 0.f && a.speed_mps <= 10.f))
      return InvalidArgument(std::string("RobotParams: ") + name +
                             " arm speed_mps must be in (0, 10]");
  }
  if (!(m.capture_hz >= 0.f && m.capture_hz <= kMaxCaptureHz))
    return InvalidArgument(std::string("RobotParams: ") + name + " capture_hz must be in [0, " +
                           std::to_string(int(kMaxCaptureHz)) + "]");
  return Status::Ok();
}

}  // namespace

const char* MountKindName(MountKind mount) { return mount == MountKind::kHead ? "head" : "arm"; }

const char* RobotModeName(RobotMode mode) {
  return mode == RobotMode::kExplorer ? "explorer" : "reconstructor";
}

ModeParams DefaultModeParams(RobotMode mode) {
  // Explorer: fast with far, wide vision; reconstructor: slow, close, narrow (Guo 2022 §3).
  // Speeds around Dong 2019's 0.3 m/s Turtlebots.
  ModeParams m;
  if (mode == RobotMode::kExplorer) {
    m.max_speed_mps = 0.5f;
    m.max_turn_rate_radps = 1.0f;
    m.horizontal_fov_deg = 90.0f;
    m.max_range_m = 5.0f;
  } else {
    m.max_speed_mps = 0.2f;
    m.max_turn_rate_radps = 0.5f;
    m.horizontal_fov_deg = 58.0f;
    m.max_range_m = 2.5f;
  }
  return m;
}

Status RobotParams::Validate() const {
  if (!(radius_m > 0.f)) return InvalidArgument("RobotParams: radius_m must be > 0");
  if (!(camera_height_m > 0.f)) return InvalidArgument("RobotParams: camera_height_m must be > 0");
  if (!(camera_yaw_rate_radps > 0.f) || !(camera_pitch_rate_radps > 0.f))
    return InvalidArgument("RobotParams: camera joint rates must be > 0");
  if (!(max_abs_pitch_deg >= 0.f && max_abs_pitch_deg < 90.f))
    return InvalidArgument("RobotParams: max_abs_pitch_deg must be in [0, 90)");
  if (!(dwell_s >= 0.f)) return InvalidArgument("RobotParams: dwell_s must be >= 0");
  if (image_width <= 0 || image_height <= 0)
    return InvalidArgument("RobotParams: image size must be positive");
  VOXPLAN_RETURN_IF_ERROR(ValidateMode(explorer, "explorer"));
  return ValidateMode(reconstructor, "reconstructor");
}

Pose3f CameraPoseFromState(const RobotState& state, float camera_height_m) {
  const float psi = state.heading_rad + state.camera_yaw_rad;
  const float phi = state.camera_pitch_rad;
  const Eigen::Vector3f forward(std::cos(phi) * std::cos(psi), std::cos(phi) * std::sin(psi),
                                std::sin(phi));
  const Eigen::Vector3f right(std::sin(psi), -std::cos(psi), 0.f);
  const Eigen::Vector3f down = forward.cross(right);  // OpenCV: x right, y down, z forward
  Pose3f T_W_C = Pose3f::Identity();
  T_W_C.linear().col(0) = right;
  T_W_C.linear().col(1) = down;
  T_W_C.linear().col(2) = forward;
  T_W_C.translation() =
      Eigen::Vector3f(state.position_W.x(), state.position_W.y(), camera_height_m);
  const Eigen::Vector3f& o = state.camera_offset_B;
  if (!o.isZero(0.f)) {  // a head camera's pose stays exactly as it always was
    const float c = std::cos(state.heading_rad), s = std::sin(state.heading_rad);
    T_W_C.translation() += Eigen::Vector3f(c * o.x() - s * o.y(), s * o.x() + c * o.y(), o.z());
  }
  return T_W_C;
}

Eigen::Vector3f ArmOffset(float camera_height_m, const Eigen::Vector2f& offset_m,
                          float head_height_m) {
  return {offset_m.x(), offset_m.y(), camera_height_m - head_height_m};
}

namespace {
// How far outside the workspace a place still counts as inside: float round trips through the ABI.
constexpr float kArmSlack_m = 1e-4f, kArmSlack_deg = 1e-2f;

float BearingRad(const Eigen::Vector2f& offset_m) {
  return offset_m.norm() > 0.f ? std::atan2(offset_m.y(), offset_m.x()) : 0.f;
}
float BearingDeg(const Eigen::Vector2f& offset_m) { return BearingRad(offset_m) * 180.f / kPi; }
}  // namespace

std::string ArmWorkspaceProblem(const ArmParams& arm, float camera_height_m,
                                const Eigen::Vector2f& offset_m) {
  constexpr float kSlack = kArmSlack_m;
  const auto num = [](float v) {
    std::ostringstream s;
    s.precision(3);
    s << v;
    return s.str();
  };
  if (!std::isfinite(camera_height_m) || !offset_m.allFinite()) return "not finite";
  if (camera_height_m < arm.height_min_m - kSlack || camera_height_m > arm.height_max_m + kSlack)
    return "camera height " + num(camera_height_m) + " m outside the arm's [" +
           num(arm.height_min_m) + ", " + num(arm.height_max_m) + "] m";
  const float reach = offset_m.norm();
  if (reach < arm.reach_min_m - kSlack || reach > arm.reach_max_m + kSlack)
    return "camera reach " + num(reach) + " m outside the arm's [" + num(arm.reach_min_m) + ", " +
           num(arm.reach_max_m) + "] m";
  const float bearing_deg = BearingDeg(offset_m);
  if (std::abs(bearing_deg) > arm.reach_half_angle_deg + kArmSlack_deg)
    return "camera bearing " + num(bearing_deg) + " deg beyond the arm's +-" +
           num(arm.reach_half_angle_deg) + " deg";
  return "";
}

bool ClampToArmWorkspace(const ArmParams& arm, float* camera_height_m, Eigen::Vector2f* offset_m) {
  if (!std::isfinite(*camera_height_m) || !offset_m->allFinite()) return false;
  if (ArmWorkspaceProblem(arm, *camera_height_m, *offset_m).empty()) return false;
  if (*camera_height_m < arm.height_min_m - kArmSlack_m ||
      *camera_height_m > arm.height_max_m + kArmSlack_m)
    *camera_height_m = std::clamp(*camera_height_m, arm.height_min_m, arm.height_max_m);
  const float reach = offset_m->norm(), bearing_deg = BearingDeg(*offset_m);
  const bool reach_out =
      reach < arm.reach_min_m - kArmSlack_m || reach > arm.reach_max_m + kArmSlack_m;
  const bool bearing_out = std::abs(bearing_deg) > arm.reach_half_angle_deg + kArmSlack_deg;
  if (reach_out || bearing_out) {  // only then rebuilt, so a height-only clamp keeps the offset
    const float r = std::clamp(reach, arm.reach_min_m, arm.reach_max_m);
    const float b =
        Deg2Rad(std::clamp(bearing_deg, -arm.reach_half_angle_deg, arm.reach_half_angle_deg));
    *offset_m = r * Eigen::Vector2f(std::cos(b), std::sin(b));
  }
  return true;
}

PinholeCamera CameraWithFov(int width, int height, float horizontal_fov_deg) {
  const float f = 0.5f * float(width) / std::tan(0.5f * Deg2Rad(horizontal_fov_deg));
  return {width, height, f, f, 0.5f * float(width - 1), 0.5f * float(height - 1)};
}

namespace {

// Visits the plan cells under the footprint that are not free (outside the plan counts), in
// row-major order, until blocked(x, y) returns false; true when there was none.
template <typename Blocked>
bool VisitBlocked(const FloorPlan& plan, const Eigen::Vector2f& p_W, float radius_m,
                  Blocked&& blocked) {
  const float res = plan.resolution_m;
  const Eigen::Vector2f lo =
      (p_W - plan.origin_W) / res - Eigen::Vector2f::Constant(radius_m / res);
  const Eigen::Vector2f hi =
      (p_W - plan.origin_W) / res + Eigen::Vector2f::Constant(radius_m / res);
  const int x0 = int(std::floor(lo.x() - 0.5f)), x1 = int(std::ceil(hi.x() - 0.5f));
  const int y0 = int(std::floor(lo.y() - 0.5f)), y1 = int(std::ceil(hi.y() - 0.5f));
  // A cell centre at the radius itself touches, it does not block: the host measures clearance
  // between cell centres and routes at exactly the radius where it must (the map's and the
  // plan's centres then lie the radius apart, give or take float rounding, absorbed here).
  constexpr float kTouch_m = 1e-4f;
  const float reach_m = std::max(radius_m - kTouch_m, 0.f);
  const float r2 = reach_m * reach_m;
  bool any = false, free = true;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      if ((plan.CellCenter(x, y) - p_W).squaredNorm() > r2) continue;
      any = true;
      if (plan.Contains(x, y) && plan.at(x, y) == PlanCell::kFree) continue;
      free = false;
      if (!blocked(x, y)) return false;
    }
  if (!any) {  // footprint smaller than a cell: the cell under the centre decides
    const Eigen::Vector2f c = (p_W - plan.origin_W) / res;
    const int x = int(std::floor(c.x())), y = int(std::floor(c.y()));
    if (plan.Contains(x, y) && plan.at(x, y) == PlanCell::kFree) return true;
    blocked(x, y);
    return false;
  }
  return free;
}

// Footprint samples of a segment: every quarter cell, both ends included.
int SegmentSteps(const FloorPlan& plan, const Eigen::Vector2f& a_W, const Eigen::Vector2f& b_W) {
  return std::max(1, int(std::ceil((b_W - a_W).norm() / (0.25f * plan.resolution_m))));
}

}  // namespace

bool FootprintFree(const FloorPlan& plan, const Eigen::Vector2f& p_W, float radius_m) {
  if (plan.width <= 0 || plan.height <= 0 || !p_W.allFinite()) return false;
  return VisitBlocked(plan, p_W, radius_m, [](int, int) { return false; });
}

bool SegmentFree(const FloorPlan& plan, const Eigen::Vector2f& a_W, const Eigen::Vector2f& b_W,
                 float radius_m) {
  const int steps = SegmentSteps(plan, a_W, b_W);
  for (int i = 0; i <= steps; ++i)
    if (!FootprintFree(plan, a_W + (b_W - a_W) * (float(i) / float(steps)), radius_m)) return false;
  return true;
}

std::vector<Eigen::Vector2f> FirstContact(const FloorPlan& plan, const Eigen::Vector2f& a_W,
                                          const Eigen::Vector2f& b_W, float radius_m) {
  std::vector<Eigen::Vector2f> contact;
  if (plan.width <= 0 || plan.height <= 0 || !a_W.allFinite() || !b_W.allFinite()) return contact;
  const int steps = SegmentSteps(plan, a_W, b_W);
  for (int i = 0; i <= steps && contact.empty(); ++i)
    VisitBlocked(plan, a_W + (b_W - a_W) * (float(i) / float(steps)), radius_m, [&](int x, int y) {
      contact.push_back(plan.CellCenter(x, y));
      return true;
    });
  return contact;
}

namespace {

// The arm camera's move between two offsets (RobotState::camera_offset_B) at fraction f:
// height, reach and bearing each linear, as the arm's joints move. The workspace is a box in
// those, so the move stays inside it when both ends are; a straight line would cut through the
// reach's inner limit, and a camera projected back onto it there would never get past.
Eigen::Vector3f ArmPathPoint(const Eigen::Vector3f& from, const Eigen::Vector3f& to, float f) {
  const float r = from.head<2>().norm() + f * (to.head<2>().norm() - from.head<2>().norm());
  const float b0 = BearingRad(from.head<2>()), b1 = BearingRad(to.head<2>());
  const float b = b0 + f * (b1 - b0);
  return {r * std::cos(b), r * std::sin(b), from.z() + f * (to.z() - from.z())};
}

}  // namespace

Eigen::Vector3f ArmStep(const Eigen::Vector3f& from, const Eigen::Vector3f& to, float max_m) {
  // The path's length from its chords; a step ends where that length reaches max_m.
  constexpr int kChords = 16;
  std::array<float, kChords + 1> along{};
  Eigen::Vector3f last = from;
  for (int k = 1; k <= kChords; ++k) {
    const Eigen::Vector3f p = ArmPathPoint(from, to, float(k) / kChords);
    along[size_t(k)] = along[size_t(k - 1)] + (p - last).norm();
    last = p;
  }
  if (along.back() <= max_m) return to;
  int k = 1;
  while (along[size_t(k)] < max_m) ++k;
  const float chord = along[size_t(k)] - along[size_t(k - 1)];
  const float within = chord > 0.f ? (max_m - along[size_t(k - 1)]) / chord : 0.f;
  return ArmPathPoint(from, to, (float(k - 1) + within) / kChords);
}

Result<Robot> Robot::Create(const RobotParams& params, FloorPlan plan, const RobotState& start,
                            RobotMode mode) {
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  if (plan.width <= 0 || plan.height <= 0 ||
      plan.cells.size() != size_t(plan.width) * size_t(plan.height))
    return InvalidArgument("Robot: empty or inconsistent floor plan");
  if (!FootprintFree(plan, start.position_W, params.radius_m))
    return InvalidArgument("Robot: start " + Point(start.position_W) + " with radius " +
                           std::to_string(params.radius_m) +
                           " m overlaps an obstacle or lies outside the floor plan");
  Robot robot;
  robot.params_ = params;
  robot.plan_ = std::move(plan);
  robot.state_ = start;
  robot.mode_ = mode;
  if (std::abs(start.camera_pitch_rad) > robot.max_abs_pitch_rad())
    return InvalidArgument("Robot: start camera pitch beyond the mode's limit");
  robot.state_.camera_offset_B = robot.RestOffset();
  return robot;
}

float Robot::max_abs_pitch_rad() const {
  const ModeParams& m = mode_params();
  return Deg2Rad(m.mount == MountKind::kArm ? m.arm.max_abs_pitch_deg : params_.max_abs_pitch_deg);
}

Eigen::Vector3f Robot::RestOffset() const {
  const ModeParams& m = mode_params();
  if (m.mount == MountKind::kHead) return Eigen::Vector3f::Zero();
  const float h = std::clamp(params_.camera_height_m, m.arm.height_min_m, m.arm.height_max_m);
  return ArmOffset(h, {m.arm.reach_min_m, 0.f}, params_.camera_height_m);
}

void Robot::SetMode(RobotMode mode) {
  if (mode == mode_) return;
  mode_ = mode;
  ++switches_;
  clock_s_ += mode_params().switch_s;
  state_.camera_offset_B = RestOffset();
  const float limit = max_abs_pitch_rad();
  state_.camera_pitch_rad = std::clamp(state_.camera_pitch_rad, -limit, limit);
}

Status Robot::SetArmCamera(float camera_height_m, const Eigen::Vector2f& offset_m) {
  const ModeParams& m = mode_params();
  if (m.mount != MountKind::kArm)
    return InvalidArgument("Robot::SetArmCamera: the " + std::string(RobotModeName(mode_)) +
                           " camera is on a head");
  if (const std::string why = ArmWorkspaceProblem(m.arm, camera_height_m, offset_m); !why.empty())
    return InvalidArgument("Robot::SetArmCamera: " + why);
  const Eigen::Vector3f target = ArmOffset(camera_height_m, offset_m, params_.camera_height_m);
  clock_s_ += (target - state_.camera_offset_B).norm() / m.arm.speed_mps;
  state_.camera_offset_B = target;
  return Status::Ok();
}

void Robot::TurnTo(float heading_rad) {
  const float delta = WrapAngle(heading_rad - state_.heading_rad);
  clock_s_ += std::abs(delta) / mode_params().max_turn_rate_radps;
  state_.heading_rad += delta;
}

Status Robot::DriveTo(const Eigen::Vector2f& goal_W) {
  const Eigen::Vector2f delta = goal_W - state_.position_W;
  const float length = delta.norm();
  if (!goal_W.allFinite()) return InvalidArgument("Robot::DriveTo: goal is not finite");
  if (length == 0.f) return Status::Ok();
  if (!SegmentFree(plan_, state_.position_W, goal_W, params_.radius_m))
    return InvalidArgument("Robot::DriveTo: path " + Point(state_.position_W) + " -> " +
                           Point(goal_W) + " collides with the floor plan");
  TurnTo(std::atan2(delta.y(), delta.x()));
  clock_s_ += length / mode_params().max_speed_mps;
  distance_m_ += length;
  state_.position_W = goal_W;
  return Status::Ok();
}

Status Robot::DriveAlong(const Eigen::Vector2f& goal_W, float speed_mps, float camera_yaw_rad,
                         float camera_pitch_rad,
                         const std::optional<Eigen::Vector3f>& arm_offset_B) {
  if (!goal_W.allFinite() || !(speed_mps > 0.f) || !std::isfinite(camera_yaw_rad))
    return InvalidArgument("Robot::DriveAlong: goal, speed or camera yaw is not valid");
  if (!(std::abs(camera_pitch_rad) <= max_abs_pitch_rad()))
    return InvalidArgument("Robot::DriveAlong: pitch beyond the limit");
  const float head_h = params_.camera_height_m;
  if (arm_offset_B) {
    if (mode_params().mount != MountKind::kArm)
      return InvalidArgument("Robot::DriveAlong: the " + std::string(RobotModeName(mode_)) +
                             " camera is on a head");
    const Eigen::Vector3f& o = *arm_offset_B;
    if (const std::string why = ArmWorkspaceProblem(mode_params().arm, o.z() + head_h, o.head<2>());
        !why.empty())
      return InvalidArgument("Robot::DriveAlong: " + why);
  }
  const Eigen::Vector2f delta = goal_W - state_.position_W;
  const float length = delta.norm();
  if (length > 0.f && !SegmentFree(plan_, state_.position_W, goal_W, params_.radius_m))
    return InvalidArgument("Robot::DriveAlong: path " + Point(state_.position_W) + " -> " +
                           Point(goal_W) + " collides with the floor plan");
  const ModeParams& m = mode_params();
  const float turn =
      length > 0.f ? WrapAngle(std::atan2(delta.y(), delta.x()) - state_.heading_rad) : 0.f;
  const double duration = std::max(
      {double(length) / std::min(speed_mps, m.max_speed_mps),
       double(std::abs(turn)) / m.max_turn_rate_radps,
       double(std::abs(camera_yaw_rad - state_.camera_yaw_rad)) / params_.camera_yaw_rate_radps,
       double(std::abs(camera_pitch_rad - state_.camera_pitch_rad)) /
           params_.camera_pitch_rate_radps});
  clock_s_ += duration;
  distance_m_ += length;
  state_.position_W = goal_W;
  state_.heading_rad += turn;
  state_.camera_yaw_rad = camera_yaw_rad;
  state_.camera_pitch_rad = camera_pitch_rad;
  if (arm_offset_B)
    state_.camera_offset_B =
        ArmStep(state_.camera_offset_B, *arm_offset_B, float(duration) * m.arm.speed_mps);
  return Status::Ok();
}

void Robot::SetCameraYaw(float yaw_rad) {
  clock_s_ += std::abs(yaw_rad - state_.camera_yaw_rad) / params_.camera_yaw_rate_radps;
  state_.camera_yaw_rad = yaw_rad;
}

void Robot::WrapCameraYaw() { state_.camera_yaw_rad = WrapAngle(state_.camera_yaw_rad); }

Status Robot::SetCameraPitch(float pitch_rad) {
  if (!(std::abs(pitch_rad) <= max_abs_pitch_rad()))
    return InvalidArgument("Robot::SetCameraPitch: " + std::to_string(pitch_rad * 180.f / kPi) +
                           " deg is beyond the limit of " +
                           std::to_string(max_abs_pitch_rad() * 180.f / kPi) + " deg");
  clock_s_ += std::abs(pitch_rad - state_.camera_pitch_rad) / params_.camera_pitch_rate_radps;
  state_.camera_pitch_rad = pitch_rad;
  return Status::Ok();
}

PinholeCamera Robot::camera() const {
  return CameraWithFov(params_.image_width, params_.image_height, mode_params().horizontal_fov_deg);
}

bool FusionTrigger::ShouldFuse(const Pose3f& T_W_C) {
  bool fire = !has_last_;
  if (!fire) {
    const float moved = (T_W_C.translation() - last_T_W_C_.translation()).norm();
    const Eigen::AngleAxisf turned(last_T_W_C_.linear().transpose() * T_W_C.linear());
    fire = moved > params_.min_translation_m ||
           std::abs(turned.angle()) > Deg2Rad(params_.min_rotation_deg);
  }
  if (fire) {
    has_last_ = true;
    last_T_W_C_ = T_W_C;
    ++fired_;
  }
  return fire;
}

}  // namespace voxplan
