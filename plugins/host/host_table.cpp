// The host's C table over a PlannerWorld (queries) and the output builder the plugin fills
// during plan(). No exception leaves a function the plugin calls.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/parallel.h"
#include "plugins/host/host_internal.h"

static_assert(sizeof(voxplan::FloorCell) == 1);
static_assert(uint8_t(voxplan::FloorCell::kUnknown) == VP_FLOOR_UNKNOWN &&
              uint8_t(voxplan::FloorCell::kFree) == VP_FLOOR_FREE &&
              uint8_t(voxplan::FloorCell::kFrontier) == VP_FLOOR_FRONTIER &&
              uint8_t(voxplan::FloorCell::kObstacle) == VP_FLOOR_OBSTACLE);
static_assert(uint8_t(voxplan::VoxelState::kUnobserved) == VP_VOXEL_UNOBSERVED &&
              uint8_t(voxplan::VoxelState::kFree) == VP_VOXEL_FREE &&
              uint8_t(voxplan::VoxelState::kOccupied) == VP_VOXEL_OCCUPIED);
static_assert(int32_t(voxplan::CameraMount::kBase) == VP_MOUNT_BASE &&
              int32_t(voxplan::CameraMount::kHead) == VP_MOUNT_HEAD &&
              int32_t(voxplan::CameraMount::kArm) == VP_MOUNT_ARM);

namespace voxplan {
namespace {

using internal::AllFinite;
using internal::ElapsedS;
using internal::FromC;
using internal::GetExtension;
using internal::Guarded;
using internal::kMaxTasksPerRobot;

// Caps on what one plan may return, so a runaway plugin cannot exhaust memory.
constexpr size_t kMaxPathPoints = 1000000;
constexpr size_t kMaxDiagnostics = 100000;
constexpr size_t kMaxDebugPoints = 5000000;
constexpr uint32_t kMaxMatrixPoints = 4096;
constexpr size_t kMaxNameChars = 256;
constexpr size_t kMaxTextChars = 4096;

// Guarded, and only while the host has not revoked the world: a plugin the host gave up on may
// still run, and the world it was shown may be gone.
template <class F>
vp_status InWorld(const vp_world* w, F&& f) noexcept {
  if (w == nullptr) return VP_ERROR_INVALID_ARGUMENT;
  const internal::WorldEntry entry(*w);
  if (!entry.ok()) return VP_ERROR_INTERNAL;
  return Guarded(f);
}

// Copies `full` into a struct the plugin sized: at most out->struct_size bytes.
template <class T>
vp_status FillSized(T* out, const T& full) {
  if (out == nullptr || out->struct_size < sizeof(uint32_t)) return VP_ERROR_INVALID_ARGUMENT;
  const uint32_t size = std::min<uint32_t>(out->struct_size, uint32_t(sizeof(T)));
  std::memcpy(static_cast<void*>(out), &full, size);
  out->struct_size = size;
  return VP_OK;
}

std::string BoundedString(const char* s, size_t max_chars) {
  return std::string(s, strnlen(s, max_chars));
}

// ---- Queries. ----------------------------------------------------------------------------

vp_status GetCallInfo(const vp_world* w, vp_call_info* out) {
  return Guarded(
      [&]() -> vp_status { return w ? FillSized(out, w->call) : VP_ERROR_INVALID_ARGUMENT; });
}

void Log(const vp_world* w, int32_t level, const char* message) {
  (void)Guarded([&]() -> vp_status {
    if (w && w->log && message) w->log->push_back({level, BoundedString(message, kMaxTextChars)});
    return VP_OK;
  });
}

vp_status GetMapInfo(const vp_world* w, vp_map_info* out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w) return VP_ERROR_INVALID_ARGUMENT;
    const PlannerMapInfo m = w->world->MapInfo();
    vp_map_info info{};
    info.struct_size = sizeof(info);
    info.revision = m.revision;
    info.voxel_size_m = m.voxel_size_m;
    info.floor_z_m = m.floor_z_m;
    for (int i = 0; i < 3; ++i) {
      info.bounds_min[i] = m.bounds_min[i];
      info.bounds_max[i] = m.bounds_max[i];
    }
    return FillSized(out, info);
  });
}

vp_status VoxelStates(const vp_world* w, const float* xyz, uint64_t count, uint8_t* out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || (count > 0 && (!xyz || !out))) return VP_ERROR_INVALID_ARGUMENT;
    std::vector<Eigen::Vector3f> points(count);
    for (uint64_t i = 0; i < count; ++i) points[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    std::vector<VoxelState> states(count, VoxelState::kUnobserved);
    w->world->VoxelStates(points, states);
    for (uint64_t i = 0; i < count; ++i) out[i] = uint8_t(states[i]);
    return VP_OK;
  });
}

vp_status Raycast(const vp_world* w, const vp_ray* rays, uint64_t count, vp_ray_hit* out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || (count > 0 && (!rays || !out))) return VP_ERROR_INVALID_ARGUMENT;
    std::vector<PlannerRay> in(count);
    for (uint64_t i = 0; i < count; ++i) {
      in[i].origin = Eigen::Vector3f(rays[i].origin[0], rays[i].origin[1], rays[i].origin[2]);
      in[i].direction =
          Eigen::Vector3f(rays[i].direction[0], rays[i].direction[1], rays[i].direction[2]);
      in[i].max_range_m = rays[i].max_range_m;
      if (!in[i].origin.allFinite() || !in[i].direction.allFinite() ||
          !std::isfinite(in[i].max_range_m)) {
        return VP_ERROR_INVALID_ARGUMENT;
      }
    }
    std::vector<PlannerRayHit> hits(count);
    w->world->Raycast(in, hits);
    for (uint64_t i = 0; i < count; ++i) {
      out[i] = {hits[i].distance_m, hits[i].unobserved_m, int32_t(hits[i].result)};
    }
    return VP_OK;
  });
}

vp_status GetFrontierVoxels(const vp_world* w, const float** out, uint64_t* count) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !out || !count) return VP_ERROR_INVALID_ARGUMENT;
    if (!w->have_frontier) {
      for (const Eigen::Vector3f& p : w->world->FrontierVoxels()) {
        w->frontier_xyz.insert(w->frontier_xyz.end(), {p.x(), p.y(), p.z()});
      }
      w->have_frontier = true;
    }
    *out = w->frontier_xyz.data();
    *count = w->frontier_xyz.size() / 3;
    return VP_OK;
  });
}

vp_status GetSurfaceVoxels(const vp_world* w, const vp_surface_voxel** out, uint64_t* count) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !out || !count) return VP_ERROR_INVALID_ARGUMENT;
    if (!w->have_surface) {
      const std::vector<SurfaceVoxel> voxels = w->world->SurfaceVoxels();
      w->surface.resize(voxels.size());
      // Hundreds of thousands in a house: converted in parallel, element by element.
      ParallelFor(voxels.size(), 4096, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
          const SurfaceVoxel& s = voxels[i];
          w->surface[i] = {{s.position.x(), s.position.y(), s.position.z()},
                           {s.normal.x(), s.normal.y(), s.normal.z()},
                           s.uncertainty,
                           s.weight,
                           s.instance};
        }
      });
      w->have_surface = true;
    }
    *out = w->surface.data();
    *count = w->surface.size();
    return VP_OK;
  });
}

vp_status GetFloor(const vp_world* w, vp_floor* out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w) return VP_ERROR_INVALID_ARGUMENT;
    const PlannerFloor& f = w->world->Floor();
    const size_t n = size_t(std::max(f.width, 0)) * size_t(std::max(f.height, 0));
    if (f.cells.size() != n || f.clearance_m.size() != n) return VP_ERROR_INTERNAL;
    vp_floor floor{};
    floor.struct_size = sizeof(floor);
    floor.width = f.width;
    floor.height = f.height;
    floor.cell_size_m = f.cell_size_m;
    floor.origin_x_m = f.origin_m.x();
    floor.origin_y_m = f.origin_m.y();
    floor.revision = f.revision;
    // FloorCell is one byte with the VP_FLOOR_* values (asserted above).
    floor.cells = reinterpret_cast<const uint8_t*>(f.cells.data());
    floor.clearance_m = f.clearance_m.data();
    return FillSized(out, floor);
  });
}

vp_status StatusToC(const Status& s) {
  switch (s.code()) {
    case StatusCode::kOk:
      return VP_OK;
    case StatusCode::kNotFound:
    case StatusCode::kUnsupported:
      return VP_ERROR_NOT_AVAILABLE;
    case StatusCode::kInvalidArgument:
      return VP_ERROR_INVALID_ARGUMENT;
    default:
      return VP_ERROR_INTERNAL;
  }
}

vp_status GeodesicField(const vp_world* w, const float source[2], float min_clearance_m,
                        const float** out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !source || !out || !AllFinite({source[0], source[1], min_clearance_m})) {
      return VP_ERROR_INVALID_ARGUMENT;
    }
    Result<std::vector<float>> field =
        w->world->GeodesicField({source[0], source[1]}, min_clearance_m);
    if (!field.ok()) return StatusToC(field.status());
    w->buffers.push_back(std::move(field).value());
    *out = w->buffers.back().data();
    return VP_OK;
  });
}

vp_status DistanceMatrix(const vp_world* w, const float* xy, uint32_t count, float min_clearance_m,
                         const float** out) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !out || (count > 0 && !xy) || !std::isfinite(min_clearance_m)) {
      return VP_ERROR_INVALID_ARGUMENT;
    }
    if (count > kMaxMatrixPoints) return VP_ERROR_LIMIT;
    std::vector<Eigen::Vector2f> points(count);
    for (uint32_t i = 0; i < count; ++i) {
      points[i] = {xy[2 * i], xy[2 * i + 1]};
      if (!points[i].allFinite()) return VP_ERROR_INVALID_ARGUMENT;
    }
    Result<std::vector<float>> matrix = w->world->DistanceMatrix(points, min_clearance_m);
    if (!matrix.ok()) return StatusToC(matrix.status());
    if (matrix->size() != size_t(count) * count) return VP_ERROR_INTERNAL;
    w->buffers.push_back(std::move(matrix).value());
    *out = w->buffers.back().data();
    return VP_OK;
  });
}

vp_status ShortestPath(const vp_world* w, const float from[2], const float to[2],
                       float min_clearance_m, const float** out, uint32_t* count) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !from || !to || !out || !count ||
        !AllFinite({from[0], from[1], to[0], to[1], min_clearance_m})) {
      return VP_ERROR_INVALID_ARGUMENT;
    }
    Result<std::vector<Eigen::Vector2f>> path =
        w->world->ShortestPath({from[0], from[1]}, {to[0], to[1]}, min_clearance_m);
    if (!path.ok()) return StatusToC(path.status());
    std::vector<float> flat;
    flat.reserve(path->size() * 2);
    for (const Eigen::Vector2f& p : *path) flat.insert(flat.end(), {p.x(), p.y()});
    w->buffers.push_back(std::move(flat));
    *out = w->buffers.back().data();
    *count = uint32_t(path->size());
    return VP_OK;
  });
}

vp_status GetInstances(const vp_world* w, const vp_instance** out, uint32_t* count) {
  return InWorld(w, [&]() -> vp_status {
    if (!w || !out || !count) return VP_ERROR_INVALID_ARGUMENT;
    if (!w->have_instances) {
      const std::vector<ObjectInstance> objects = w->world->Instances();
      // Labels first: their c_str() must not move once handed out.
      for (const ObjectInstance& o : objects) w->instance_labels.push_back(o.label);
      for (size_t i = 0; i < objects.size(); ++i) {
        const ObjectInstance& o = objects[i];
        w->instances.push_back({o.id,
                                o.class_id,
                                w->instance_labels[i].c_str(),
                                {o.bbox_min.x(), o.bbox_min.y(), o.bbox_min.z()},
                                {o.bbox_max.x(), o.bbox_max.y(), o.bbox_max.z()},
                                o.completeness});
      }
      w->have_instances = true;
    }
    *out = w->instances.data();
    *count = uint32_t(w->instances.size());
    return VP_OK;
  });
}

uint32_t RobotCount(const vp_world* w) { return w ? uint32_t(w->robots.size()) : 0; }

vp_status GetRobot(const vp_world* w, uint32_t index, vp_robot* out) {
  return Guarded([&]() -> vp_status {
    if (!w || index >= w->robots.size()) return VP_ERROR_INVALID_ARGUMENT;
    const PlannerRobot& r = w->robots[index];
    vp_robot robot{};
    robot.struct_size = sizeof(robot);
    robot.id = r.id;
    robot.x_m = r.position_m.x();
    robot.y_m = r.position_m.y();
    robot.theta_rad = r.theta_rad;
    robot.camera_yaw_rad = r.camera_yaw_rad;
    robot.camera_pitch_rad = r.camera_pitch_rad;
    robot.mode = r.mode;
    robot.status = r.executing ? VP_ROBOT_EXECUTING : VP_ROBOT_IDLE;
    robot.queued_tasks = uint32_t(r.queue.size());
    robot.mode_count = uint32_t(r.modes.size());
    robot.radius_m = r.radius_m;
    robot.camera_height_m = r.camera_height_m;
    robot.min_pitch_rad = r.min_pitch_rad;
    robot.max_pitch_rad = r.max_pitch_rad;
    robot.camera_yaw_rate_radps = r.camera_yaw_rate_radps;
    robot.camera_pitch_rate_radps = r.camera_pitch_rate_radps;
    robot.distance_m = r.distance_m;
    robot.busy_s = r.busy_s;
    robot.idle_s = r.idle_s;
    return FillSized(out, robot);
  });
}

vp_status GetRobotMode(const vp_world* w, uint32_t index, uint32_t mode, vp_mode_params* out) {
  return Guarded([&]() -> vp_status {
    if (!w || index >= w->robots.size() || mode >= w->robots[index].modes.size()) {
      return VP_ERROR_INVALID_ARGUMENT;
    }
    const ScanMode& m = w->robots[index].modes[mode];
    vp_mode_params p{};
    p.struct_size = sizeof(p);
    p.max_speed_mps = m.max_speed_mps;
    p.max_turn_rate_radps = m.max_turn_rate_radps;
    p.horizontal_fov_rad = m.horizontal_fov_rad;
    p.vertical_fov_rad = m.vertical_fov_rad;
    p.min_range_m = m.min_range_m;
    p.max_range_m = m.max_range_m;
    p.image_width = m.image_width;
    p.image_height = m.image_height;
    p.fx = m.fx;
    p.fy = m.fy;
    p.cx = m.cx;
    p.cy = m.cy;
    p.mount = int32_t(m.mount);
    p.camera_height_min_m = m.camera_height_min_m;
    p.camera_height_max_m = m.camera_height_max_m;
    p.reach_min_m = m.reach_min_m;
    p.reach_max_m = m.reach_max_m;
    p.reach_half_angle_rad = m.reach_half_angle_rad;
    p.min_pitch_rad = m.min_pitch_rad;
    p.max_pitch_rad = m.max_pitch_rad;
    p.camera_speed_mps = m.camera_speed_mps;
    p.camera_turn_rate_radps = m.camera_turn_rate_radps;
    p.capture_hz = m.capture_hz;
    p.switch_s = m.switch_s;
    return FillSized(out, p);
  });
}

vp_status GetRobotQueue(const vp_world* w, uint32_t index, const vp_task** out, uint32_t* count) {
  return Guarded([&]() -> vp_status {
    if (!w || !out || !count || index >= w->robots.size()) return VP_ERROR_INVALID_ARGUMENT;
    *out = w->queues[index].data();
    *count = uint32_t(w->queues[index].size());
    return VP_OK;
  });
}

// ---- Output builder. ---------------------------------------------------------------------

RobotPlan* RobotOf(vp_plan_output* o, uint32_t robot) {
  return o && robot < o->result->robots.size() ? &o->result->robots[robot] : nullptr;
}

vp_status SetTaskPolicy(vp_plan_output* o, uint32_t robot, int32_t policy) {
  return Guarded([&]() -> vp_status {
    RobotPlan* plan = RobotOf(o, robot);
    if (!plan || (policy != VP_TASKS_APPEND && policy != VP_TASKS_REPLACE)) {
      return VP_ERROR_INVALID_ARGUMENT;
    }
    plan->policy = TaskPolicy(policy);
    return VP_OK;
  });
}

vp_status AddTask(vp_plan_output* o, uint32_t robot, const vp_task* task) {
  return Guarded([&]() -> vp_status {
    RobotPlan* plan = RobotOf(o, robot);
    if (!plan || !task) return VP_ERROR_INVALID_ARGUMENT;
    if (plan->tasks.size() >= kMaxTasksPerRobot) return VP_ERROR_LIMIT;
    plan->tasks.push_back(FromC(*task));  // validated after plan() returns
    return VP_OK;
  });
}

vp_status SetPath(vp_plan_output* o, uint32_t robot, const vp_path_point* points, uint32_t count) {
  return Guarded([&]() -> vp_status {
    RobotPlan* plan = RobotOf(o, robot);
    if (!plan || (count > 0 && !points)) return VP_ERROR_INVALID_ARGUMENT;
    if (count > kMaxPathPoints) return VP_ERROR_LIMIT;
    plan->path.clear();
    for (uint32_t i = 0; i < count; ++i) {
      plan->path.push_back({{points[i].x_m, points[i].y_m}, points[i].theta_rad});
    }
    return VP_OK;
  });
}

vp_status SetCameraTrajectory(vp_plan_output* o, uint32_t robot, const vp_camera_sample* samples,
                              uint32_t count) {
  return Guarded([&]() -> vp_status {
    RobotPlan* plan = RobotOf(o, robot);
    if (!plan || (count > 0 && !samples)) return VP_ERROR_INVALID_ARGUMENT;
    if (count > kMaxPathPoints) return VP_ERROR_LIMIT;
    plan->camera_trajectory.clear();
    for (uint32_t i = 0; i < count; ++i) {
      const vp_camera_sample& s = samples[i];
      plan->camera_trajectory.push_back(
          {s.t_s, {s.position[0], s.position[1], s.position[2]}, s.yaw_rad, s.pitch_rad});
    }
    return VP_OK;
  });
}

vp_status SetDone(vp_plan_output* o, int32_t done) {
  if (!o) return VP_ERROR_INVALID_ARGUMENT;
  o->result->done = done != 0;
  return VP_OK;
}

vp_status AddDiagnostic(vp_plan_output* o, const char* name, double value) {
  return Guarded([&]() -> vp_status {
    if (!o || !name) return VP_ERROR_INVALID_ARGUMENT;
    if (o->result->diagnostics.size() >= kMaxDiagnostics) return VP_ERROR_LIMIT;
    o->result->diagnostics.emplace_back(BoundedString(name, kMaxNameChars), value);
    return VP_OK;
  });
}

vp_status AddDrawing(vp_plan_output* o, DebugDrawing::Kind kind, const char* layer,
                     const float* xyz, uint32_t count, const char* text, uint32_t rgba) {
  return Guarded([&]() -> vp_status {
    if (!o || !layer || (count > 0 && !xyz)) return VP_ERROR_INVALID_ARGUMENT;
    if (o->debug_points + count > kMaxDebugPoints) return VP_ERROR_LIMIT;
    o->debug_points += count;
    DebugDrawing d;
    d.kind = kind;
    d.layer = BoundedString(layer, kMaxNameChars);
    for (uint32_t i = 0; i < count; ++i)
      d.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    if (text) d.text = BoundedString(text, kMaxTextChars);
    d.rgba = rgba;
    o->result->drawings.push_back(std::move(d));
    return VP_OK;
  });
}

vp_status AddDebugPoints(vp_plan_output* o, const char* layer, const float* xyz, uint32_t count,
                         uint32_t rgba) {
  return AddDrawing(o, DebugDrawing::Kind::kPoints, layer, xyz, count, nullptr, rgba);
}
vp_status AddDebugPolyline(vp_plan_output* o, const char* layer, const float* xyz, uint32_t count,
                           uint32_t rgba) {
  return AddDrawing(o, DebugDrawing::Kind::kPolyline, layer, xyz, count, nullptr, rgba);
}
vp_status AddDebugLabel(vp_plan_output* o, const char* layer, const float xyz[3], const char* text,
                        uint32_t rgba) {
  if (!text) return VP_ERROR_INVALID_ARGUMENT;
  return AddDrawing(o, DebugDrawing::Kind::kLabel, layer, xyz, 1, text, rgba);
}

vp_status SetError(vp_plan_output* o, const char* message) {
  return Guarded([&]() -> vp_status {
    if (!o || !message) return VP_ERROR_INVALID_ARGUMENT;
    o->error = BoundedString(message, kMaxTextChars);
    return VP_OK;
  });
}

// Designated, so two functions of the same signature can never swap places.
const vp_host_api kHostApi = {
    .struct_size = sizeof(vp_host_api),
    .abi_version = VP_PLANNER_ABI_VERSION,
    .get_call_info = GetCallInfo,
    .elapsed_s = ElapsedS,
    .log = Log,
    .get_map_info = GetMapInfo,
    .voxel_states = VoxelStates,
    .raycast = Raycast,
    .get_frontier_voxels = GetFrontierVoxels,
    .get_surface_voxels = GetSurfaceVoxels,
    .get_floor = GetFloor,
    .geodesic_field = GeodesicField,
    .distance_matrix = DistanceMatrix,
    .shortest_path = ShortestPath,
    .get_instances = GetInstances,
    .robot_count = RobotCount,
    .get_robot = GetRobot,
    .get_robot_mode = GetRobotMode,
    .get_robot_queue = GetRobotQueue,
    .set_task_policy = SetTaskPolicy,
    .add_task = AddTask,
    .set_path = SetPath,
    .set_camera_trajectory = SetCameraTrajectory,
    .set_done = SetDone,
    .add_diagnostic = AddDiagnostic,
    .add_debug_points = AddDebugPoints,
    .add_debug_polyline = AddDebugPolyline,
    .add_debug_label = AddDebugLabel,
    .set_error = SetError,
    .get_extension = GetExtension,
};

}  // namespace

const vp_host_api& PlannerHostApi() { return kHostApi; }

}  // namespace voxplan
