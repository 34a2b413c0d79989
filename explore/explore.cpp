#include "explore/explore.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/bounds.h"
#include "core/queries.h"
#include "core/summary.h"
#include "explore/explore_world.h"
#include "fusion/integrate.h"
#include "planning/integrate_planning.h"
#include "planning/map_summary.h"
#include "sim/raycaster.h"
#include "sim/sensor_noise.h"

namespace voxplan {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr uint32_t kPathOnlyTag = 0xffffffffu;  // a task made for a path given without tasks

// Into [-π, π]: a turn of exactly ±π keeps its sign (the way the robot turns around).
float WrapAngle(float a) { return std::remainder(a, 2.f * kPi); }

float Clamp(float v, float limit) { return std::clamp(v, -limit, limit); }

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string Fmt(double v, int decimals = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

struct QueuedTask {
  PlannerTask task;
  std::vector<Eigen::Vector2f> path;  // the plugin's dense path to it; empty: route on the map
  // vp.motion: the path is driven without stopping (a path-only task: no final turn or dwell),
  // each point at its speed (parallel to path; empty: the mode's speed).
  bool continuous = false;
  std::vector<float> speeds_mps = {};
  bool dwelt = false;        // at the view: the dwell's frames are taken
  int sweep_steps_done = 0;  // then the pitch sweep's (TaskCamera)
};

struct RobotRun {
  RobotRun(size_t i, Robot r, const FusionTriggerParams& trigger_params)
      : index(i), robot(std::move(r)), trigger(trigger_params) {}
  size_t index = 0;
  Robot robot;
  FusionTrigger trigger;
  std::deque<QueuedTask> queue;
  bool routed = false;                // the front task's route is set
  std::deque<Eigen::Vector2f> route;  // waypoints left to the front task
  std::deque<float> route_speed_mps;  // a continuous task's speed per waypoint (else empty)
  std::vector<CameraSample> camera_trajectory;
  double trajectory_t0_s = 0.0;
  // Continuous pieces driven since the trajectory was given, each at its length over its speed:
  // the trajectory's time for the distance driven along the path (ArmTarget), whatever the
  // pieces really took.
  double path_s = 0.0;
  double t_s = 0.0;  // this robot's time on the run clock (its Robot clock plus waiting)
  bool idle = false;
  double next_capture_s = 0.0;  // time-based capture (ModeParams::capture_hz): the next frame
  // Tracked poses: a tracker per mode (each mode's camera), the last frame's true and fused
  // camera poses (the odometry's start and the tracker's prior's base).
  // (Shared: RobotRun is copied when robots_ grows, and a tracker cannot be.)
  std::map<int, std::shared_ptr<FrameTracker>> trackers;
  bool tracking_started = false;  // after the start sweep
  Pose3f last_true_T_W_C = Pose3f::Identity(), last_fused_T_W_C = Pose3f::Identity();
  double idle_s = 0.0;  // of t_s, with an empty queue
  uint64_t frames = 0;
  RobotTrack track;
  std::vector<PlannerTask> views;
};

struct CameraAim {
  float yaw_rad, pitch_rad;  // camera yaw relative to the base; pitch
};

struct Failure {
  size_t robot = 0;
  PlannerTask task;
};

// The scene's interior for the unobserved-volume curve (RunTimePoint::unobserved_m3): the
// planning map's voxels whose centre lies over a cell of the true plan with a floor (free or
// obstacle, FloorArea's cells) and between the floor and the floor map's band top (the robot's
// height, where completeness_below_robot stops too). Fixed for the run, so the curve only falls:
// fused weights never decrease, so an observed voxel stays observed. Wall and furniture cores
// are in it and are never observed, so it levels off above zero.
ColumnRegion InteriorRegion(const FloorPlan& plan, const ExploreParams& p) {
  const double s = p.voxel_size_m;
  std::vector<Eigen::Vector2i> columns;
  if (plan.width > 0 && plan.height > 0) {
    const Eigen::Vector2d lo = plan.origin_W.cast<double>() / s;
    const Eigen::Vector2d hi =
        (plan.origin_W.cast<double>() +
         double(plan.resolution_m) * Eigen::Vector2d(plan.width, plan.height)) /
        s;
    for (int iy = int(std::floor(lo.y())); iy <= int(std::floor(hi.y())); ++iy)
      for (int ix = int(std::floor(lo.x())); ix <= int(std::floor(hi.x())); ++ix) {
        const Eigen::Vector2d cell =
            ((Eigen::Vector2d(ix, iy).array() + 0.5) * s - plan.origin_W.cast<double>().array()) /
            double(plan.resolution_m);
        const int cx = int(std::floor(cell.x())), cy = int(std::floor(cell.y()));
        if (plan.Contains(cx, cy) && plan.at(cx, cy) != PlanCell::kOutside)
          columns.emplace_back(ix, iy);
      }
  }
  // Voxel z has its centre at (z + 0.5) s.
  const double floor_z = p.floor.floor_z_m, top_z = floor_z + double(p.floor.band_max_m);
  const int z_begin = int(std::ceil(floor_z / s - 0.5)),
            z_end = int(std::floor(top_z / s - 0.5)) + 1;
  return ColumnRegion(columns, z_begin, z_end);
}

class Explorer {
 public:
  Explorer(const World& world, const FloorPlan& plan, LoadedPlanner& planner,
           const ExploreParams& params, const std::function<double(const TsdfVolume&)>& probe,
           const ExploreProgressFn& progress)
      : world_(world),
        plan_(plan),
        planner_(planner),
        p_(params),
        probe_(probe),
        progress_(progress),
        volume_(std::make_unique<TsdfVolume>(VolumeParams{
            params.voxel_size_m, params.trunc_vox * params.voxel_size_m, params.max_memory_bytes})),
        recon_(params.recon_voxel_size_m > 0.f
                   ? std::make_unique<TsdfVolume>(VolumeParams{
                         params.recon_voxel_size_m, params.trunc_vox * params.recon_voxel_size_m,
                         params.max_memory_bytes})
                   : nullptr),
        map_(*volume_),
        floor_(std::make_unique<FloorMap>(params.voxel_size_m, params.floor)),
        explore_world_(map_, *floor_, ExploreWorldParams{}) {}

  Result<ExploreResult> Run(const std::vector<Eigen::Vector2f>& starts);

 private:
  Status Fuse(RobotRun& r, bool force);
  Status AfterPrimitive(RobotRun& r, double clock_before_s, bool force_fuse = false);
  void Sample(RobotRun& r, RobotStatus status);
  Status Sweep(RobotRun& r);
  Status Advance(RobotRun& r, double t_end_s);
  Status StepToView(RobotRun& r, QueuedTask& q);
  bool RouteTo(RobotRun& r, const QueuedTask& q);
  void Fail(RobotRun& r, const std::string& why);
  // Tracked poses: where frame `frame` of r is fused, or nullopt when the tracker lost it;
  // *odometry: fused at the odometry prior (ExploreParams::odometry_without_model).
  Result<std::optional<Pose3f>> TrackFrame(RobotRun& r, const RenderOutput& frame,
                                           const PinholeCamera& camera, const Pose3f& T_W_C,
                                           float* residual_rms_m, bool* odometry);
  void Bump(RobotRun& r, const Eigen::Vector2f& goal_W);
  // A drive the true floor refused on the way to q: a plugin path is left for the host's route,
  // the host's own route bumps and fails the task.
  void Blocked(RobotRun& r, QueuedTask& q, const Eigen::Vector2f& goal_W, const Status& why);
  Status UpdateFloor();
  std::vector<PlannerRobot> Snapshot() const;
  void CallPlanner(PlanEvent event, int32_t event_robot, const PlannerTask& failed);
  void EndOnFault(const PlannerFault& fault, const std::string& head, PlanCallRecord record);
  void Record(bool with_completeness);
  double DistanceTotal() const;
  CameraAim CameraTarget(const RobotRun& r) const;
  struct ArmAim {
    Eigen::Vector3f offset_B;  // RobotState::camera_offset_B, in the workspace
    std::string clamped;       // why the trajectory's position was moved into it; empty: it was not
  };
  std::optional<ArmAim> ArmTarget(const RobotRun& r, const Eigen::Vector2f& goal_W,
                                  float heading_rad, double path_s) const;
  void CountArmClamps(const RobotRun& r, const ArmAim& aim);

  const World& world_;
  const FloorPlan& plan_;
  LoadedPlanner& planner_;
  ExploreParams p_;
  std::function<double(const TsdfVolume&)> probe_;
  ExploreProgressFn progress_;
  std::unique_ptr<MeshRaycaster> raycaster_;
  std::unique_ptr<TsdfVolume> volume_;
  std::unique_ptr<TsdfVolume> recon_;  // ExploreParams::recon_voxel_size_m > 0
  PlanningMap map_;
  std::unique_ptr<FloorMap> floor_;
  ExploreWorld explore_world_;
  std::optional<ColumnRegion> interior_;  // the unobserved-volume curve's (InteriorRegion)
  std::vector<RobotRun> robots_;
  std::vector<uint8_t> structure_by_id_;  // world instance id -> scene structure (detector)
  std::vector<BlockIndex> touched_;       // since the last floor-map update
  std::vector<Failure> failures_;
  std::vector<size_t> went_idle_;
  ExploreResult result_;
  double t_s_ = 0.0;
  double last_call_s_ = 0.0;
  uint32_t call_index_ = 0;
  int empty_calls_ = 0;  // consecutive calls that left every robot idle without a task
  bool done_ = false;
  double wakeup_t_s_ = std::numeric_limits<double>::quiet_NaN();  // vp.schedule's request
};

// The waypoints left to a robot's front task.
void ClearRoute(RobotRun& r) {
  r.route.clear();
  r.route_speed_mps.clear();
}

void PopWaypoint(RobotRun& r) {
  r.route.pop_front();
  if (!r.route_speed_mps.empty()) r.route_speed_mps.pop_front();
}

Status Explorer::Fuse(RobotRun& r, bool force) {
  const Pose3f T_W_C = r.robot.T_W_C();
  const float capture_hz = r.robot.mode_params().capture_hz;
  if (capture_hz > 0.f) {
    // On the run clock: a frame once a period has passed since the last, whatever moved.
    if (!force && r.t_s + 1e-9 < r.next_capture_s) return Status::Ok();
    r.next_capture_s = r.t_s + 1.0 / double(capture_hz);
  } else if (!r.trigger.ShouldFuse(T_W_C) && !force) {
    return Status::Ok();
  }
  const PinholeCamera camera = r.robot.camera();
  RenderParams rp;
  // Clearing needs the readings beyond the range: the sensor returns them, unlimited here.
  rp.max_range_m = p_.clear_beyond_range ? 0.f : r.robot.mode_params().max_range_m;
  rp.color = p_.fuse_color;
  rp.labels = p_.fuse_labels;
  rp.normals = p_.noise;
  double t0 = NowMs();
  RenderOutput out = raycaster_->Render(camera, T_W_C, rp);
  result_.timings.render_ms += NowMs() - t0;
  if (p_.fuse_labels) {
    t0 = NowMs();
    const DetectorStats detected = ApplyDetector(out.labels, structure_by_id_, p_.detector, p_.seed,
                                                 (uint64_t(r.index) << 32) | r.frames);
    result_.objects_detected += detected.objects_out;
    result_.timings.detect_ms += NowMs() - t0;
  }
  if (p_.noise) {
    t0 = NowMs();
    KinectNoiseParams noise;
    noise.seed = p_.seed;
    // Frames of different robots never share a noise pattern.
    Result<DepthImage> noisy = ApplyKinectNoise(out.depth, out.normals_C, camera, noise,
                                                (uint64_t(r.index) << 32) | r.frames);
    if (!noisy.ok()) return noisy.status();
    out.depth = std::move(noisy).value();
    result_.timings.noise_ms += NowMs() - t0;
  }
  Pose3f T_fuse = T_W_C;
  float residual_rms_m = 0.f;
  bool odometry = false;
  if (p_.poses == ExploreParams::Poses::kTracked) {
    t0 = NowMs();
    Result<std::optional<Pose3f>> tracked =
        TrackFrame(r, out, camera, T_W_C, &residual_rms_m, &odometry);
    result_.timings.track_ms += NowMs() - t0;
    if (!tracked.ok()) return tracked.status();
    if (!tracked->has_value()) {  // lost: not fused (a wrong pose would smear the map)
      ++r.frames;
      ++result_.frames_lost;
      return Status::Ok();
    }
    T_fuse = **tracked;
    if (odometry) ++result_.frames_odometry;
  }
  IntegrateParams ip;
  ip.min_depth_m = r.robot.mode_params().min_range_m;
  ip.max_depth_m = r.robot.mode_params().max_range_m;
  ip.clear_beyond_max_depth = p_.clear_beyond_range;
  ip.integrate_color = p_.fuse_color;
  t0 = NowMs();
  Result<PlanningFrameStats> stats =
      IntegratePlanningFrame(out.depth, out.color, p_.fuse_labels ? &out.labels : nullptr, camera,
                             T_fuse, ip, *volume_, map_);
  if (!stats.ok()) return stats.status();
  result_.blocks_dropped += stats->integrate.blocks_refused;
  if (recon_) {  // the same frame into the finer volume, for the mesh alone
    IntegrateParams fine_ip = ip;
    fine_ip.weighting = p_.recon_weighting;
    Result<IntegrateStats> fine =
        IntegrateFrame(out.depth, out.color, camera, T_fuse, fine_ip, *recon_);
    if (!fine.ok()) return fine.status();
    result_.blocks_dropped += fine->blocks_refused;
  }
  result_.timings.fuse_ms += NowMs() - t0;
  touched_.insert(touched_.end(), stats->integrate.touched_blocks.begin(),
                  stats->integrate.touched_blocks.end());
  ++r.frames;
  ++result_.frames_fused;
  result_.frames[r.index].push_back({r.t_s, T_W_C, T_fuse, residual_rms_m, odometry});
  return Status::Ok();
}

Result<std::optional<Pose3f>> Explorer::TrackFrame(RobotRun& r, const RenderOutput& frame,
                                                   const PinholeCamera& camera, const Pose3f& T_W_C,
                                                   float* residual_rms_m, bool* odometry) {
  if (!r.tracking_started) {  // the start sweep anchors the map where the robot truly is
    r.last_true_T_W_C = r.last_fused_T_W_C = T_W_C;
    return std::optional<Pose3f>(T_W_C);
  }
  const int mode = int(r.robot.mode());
  auto it = r.trackers.find(mode);
  if (it == r.trackers.end()) {
    try {
      it = r.trackers.emplace(mode, std::make_shared<FrameTracker>(camera, p_.tracking)).first;
    } catch (const std::invalid_argument& e) {
      return InvalidArgument(std::string("tracked poses: ") + e.what());
    }
  }
  // The odometry's motion since the last frame, noisy, from where that frame was fused.
  const Pose3f delta = r.last_true_T_W_C.inverse() * T_W_C;
  const Pose3f prior =
      r.last_fused_T_W_C *
      NoisyOdometry(delta, p_.odometry, p_.seed, (uint64_t(r.index) << 32) | uint64_t(r.frames));
  // Against the planning map, also beside a finer volume: at 320 x 240 a 2 cm volume is too
  // sparse a model (a fifth of the pixels associate; every frame after the sweep was lost).
  Result<TrackingResult> t = it->second->Track(frame.depth, frame.color, *volume_, prior);
  if (!t.ok()) return t.status();
  r.last_true_T_W_C = T_W_C;
  *residual_rms_m = t->residual_rms_m;
  if (!t->ok && t->no_model && p_.odometry_without_model) {
    // Nothing in view to register against (the camera looks into space the map does not hold
    // yet): the odometry is the best pose there is, and skipping the frame would keep the map
    // from ever growing there, so every later frame would see no model either.
    *odometry = true;
    r.last_fused_T_W_C = prior;
    it->second->Accept(prior);
    return std::optional<Pose3f>(prior);
  }
  if (!t->ok) {  // dead reckoning carries on from the prior
    r.last_fused_T_W_C = prior;
    return std::optional<Pose3f>();
  }
  r.last_fused_T_W_C = t->T_W_C;
  it->second->Accept(t->T_W_C);
  return std::optional<Pose3f>(t->T_W_C);
}

void Explorer::Sample(RobotRun& r, RobotStatus status) {
  const RobotState& s = r.robot.state();
  RobotSample sample;
  sample.t_s = r.t_s;
  sample.x_m = s.position_W.x();
  sample.y_m = s.position_W.y();
  sample.yaw_rad = s.heading_rad;
  sample.cam_yaw_rad = s.camera_yaw_rad;
  sample.cam_pitch_rad = s.camera_pitch_rad;
  sample.status = status;
  sample.mode = RobotModeName(r.robot.mode());
  std::vector<RobotSample>& samples = r.track.samples;
  if (!samples.empty() && samples.back().t_s >= sample.t_s) {
    samples.back() = sample;  // a step that took no time: the newer state wins
  } else {
    samples.push_back(sample);
  }
}

Status Explorer::AfterPrimitive(RobotRun& r, double clock_before_s, bool force_fuse) {
  r.t_s += r.robot.clock_s() - clock_before_s;
  Sample(r, RobotStatus::kBusy);
  explore_world_.MarkFootprint(r.robot.state().position_W, r.robot.params().radius_m);
  return Fuse(r, force_fuse);
}

Status Explorer::Sweep(RobotRun& r) {
  const int steps = std::max(1, int(std::lround(360.f / p_.sweep_step_deg)));
  for (float pitch_deg : p_.sweep_pitches_deg) {
    double c = r.robot.clock_s();
    VOXPLAN_RETURN_IF_ERROR(r.robot.SetCameraPitch(Deg2Rad(pitch_deg)));
    VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c, /*force_fuse=*/true));
    const float yaw0 = r.robot.state().camera_yaw_rad;
    for (int k = 1; k < steps; ++k) {  // the ring's last direction is its first
      c = r.robot.clock_s();
      r.robot.SetCameraYaw(yaw0 + 2.f * kPi * float(k) / float(steps));
      VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c, /*force_fuse=*/true));  // every direction
    }
    r.robot.WrapCameraYaw();
  }
  const double c = r.robot.clock_s();
  VOXPLAN_RETURN_IF_ERROR(r.robot.SetCameraPitch(0.f));
  return AfterPrimitive(r, c);
}

void Explorer::Fail(RobotRun& r, const std::string& why) {
  failures_.push_back({r.index, r.queue.front().task});
  result_.plan_log.push_back("t=" + Fmt(r.t_s) + " robot " + std::to_string(r.index) +
                             " task failed: " + why);
  ++result_.failed_tasks;
  r.queue.pop_front();
  r.routed = false;
  ClearRoute(r);
}

// The bumper: what a refused drive on the host's route ran into goes on the floor map as
// obstacle (FloorMap::MarkContacts), so the host's routes and the planner's raster avoid it.
// Without it a robot whose camera never sees the obstacle (too low, or too close) is routed into
// it again and again.
void Explorer::Bump(RobotRun& r, const Eigen::Vector2f& goal_W) {
  const Robot& robot = r.robot;
  const std::vector<Eigen::Vector2f> marked = floor_->MarkContacts(
      FirstContact(robot.plan(), robot.state().position_W, goal_W, robot.params().radius_m));
  if (marked.empty()) return;
  result_.plan_log.push_back("t=" + Fmt(r.t_s) + " robot " + std::to_string(r.index) +
                             " bumped into " + std::to_string(marked.size()) +
                             " floor cells near (" + Fmt(marked.front().x()) + ", " +
                             Fmt(marked.front().y()) + "): marked as obstacles");
}

// Straight shortcuts over the known raster: from each kept point, the farthest later point in
// line of sight over cells traversable with the clearance.
std::vector<Eigen::Vector2f> Shortcut(const std::vector<Eigen::Vector2f>& path,
                                      const PlannerFloor& floor, float clearance_m) {
  if (path.size() <= 2) return path;
  auto clear = [&](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    const int n = std::max(1, int(std::ceil((b - a).norm() / (0.5f * floor.cell_size_m))));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2i c = floor.CellOf(a + (b - a) * (float(i) / float(n)));
      if (!floor.Traversable(c.x(), c.y(), clearance_m)) return false;
    }
    return true;
  };
  std::vector<Eigen::Vector2f> out = {path.front()};
  size_t i = 0;
  while (i + 1 < path.size()) {
    size_t j = i + 1;
    // The inner points are cell centres; the ends may lie on untraversable cells (a robot on
    // cells it never saw), so they only connect to their neighbours.
    if (i > 0) {
      for (size_t k = path.size() - 2; k > i + 1; --k) {
        if (clear(path[i], path[k])) {
          j = k;
          break;
        }
      }
    }
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

bool Explorer::RouteTo(RobotRun& r, const QueuedTask& q) {
  const Eigen::Vector2f from = r.robot.state().position_W;
  const Eigen::Vector2f to = q.task.position_m;
  ClearRoute(r);
  if (!q.path.empty()) {
    r.route.assign(q.path.begin(), q.path.end());
    r.route_speed_mps.assign(q.speeds_mps.begin(), q.speeds_mps.end());
    if ((r.route.back() - to).norm() > 1e-4f) {
      r.route.push_back(to);
      if (!r.route_speed_mps.empty()) r.route_speed_mps.push_back(r.route_speed_mps.back());
    }
    return true;
  }
  explore_world_.Refresh();
  const float radius = r.robot.params().radius_m;
  for (float clearance : {radius + p_.route_margin_m, radius}) {
    Result<std::vector<Eigen::Vector2f>> path = explore_world_.ShortestPath(from, to, clearance);
    if (!path.ok()) continue;
    const std::vector<Eigen::Vector2f> shortcut =
        Shortcut(*path, explore_world_.Floor(), clearance);
    r.route.assign(shortcut.begin() + 1, shortcut.end());
    return true;
  }
  return false;
}

// The plugin's camera trajectory t seconds after it was given: world yaw (turning the short way)
// and pitch, linear between samples, held before the first and after the last.
std::pair<float, float> TrajectoryYawPitch(const std::vector<CameraSample>& tr, float t) {
  if (t <= tr.front().t_s) return {tr.front().yaw_rad, tr.front().pitch_rad};
  for (size_t i = 1; i < tr.size(); ++i) {
    if (t > tr[i].t_s) continue;
    const float span = tr[i].t_s - tr[i - 1].t_s;
    const float a = span > 0.f ? (t - tr[i - 1].t_s) / span : 1.f;
    return {tr[i - 1].yaw_rad + a * WrapAngle(tr[i].yaw_rad - tr[i - 1].yaw_rad),
            tr[i - 1].pitch_rad + a * (tr[i].pitch_rad - tr[i - 1].pitch_rad)};
  }
  return {tr.back().yaw_rad, tr.back().pitch_rad};
}

// The trajectory's camera position t seconds after it was given, keyed and interpolated as
// TrajectoryYawPitch; nullopt where a sample it reads has none (NaN).
std::optional<Eigen::Vector3f> TrajectoryPosition(const std::vector<CameraSample>& tr, float t) {
  const auto known = [](const CameraSample& s) -> std::optional<Eigen::Vector3f> {
    if (!s.position_m.allFinite()) return std::nullopt;
    return s.position_m;
  };
  if (t <= tr.front().t_s) return known(tr.front());
  for (size_t i = 1; i < tr.size(); ++i) {
    if (t > tr[i].t_s) continue;
    if (!known(tr[i - 1]) || !known(tr[i])) return std::nullopt;
    const float span = tr[i].t_s - tr[i - 1].t_s;
    const float a = span > 0.f ? (t - tr[i - 1].t_s) / span : 1.f;
    return Eigen::Vector3f(tr[i - 1].position_m + a * (tr[i].position_m - tr[i - 1].position_m));
  }
  return known(tr.back());
}

// The camera yaw (relative to the base) and pitch that aim from the robot's camera at a point.
CameraAim AimAt(const Robot& robot, const Eigen::Vector3f& target_W) {
  const Eigen::Vector3f d = target_W - robot.T_W_C().translation();
  const float limit = robot.max_abs_pitch_rad();
  const float pitch = d.head<2>().norm() > 1e-6f || std::abs(d.z()) > 1e-6f
                          ? std::atan2(d.z(), d.head<2>().norm())
                          : 0.f;
  const float yaw_W = d.head<2>().norm() > 1e-6f
                          ? std::atan2(d.y(), d.x())
                          : robot.state().heading_rad + robot.state().camera_yaw_rad;
  return {WrapAngle(yaw_W - robot.state().heading_rad), std::clamp(pitch, -limit, limit)};
}

CameraAim Explorer::CameraTarget(const RobotRun& r) const {
  // A task that looks at a point aims there on the way (vp.task's look_at).
  if (r.camera_trajectory.empty() && !r.queue.empty() && r.queue.front().task.camera.look_at)
    return AimAt(r.robot, r.queue.front().task.camera.look_at_W);
  // Along the motion and level unless the plugin said otherwise (a view may have tilted it).
  if (r.camera_trajectory.empty()) return {0.f, 0.f};
  const auto [world_yaw, pitch] =
      TrajectoryYawPitch(r.camera_trajectory, float(r.t_s - r.trajectory_t0_s));
  const float max_pitch = r.robot.max_abs_pitch_rad();
  return {WrapAngle(world_yaw - r.robot.state().heading_rad),
          std::clamp(pitch, -max_pitch, max_pitch)};
}

// On an arm mount, where the camera trajectory puts the camera as a piece of continuous motion
// ends: its position at `path_s`, the path's time at its speeds up to the piece's end, in the base
// frame of the pose the piece ends at, moved into the workspace. The samples' t_s is time along
// the path at its speeds, so this keys the positions by arc length along the base path (Xu
// 2017's camera path): a base held up by its turns or camera joints (the first piece turning the
// camera round from the start sweep) does not leave the camera running ahead. Yaw and pitch keep
// the run clock at the piece's start, as they always did. nullopt on a head, without a trajectory
// or where it gives no position.
std::optional<Explorer::ArmAim> Explorer::ArmTarget(const RobotRun& r,
                                                    const Eigen::Vector2f& goal_W,
                                                    float heading_rad, double path_s) const {
  const ModeParams& m = r.robot.mode_params();
  if (m.mount != MountKind::kArm || r.camera_trajectory.empty()) return std::nullopt;
  const std::optional<Eigen::Vector3f> p_W = TrajectoryPosition(r.camera_trajectory, float(path_s));
  if (!p_W) return std::nullopt;
  const Eigen::Vector2f d = p_W->head<2>() - goal_W;
  const float c = std::cos(heading_rad), sn = std::sin(heading_rad);
  Eigen::Vector2f offset(c * d.x() + sn * d.y(), -sn * d.x() + c * d.y());
  float height = p_W->z();  // above the robots' floor, z = 0 (CameraPoseFromState)
  ArmAim aim;
  aim.clamped = ArmWorkspaceProblem(m.arm, height, offset);
  ClampToArmWorkspace(m.arm, &height, &offset);
  aim.offset_B = ArmOffset(height, offset, r.robot.params().camera_height_m);
  return aim;
}

// After a piece driven towards `aim`: the clampings counted, the first of each kind logged.
void Explorer::CountArmClamps(const RobotRun& r, const ArmAim& aim) {
  const std::string head = "t=" + Fmt(r.t_s) + " robot " + std::to_string(r.index) + " ";
  if (!aim.clamped.empty() && result_.camera_position_clamped_workspace++ == 0)
    result_.plan_log.push_back(
        head + "camera trajectory position moved into the arm's workspace (" + aim.clamped +
        "); later ones are counted in camera_position_clamped_workspace");
  const Eigen::Vector3f left = aim.offset_B - r.robot.state().camera_offset_B;
  if (!left.isZero(0.f) && result_.camera_position_clamped_speed++ == 0)
    result_.plan_log.push_back(
        head + "arm camera held back by the arm's speed (" +
        Fmt(r.robot.mode_params().arm.speed_mps) + " m/s), " + Fmt(left.norm(), 3) +
        " m short of the trajectory; later ones are counted in camera_position_clamped_speed");
}

// One primitive at the view: turn the base, move the arm camera (vp.task), turn the camera
// (at the look-at point, or to the task's angles), then dwell and capture, then the pitch sweep.
Status Explorer::StepToView(RobotRun& r, QueuedTask& q) {
  const double c = r.robot.clock_s();
  const RobotState& s = r.robot.state();
  const TaskCamera& cam = q.task.camera;
  const float turn_step = Deg2Rad(p_.turn_step_deg);
  const float dh = WrapAngle(q.task.theta_rad - s.heading_rad);
  if (std::abs(dh) > 1e-3f) {
    r.robot.TurnTo(s.heading_rad + Clamp(dh, turn_step));
    return AfterPrimitive(r, c);
  }
  if (cam.ArmSet() && !q.dwelt) {
    const ModeParams& m = r.robot.mode_params();
    const float head_h = r.robot.params().camera_height_m;
    const float h =
        cam.HeightSet() ? cam.height_m : std::clamp(head_h, m.arm.height_min_m, m.arm.height_max_m);
    const Eigen::Vector2f o =
        cam.OffsetSet() ? cam.offset_m : Eigen::Vector2f(m.arm.reach_min_m, 0.f);
    if ((ArmOffset(h, o, head_h) - s.camera_offset_B).norm() > 1e-4f) {
      VOXPLAN_RETURN_IF_ERROR(r.robot.SetArmCamera(h, o));
      return AfterPrimitive(r, c);
    }
  }
  if (!q.dwelt) {
    const CameraAim aim = cam.look_at ? AimAt(r.robot, cam.look_at_W)
                                      : CameraAim{q.task.camera_yaw_rad, q.task.camera_pitch_rad};
    const float dy = WrapAngle(aim.yaw_rad - s.camera_yaw_rad);
    if (std::abs(dy) > 1e-3f) {
      r.robot.SetCameraYaw(s.camera_yaw_rad + Clamp(dy, turn_step));
      return AfterPrimitive(r, c);
    }
    const float max_pitch = r.robot.max_abs_pitch_rad();
    const float pitch = std::clamp(aim.pitch_rad, -max_pitch, max_pitch);
    if (std::abs(pitch - s.camera_pitch_rad) > 1e-3f) {
      VOXPLAN_RETURN_IF_ERROR(r.robot.SetCameraPitch(pitch));
      return AfterPrimitive(r, c);
    }
    r.robot.WrapCameraYaw();
    // Dwell at the view: the task's time, at least the robot's capture time. With time-based
    // capture the dwell yields floor(dwell x rate) frames (at least one), spread over it.
    const double dwell_s = std::max(double(q.task.dwell_s), double(r.robot.params().dwell_s));
    const float capture_hz = r.robot.mode_params().capture_hz;
    const int frames = capture_hz > 0.f ? std::max(1, int(std::floor(dwell_s * capture_hz))) : 1;
    for (int k = 0; k < frames; ++k) {
      r.t_s += dwell_s / frames;
      Sample(r, RobotStatus::kBusy);
      VOXPLAN_RETURN_IF_ERROR(Fuse(r, true));
    }
    q.dwelt = true;
  }
  if (cam.Sweeps()) {  // the head's tilt up and down at the view (Guo 2022), a frame per step
    const int steps = int(std::floor(
        (cam.sweep_pitch_max_rad - cam.sweep_pitch_min_rad) / cam.sweep_pitch_step_rad + 1e-4f));
    if (q.sweep_steps_done <= steps) {
      const float limit = r.robot.max_abs_pitch_rad();
      const float pitch =
          std::clamp(cam.sweep_pitch_min_rad + float(q.sweep_steps_done) * cam.sweep_pitch_step_rad,
                     -limit, limit);
      ++q.sweep_steps_done;
      VOXPLAN_RETURN_IF_ERROR(r.robot.SetCameraPitch(pitch));
      return AfterPrimitive(r, c, /*force_fuse=*/true);
    }
  }
  if (q.task.tag != kPathOnlyTag) r.views.push_back(q.task);
  r.queue.pop_front();
  r.routed = false;
  ClearRoute(r);
  return Status::Ok();
}

Status Explorer::Advance(RobotRun& r, double t_end_s) {
  const float turn_step = Deg2Rad(p_.turn_step_deg);
  while (r.t_s < t_end_s) {
    if (r.queue.empty()) {
      if (!r.idle) {
        r.idle = true;
        Sample(r, RobotStatus::kIdle);
        went_idle_.push_back(r.index);
      }
      r.idle_s += t_end_s - r.t_s;
      r.t_s = t_end_s;
      break;
    }
    if (r.idle) {
      r.idle = false;
      Sample(r, RobotStatus::kBusy);
    }
    QueuedTask& q = r.queue.front();
    if (!r.routed) {
      const double c = r.robot.clock_s();
      r.robot.SetMode(q.task.mode == 1 ? RobotMode::kReconstructor : RobotMode::kExplorer);
      if (r.robot.clock_s() != c) {  // the switch took time (ModeParams::switch_s)
        VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
        continue;
      }
      if (!RouteTo(r, q)) {
        Fail(r, "no route over the known floor map to (" + Fmt(q.task.position_m.x()) + ", " +
                    Fmt(q.task.position_m.y()) + ")");
        continue;
      }
      r.routed = true;
    }
    if (r.route.empty()) {
      if (q.continuous) {  // the end of a continuous path: no turn, dwell or stop there
        r.queue.pop_front();
        r.routed = false;
        continue;
      }
      VOXPLAN_RETURN_IF_ERROR(StepToView(r, q));
      continue;
    }
    const double c = r.robot.clock_s();
    const RobotState& s = r.robot.state();
    const Eigen::Vector2f delta = r.route.front() - s.position_W;
    const float dist = delta.norm();
    if (dist < 1e-3f) {
      PopWaypoint(r);
      continue;
    }
    const float dh = WrapAngle(std::atan2(delta.y(), delta.x()) - s.heading_rad);
    // The next straight piece towards the waypoint, at most a drive step.
    const float piece = std::min(dist, p_.drive_step_m);
    const Eigen::Vector2f goal =
        piece < dist ? Eigen::Vector2f(s.position_W + delta * (piece / dist)) : r.route.front();
    // Continuous motion turns while it drives, the camera moving with it; a piece that would
    // drive backwards (more than a right angle off) turns in place first.
    if (q.continuous && std::abs(dh) <= 0.5f * kPi) {
      const CameraAim aim = CameraTarget(r);
      const float max_pitch = r.robot.max_abs_pitch_rad();
      const float speed = r.route_speed_mps.empty() ? r.robot.mode_params().max_speed_mps
                                                    : r.route_speed_mps.front();
      const double piece_s = double(piece) / std::min(speed, r.robot.mode_params().max_speed_mps);
      const std::optional<ArmAim> arm = ArmTarget(r, goal, s.heading_rad + dh, r.path_s + piece_s);
      if (Status st = r.robot.DriveAlong(
              goal, speed, s.camera_yaw_rad + WrapAngle(aim.yaw_rad - s.camera_yaw_rad),
              std::clamp(aim.pitch_rad, -max_pitch, max_pitch),
              arm ? std::optional<Eigen::Vector3f>(arm->offset_B) : std::nullopt);
          !st.ok()) {
        Blocked(r, q, goal, st);
        continue;
      }
      if (arm) CountArmClamps(r, *arm);
      r.path_s += piece_s;
      if (piece >= dist) PopWaypoint(r);
      VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
      continue;
    }
    if (std::abs(dh) > 1e-3f) {
      r.robot.TurnTo(s.heading_rad + Clamp(dh, turn_step));
      VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
      continue;
    }
    const CameraAim aim = CameraTarget(r);
    const float dy = WrapAngle(aim.yaw_rad - s.camera_yaw_rad);
    if (std::abs(dy) > Deg2Rad(2.f)) {
      r.robot.SetCameraYaw(s.camera_yaw_rad + Clamp(dy, turn_step));
      VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
      continue;
    }
    if (std::abs(aim.pitch_rad - s.camera_pitch_rad) > 1e-3f) {
      VOXPLAN_RETURN_IF_ERROR(r.robot.SetCameraPitch(aim.pitch_rad));
      VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
      continue;
    }
    if (Status st = r.robot.DriveTo(goal); !st.ok()) {
      Blocked(r, q, goal, st);
      continue;
    }
    if (piece >= dist) PopWaypoint(r);
    VOXPLAN_RETURN_IF_ERROR(AfterPrimitive(r, c));
  }
  return Status::Ok();
}

void Explorer::Blocked(RobotRun& r, QueuedTask& q, const Eigen::Vector2f& goal_W,
                       const Status& why) {
  ++result_.blocked_paths;
  if (!q.path.empty()) {
    // The plugin's path runs closer to obstacles than the true floor allows: route this task on
    // the known map (with its margin) instead, once.
    result_.plan_log.push_back("t=" + Fmt(r.t_s) + " robot " + std::to_string(r.index) +
                               " leaves the planner's path: " + why.message());
    q.path.clear();
    q.speeds_mps.clear();
    r.routed = false;
    return;
  }
  // The host's own route, over the known map with its margin, ran into something the map lacks.
  // (A plugin path that grazes a known wall, as above, teaches nothing: the grids of the map and
  // the true plan are offset, and marking there narrows doorways.)
  Bump(r, goal_W);
  Fail(r, why.message());
}

Status Explorer::UpdateFloor() {
  if (touched_.empty()) return Status::Ok();
  const double t0 = NowMs();
  std::sort(touched_.begin(), touched_.end());
  touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
  Status s = floor_->Update(*volume_, touched_);
  touched_.clear();
  result_.timings.floor_ms += NowMs() - t0;
  return s;
}

std::vector<PlannerRobot> Explorer::Snapshot() const {
  std::vector<PlannerRobot> out;
  for (const RobotRun& r : robots_) {
    const RobotParams& rp = r.robot.params();
    const RobotState& s = r.robot.state();
    PlannerRobot pr;
    pr.id = uint32_t(r.index);
    pr.position_m = s.position_W;
    pr.theta_rad = s.heading_rad;
    pr.camera_yaw_rad = s.camera_yaw_rad;
    pr.camera_pitch_rad = s.camera_pitch_rad;
    pr.mode = r.robot.mode() == RobotMode::kReconstructor ? 1 : 0;
    pr.executing = !r.queue.empty();
    for (const QueuedTask& q : r.queue) pr.queue.push_back(q.task);
    pr.radius_m = rp.radius_m;
    pr.camera_height_m = rp.camera_height_m;
    pr.max_pitch_rad = Deg2Rad(rp.max_abs_pitch_deg);
    pr.min_pitch_rad = -pr.max_pitch_rad;
    pr.camera_yaw_rate_radps = rp.camera_yaw_rate_radps;
    pr.camera_pitch_rate_radps = rp.camera_pitch_rate_radps;
    pr.distance_m = float(r.robot.distance_m());
    pr.idle_s = float(r.idle_s);
    pr.busy_s = float(r.t_s - r.idle_s);
    for (RobotMode m : {RobotMode::kExplorer, RobotMode::kReconstructor}) {
      const ModeParams& mp = rp.mode(m);
      const PinholeCamera cam =
          CameraWithFov(rp.image_width, rp.image_height, mp.horizontal_fov_deg);
      ScanMode sm;
      sm.max_speed_mps = mp.max_speed_mps;
      sm.max_turn_rate_radps = mp.max_turn_rate_radps;
      sm.horizontal_fov_rad = Deg2Rad(mp.horizontal_fov_deg);
      sm.vertical_fov_rad = 2.f * std::atan(0.5f * float(cam.height) / cam.fy);
      sm.min_range_m = mp.min_range_m;
      sm.max_range_m = mp.max_range_m;
      sm.image_width = cam.width;
      sm.image_height = cam.height;
      sm.fx = cam.fx;
      sm.fy = cam.fy;
      sm.cx = cam.cx;
      sm.cy = cam.cy;
      sm.capture_hz = mp.capture_hz;
      sm.switch_s = mp.switch_s;
      sm.camera_turn_rate_radps = std::min(rp.camera_yaw_rate_radps, rp.camera_pitch_rate_radps);
      if (mp.mount == MountKind::kArm) {
        sm.mount = CameraMount::kArm;
        sm.camera_height_min_m = mp.arm.height_min_m;
        sm.camera_height_max_m = mp.arm.height_max_m;
        sm.reach_min_m = mp.arm.reach_min_m;
        sm.reach_max_m = mp.arm.reach_max_m;
        sm.reach_half_angle_rad = Deg2Rad(mp.arm.reach_half_angle_deg);
        sm.max_pitch_rad = Deg2Rad(mp.arm.max_abs_pitch_deg);
        sm.min_pitch_rad = -sm.max_pitch_rad;
        sm.camera_speed_mps = mp.arm.speed_mps;
      } else {
        sm.mount = CameraMount::kHead;
        sm.camera_height_min_m = sm.camera_height_max_m = rp.camera_height_m;
        sm.min_pitch_rad = pr.min_pitch_rad;
        sm.max_pitch_rad = pr.max_pitch_rad;
      }
      pr.modes.push_back(sm);
    }
    out.push_back(std::move(pr));
  }
  return out;
}

// Splits a plugin's dense path among its tasks: task k's piece ends at the path point nearest
// it (searching forward from the previous task's); a task farther than max_gap_m from the path
// and those after it get no piece (the host routes them).
std::vector<std::vector<Eigen::Vector2f>> SplitPath(const std::vector<PathPoint>& path,
                                                    const std::vector<PlannerTask>& tasks,
                                                    float max_gap_m = 0.5f,
                                                    float min_step_m = 0.1f) {
  std::vector<std::vector<Eigen::Vector2f>> pieces(tasks.size());
  size_t start = 0;
  for (size_t k = 0; k < tasks.size() && start < path.size(); ++k) {
    size_t best = start;
    float best_d = std::numeric_limits<float>::infinity();
    for (size_t j = start; j < path.size(); ++j) {
      const float d = (path[j].position_m - tasks[k].position_m).norm();
      if (d < best_d) {
        best_d = d;
        best = j;
      }
    }
    if (best_d > max_gap_m) break;
    // Points closer than a drive step add turns and samples, not shape.
    for (size_t j = start; j <= best; ++j) {
      const Eigen::Vector2f& p = path[j].position_m;
      if (j == best || pieces[k].empty() || (p - pieces[k].back()).norm() >= min_step_m)
        pieces[k].push_back(p);
    }
    start = best;
  }
  return pieces;
}

// A continuous path's waypoints and speeds: points closer than min_step_m to the last kept one
// dropped as SplitPath does, the speed of a kept point that of the piece ending there.
void ContinuousPiece(const RobotPlan& rp, QueuedTask* q, float min_step_m = 0.1f) {
  for (size_t j = 0; j < rp.path.size(); ++j) {
    const Eigen::Vector2f& p = rp.path[j].position_m;
    if (j + 1 < rp.path.size() && !q->path.empty() && (p - q->path.back()).norm() < min_step_m)
      continue;
    q->path.push_back(p);
    if (!rp.path_speed_mps.empty()) q->speeds_mps.push_back(rp.path_speed_mps[j]);
  }
}

void Explorer::CallPlanner(PlanEvent event, int32_t event_robot, const PlannerTask& failed) {
  explore_world_.Refresh();
  explore_world_.SetRobots(Snapshot());
  PlanRequest request;
  request.event = event;
  request.event_robot = event_robot;
  request.call_index = call_index_++;
  request.seed = p_.seed;
  request.time_budget_s = p_.plan_time_budget_s;
  request.sim_time_s = t_s_;
  request.failed_task = failed;
  last_call_s_ = t_s_;
  PlanCallRecord record;
  record.call_index = request.call_index;
  record.t_s = t_s_;
  record.event = event;
  record.event_robot = event_robot;
  const double t0 = NowMs();
  Result<PlanResult> plan = planner_.Plan(explore_world_, request);
  result_.timings.plan_ms += NowMs() - t0;
  const std::string head = "t=" + Fmt(t_s_) + " call " + std::to_string(request.call_index) + " (" +
                           PlanEventName(event) +
                           (event_robot >= 0 ? " robot " + std::to_string(event_robot) : "") +
                           "): ";
  if (!plan.ok() && planner_.fault() != nullptr) {
    EndOnFault(*planner_.fault(), head, record);
    return;
  }
  if (!plan.ok()) {
    // Not "no task": the robots keep their queues and the next event or interval asks again.
    result_.plan_log.push_back(head + "plan failed: " + plan.status().message());
    record.tasks_per_robot.assign(robots_.size(), 0);
    result_.plan_calls.push_back(record);
    ++result_.failed_plans;
    return;
  } else {
    for (const PlanLogEntry& e : plan->log) result_.plan_log.push_back(head + e.message);
    if (p_.keep_planner_drawings) {
      std::map<std::string, std::vector<DebugDrawing>> sent;
      for (const DebugDrawing& d : plan->drawings) sent[d.layer].push_back(d);
      for (auto& [layer, drawings] : sent) result_.planner_drawings[layer] = std::move(drawings);
    }
    record.rejections = plan->rejections.size();
    record.done = plan->done;
    record.elapsed_ms = plan->elapsed_ms;
    record.over_budget = plan->over_budget;
    record.diagnostics = plan->diagnostics;
    result_.rejected_tasks += plan->rejections.size();
    result_.over_budget_calls += plan->over_budget ? 1 : 0;
    for (size_t i = 0; i < robots_.size() && i < plan->robots.size(); ++i) {
      RobotRun& r = robots_[i];
      RobotPlan& rp = plan->robots[i];
      record.tasks_per_robot.push_back(rp.tasks.size());
      std::vector<PlannerTask> tasks = rp.tasks;
      if (tasks.empty() && !rp.path.empty()) {  // a path to follow on its own
        PlannerTask t;
        t.position_m = rp.path.back().position_m;
        t.theta_rad = rp.path.back().theta_rad;
        t.tag = kPathOnlyTag;
        tasks.push_back(t);
      }
      const bool replace = rp.policy == TaskPolicy::kReplace;
      if (replace) {
        r.queue.clear();
        r.routed = false;
        ClearRoute(r);
      }
      // A dense path starts at the robot, so it only applies to tasks it will drive next.
      std::vector<std::vector<Eigen::Vector2f>> pieces(tasks.size());
      if (!rp.path.empty() && r.queue.empty()) pieces = SplitPath(rp.path, tasks);
      if (!rp.camera_trajectory.empty() || replace) {
        r.camera_trajectory = rp.camera_trajectory;
        r.trajectory_t0_s = r.t_s;
        r.path_s = 0.0;
      }
      if (rp.path_continuous && rp.tasks.empty() && r.queue.empty()) {
        QueuedTask q{tasks.front(), {}};
        q.continuous = true;
        ContinuousPiece(rp, &q);
        r.queue.push_back(std::move(q));
        continue;
      }
      for (size_t k = 0; k < tasks.size(); ++k) r.queue.push_back({tasks[k], pieces[k]});
    }
    if (!std::isnan(plan->wakeup_t_s)) {
      constexpr double kMaxWakeupAhead_s = 600.0;
      if (plan->wakeup_t_s > t_s_ && plan->wakeup_t_s <= t_s_ + kMaxWakeupAhead_s) {
        wakeup_t_s_ = plan->wakeup_t_s;
      } else {
        result_.plan_log.push_back(head + "request_call refused: t=" + Fmt(plan->wakeup_t_s) +
                                   " is not in (now, now + 600 s]");
      }
    }
    result_.plan_calls.push_back(record);
    if (plan->done) {
      done_ = true;
      result_.done_reason = "planner";
      return;
    }
  }
  const bool all_idle = std::all_of(robots_.begin(), robots_.end(),
                                    [](const RobotRun& r) { return r.queue.empty(); });
  empty_calls_ = all_idle ? empty_calls_ + 1 : 0;
  if (empty_calls_ >= 2) {
    done_ = true;
    result_.done_reason = "no_tasks";
    result_.plan_log.push_back(head +
                               "no task for any robot while all are idle, twice: counted as done");
  }
}

// The planner crashed or hung: it is never called again, so the run ends with what it has.
void Explorer::EndOnFault(const PlannerFault& fault, const std::string& head,
                          PlanCallRecord record) {
  record.tasks_per_robot.assign(robots_.size(), 0);
  record.elapsed_ms = fault.elapsed_s * 1e3;
  result_.plan_calls.push_back(record);
  result_.plan_log.push_back(head + fault.Describe(planner_.name()) + "; the run ends here");
  result_.planner_fault = fault;
  done_ = true;
}

double Explorer::DistanceTotal() const {
  double d = 0.0;
  for (const RobotRun& r : robots_) d += r.robot.distance_m();
  return d;
}

void Explorer::Record(bool with_completeness) {
  const double t0 = NowMs();
  RunTimePoint point;
  point.t_s = t_s_;
  point.distance_total_m = DistanceTotal();
  for (const RobotRun& r : robots_) point.busy_robots += r.queue.empty() ? 0 : 1;
  if (floor_->width() > 0) {
    Result<double> coverage = FloorCoverage(plan_, ObservedFromFloor(*floor_));
    if (coverage.ok()) point.coverage = *coverage;
  }
  if (with_completeness && probe_) point.completeness = probe_(*volume_);
  const double voxel_m3 = std::pow(double(p_.voxel_size_m), 3);
  point.unobserved_m3 = double(interior_->CountUnobserved(map_)) * voxel_m3;
  point.mean_uncertainty = MeanSurfaceUncertainty(map_);
  result_.series.push_back(point);
  result_.timings.series_ms += NowMs() - t0;
}

Result<ExploreResult> Explorer::Run(const std::vector<Eigen::Vector2f>& starts) {
  const double run_t0 = NowMs();
  VOXPLAN_RETURN_IF_ERROR(p_.Validate());
  VOXPLAN_RETURN_IF_ERROR(CheckStarts(plan_, starts, p_.robot.radius_m));
  interior_.emplace(InteriorRegion(plan_, p_));
  Result<std::unique_ptr<MeshRaycaster>> raycaster = MeshRaycaster::Create(world_);
  if (!raycaster.ok()) return raycaster.status();
  raycaster_ = std::move(raycaster).value();
  // The oracle classifier: every world instance carries its class name (shown once it is in the
  // map); structure ids are kept from the detector's noise.
  for (const Instance& instance : world_.instances) {
    map_.SetInstanceClass(instance.id, instance.class_name);
    if (structure_by_id_.size() <= instance.id) structure_by_id_.resize(instance.id + 1, 0);
    structure_by_id_[instance.id] = IsStructureClass(instance.class_name);
  }
  RobotParams rp = p_.robot;
  rp.image_width = p_.image_width;
  rp.image_height = p_.image_height;
  for (size_t i = 0; i < starts.size(); ++i) {
    RobotState state;
    state.position_W = starts[i];
    Result<Robot> robot = Robot::Create(rp, plan_, state);
    if (!robot.ok()) return robot.status();
    RobotRun r(i, std::move(robot).value(), p_.trigger);
    r.track.robot = "r" + std::to_string(i);
    robots_.push_back(std::move(r));
    result_.frames.emplace_back();
  }
  for (RobotRun& r : robots_) {
    Sample(r, RobotStatus::kBusy);
    VOXPLAN_RETURN_IF_ERROR(Sweep(r));
    r.tracking_started = true;  // the sweep's frames anchor the map; tracked poses from here
    t_s_ = std::max(t_s_, r.t_s);
  }
  for (RobotRun& r : robots_) r.t_s = t_s_;  // the slower sweeps set the start of planning
  VOXPLAN_RETURN_IF_ERROR(UpdateFloor());
  Record(true);
  double next_series_s = t_s_ + p_.series_interval_s;
  double next_completeness_s = t_s_ + p_.completeness_interval_s;
  double next_progress_s = t_s_ + p_.progress_interval_s;
  CallPlanner(PlanEvent::kStart, -1, {});

  while (!done_ && t_s_ < p_.max_time_s) {
    const double t_next = std::min(t_s_ + p_.step_s, p_.max_time_s);
    for (RobotRun& r : robots_) VOXPLAN_RETURN_IF_ERROR(Advance(r, t_next));
    t_s_ = t_next;
    VOXPLAN_RETURN_IF_ERROR(UpdateFloor());

    bool called = false;
    std::vector<Failure> failures = std::move(failures_);
    failures_.clear();
    for (const Failure& f : failures) {
      if (done_) break;
      CallPlanner(PlanEvent::kTaskFailed, int32_t(f.robot), f.task);
      called = true;
    }
    std::vector<size_t> idle = std::move(went_idle_);
    went_idle_.clear();
    for (size_t i : idle) {
      if (done_ || !robots_[i].queue.empty()) continue;  // an earlier call gave it work
      CallPlanner(PlanEvent::kRobotIdle, int32_t(i), {});
      called = true;
    }
    // A run where every robot waits and the last call gave nothing asks again at once, so
    // "no task twice" ends it without waiting out an interval.
    const bool all_idle = std::all_of(robots_.begin(), robots_.end(),
                                      [](const RobotRun& r) { return r.queue.empty(); });
    if (!done_ && !called &&
        (t_s_ - last_call_s_ >= p_.planning_interval_s - 1e-9 || (all_idle && empty_calls_ > 0))) {
      CallPlanner(PlanEvent::kInterval, -1, {});
    }
    if (!done_ && wakeup_t_s_ <= t_s_ + 1e-9) {  // NaN (none asked) compares false
      wakeup_t_s_ = std::numeric_limits<double>::quiet_NaN();
      CallPlanner(PlanEvent::kWakeup, -1, {});
    }

    if (t_s_ >= next_series_s - 1e-9) {
      const bool with_completeness = t_s_ >= next_completeness_s - 1e-9;
      Record(with_completeness);
      next_series_s += p_.series_interval_s;
      if (with_completeness) next_completeness_s += p_.completeness_interval_s;
    }
    if (progress_ && t_s_ >= next_progress_s - 1e-9) {
      progress_({t_s_, result_.frames_fused,
                 result_.series.empty() ? 0.0 : result_.series.back().coverage, DistanceTotal(),
                 result_.plan_calls.size()});
      next_progress_s += p_.progress_interval_s;
    }
  }

  result_.terminated = result_.planner_fault ? result_.planner_fault->Terminated()
                       : done_               ? "done"
                                             : "time_limit";
  double t_end = t_s_;
  for (const RobotRun& r : robots_) t_end = std::max(t_end, r.t_s);
  result_.time_s = t_end;
  for (RobotRun& r : robots_) {
    r.t_s = t_end;
    Sample(r, r.queue.empty() ? RobotStatus::kIdle : RobotStatus::kBusy);
    result_.tracks.push_back(std::move(r.track));
    result_.task_views.push_back(std::move(r.views));
  }
  if (result_.series.empty() || result_.series.back().t_s < t_s_) {
    Record(true);
  } else if (probe_ && std::isnan(result_.series.back().completeness)) {
    result_.series.back().completeness = probe_(*volume_);
  }
  result_.timings.total_ms = NowMs() - run_t0;
  result_.volume = std::move(volume_);
  result_.recon_volume = std::move(recon_);
  result_.floor = std::move(floor_);
  return std::move(result_);
}

}  // namespace

Status ExploreParams::Validate() const {
  const VolumeParams volume{voxel_size_m, trunc_vox * voxel_size_m, max_memory_bytes};
  VOXPLAN_RETURN_IF_ERROR(volume.Validate().WithContext("explore"));
  VOXPLAN_RETURN_IF_ERROR(detector.Validate());
  if (recon_voxel_size_m != 0.f) {
    const VolumeParams recon{recon_voxel_size_m, trunc_vox * recon_voxel_size_m, max_memory_bytes};
    VOXPLAN_RETURN_IF_ERROR(recon.Validate().WithContext("explore: reconstruction volume"));
  }
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize("explore: image size", image_width, image_height));
  if (!(step_s > 0.0)) return InvalidArgument("explore: step_s must be > 0");
  if (!(planning_interval_s > 0.0))
    return InvalidArgument("explore: planning_interval_s must be > 0");
  if (!(max_time_s > 0.0) || !std::isfinite(max_time_s))
    return InvalidArgument("explore: max_time_s must be a positive number");
  if (!(drive_step_m > 0.f) || !(turn_step_deg > 0.f) || !(sweep_step_deg > 0.f))
    return InvalidArgument("explore: drive, turn and sweep steps must be > 0");
  if (!(series_interval_s > 0.0) || !(completeness_interval_s > 0.0) ||
      !(progress_interval_s > 0.0))
    return InvalidArgument("explore: output intervals must be > 0");
  if (!(route_margin_m >= 0.f)) return InvalidArgument("explore: route_margin_m must be >= 0");
  const auto noise_ok = [](float v) { return v >= 0.f && v <= 1.f; };
  if (!noise_ok(odometry.translation_per_m) || !noise_ok(odometry.rotation_per_rad) ||
      !noise_ok(odometry.rotation_per_m))
    return InvalidArgument("explore: odometry noise must be in [0, 1] per metre or radian");
  return robot.Validate();
}

Status CheckStarts(const FloorPlan& plan, const std::vector<Eigen::Vector2f>& starts,
                   float radius_m) {
  if (starts.empty()) return InvalidArgument("explore: no robot to start");
  for (size_t i = 0; i < starts.size(); ++i) {
    if (!FootprintFree(plan, starts[i], radius_m)) {
      return InvalidArgument("explore: robot " + std::to_string(i) + " cannot start at (" +
                             Fmt(starts[i].x()) + ", " + Fmt(starts[i].y()) +
                             "): its footprint of radius " + Fmt(radius_m) +
                             " m overlaps an obstacle or lies outside the floor plan");
    }
  }
  return Status::Ok();
}

Result<std::vector<Eigen::Vector2f>> ChooseStarts(const FloorPlan& plan,
                                                  const std::vector<Room>& rooms, int robots,
                                                  float radius_m, float spacing_m, float margin_m) {
  if (robots < 1) return InvalidArgument("explore: need at least one robot");
  if (plan.width <= 0 || plan.height <= 0) return InvalidArgument("explore: empty floor plan");
  Eigen::Vector2f centre = Eigen::Vector2f::Zero();
  if (!rooms.empty()) {
    const Room* largest = &rooms.front();
    for (const Room& room : rooms) {
      if (room.footprint_W.volume() > largest->footprint_W.volume()) largest = &room;
    }
    centre = largest->footprint_W.center();
  } else {
    size_t n = 0;
    for (int y = 0; y < plan.height; ++y)
      for (int x = 0; x < plan.width; ++x)
        if (plan.at(x, y) == PlanCell::kFree) {
          centre += plan.CellCenter(x, y);
          ++n;
        }
    if (n == 0) return NotFound("explore: the floor plan has no free cell to start on");
    centre /= float(n);
  }
  // Candidate cells by distance from the centre (ties in row-major order): deterministic.
  std::vector<std::pair<float, int>> cells;
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x)
      if (plan.at(x, y) == PlanCell::kFree)
        cells.push_back({(plan.CellCenter(x, y) - centre).squaredNorm(), y * plan.width + x});
  std::sort(cells.begin(), cells.end());
  const float half = 0.5f * float(robots - 1) * spacing_m;
  for (const auto& [d2, li] : cells) {
    const Eigen::Vector2f c = plan.CellCenter(li % plan.width, li / plan.width);
    for (const Eigen::Vector2f& dir : {Eigen::Vector2f(1.f, 0.f), Eigen::Vector2f(0.f, 1.f)}) {
      std::vector<Eigen::Vector2f> starts;
      bool ok = true;
      for (int k = 0; k < robots && ok; ++k) {
        const Eigen::Vector2f s = c + dir * (float(k) * spacing_m - half);
        ok = FootprintFree(plan, s, radius_m + margin_m);
        starts.push_back(s);
      }
      // One straight free line through them: they start in one connected piece of floor.
      if (ok && SegmentFree(plan, starts.front(), starts.back(), radius_m)) return starts;
    }
  }
  return NotFound("explore: no free spot fits " + std::to_string(robots) + " robots side by side");
}

Result<ExploreResult> RunExplore(const World& world, const FloorPlan& plan,
                                 const std::vector<Eigen::Vector2f>& starts, LoadedPlanner& planner,
                                 const ExploreParams& params,
                                 const std::function<double(const TsdfVolume&)>& completeness_probe,
                                 const ExploreProgressFn& progress) {
  Explorer explorer(world, plan, planner, params, completeness_probe, progress);
  return explorer.Run(starts);
}

double VolumeCompleteness(const TsdfVolume& volume, const std::vector<Eigen::Vector3f>& samples_W,
                          float threshold_m) {
  if (samples_W.empty()) return 0.0;
  size_t hit = 0;
  for (const Eigen::Vector3f& p : samples_W) {
    // The interpolated TSDF at the sample is (about) its distance to the fused surface, which
    // the mesh's zero crossing follows; unobserved neighbours mean no surface there yet.
    const std::optional<VoxelValue> v = Interpolate(volume, p, 0.5f);
    if (v && std::abs(v->tsdf_m) <= threshold_m) ++hit;
  }
  return double(hit) / double(samples_W.size());
}

ObservedRaster ObservedFromFloor(const FloorMap& floor) {
  const FloorGeometry& g = floor.geometry();
  ObservedRaster out;
  out.origin_W = g.origin_cell.cast<double>() * double(g.cell_size_m);
  out.resolution_m = g.cell_size_m;
  out.width = g.width;
  out.height = g.height;
  out.cells.resize(floor.cells().size());
  for (size_t i = 0; i < out.cells.size(); ++i)
    out.cells[i] = floor.cells()[i] == FloorCell::kUnknown ? kUnknownCell : 1;
  return out;
}

TrackedPoseSummary SummarizeTrackedPoses(const std::vector<std::vector<ExploreFrame>>& frames) {
  TrackedPoseSummary out;
  std::vector<double> residuals;
  double squared = 0.0;
  for (const std::vector<ExploreFrame>& robot : frames) {
    for (size_t i = 0; i < robot.size(); ++i) {
      const ExploreFrame& f = robot[i];
      squared += (f.T_W_C_fused.translation() - f.T_W_C.translation()).squaredNorm();
      ++out.frames;
      // Registered frames only: the sweep's are anchored, the odometry's had nothing to register.
      if (!f.odometry && f.residual_rms_m > 0.f) residuals.push_back(f.residual_rms_m);
    }
  }
  const TimingSummary r = Summarize(residuals);
  out.residual_mean_m = r.mean;
  out.residual_p90_m = r.p90;
  out.ate_rms_m = out.frames > 0 ? std::sqrt(squared / double(out.frames)) : 0.0;
  return out;
}

const char* PlanEventName(PlanEvent event) {
  switch (event) {
    case PlanEvent::kStart:
      return "start";
    case PlanEvent::kInterval:
      return "interval";
    case PlanEvent::kWakeup:
      return "wakeup";
    case PlanEvent::kRobotIdle:
      return "robot_idle";
    case PlanEvent::kTaskFailed:
      return "task_failed";
  }
  return "unknown";
}

}  // namespace voxplan
