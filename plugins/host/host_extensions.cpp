// The extension tables behind vp_host_api.get_extension (planner ABI 1.1): a name, a version
// and a static table each. A table grows by appended fields only, its version with it.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "plugins/host/host_internal.h"

namespace voxplan::internal {
namespace {

// Whether a struct of `size` bytes starting at `s` (a plugin's, maybe an older, shorter version)
// holds `field`: fields past its end keep the host's defaults.
template <typename S, typename F>
bool HasField(const S& s, uint32_t size, const F& field) {
  return size >=
         uint32_t(reinterpret_cast<const char*>(&field) - reinterpret_cast<const char*>(&s)) +
             uint32_t(sizeof(field));
}

// ---- vp.objects 1. ----------------------------------------------------------------------------

vp_status GetInstanceSurface(const vp_world* w, uint32_t id, const vp_surface_voxel** out,
                             uint64_t* count) {
  if (!w || !out || !count) return VP_ERROR_INVALID_ARGUMENT;
  if (!w->have_surface_by_instance) {
    // The host's own query fills (and caches) the call's surface voxels, inside its guards.
    const vp_surface_voxel* all = nullptr;
    uint64_t n = 0;
    const vp_status s = PlannerHostApi().get_surface_voxels(w, &all, &n);
    if (s != VP_OK) return s;
    try {
      w->surface_by_instance.assign(all, all + n);
      // Stable: within an instance the order stays the world's.
      std::stable_sort(w->surface_by_instance.begin(), w->surface_by_instance.end(),
                       [](const vp_surface_voxel& a, const vp_surface_voxel& b) {
                         return a.instance < b.instance;
                       });
    } catch (...) {  // bad_alloc: the plugin gets a status instead
      w->surface_by_instance.clear();
      return VP_ERROR_INTERNAL;
    }
    w->have_surface_by_instance = true;
  }
  // Compared as int64_t: voxels store ids as int32_t, so an id past INT32_MAX matches none.
  const int64_t key = id;
  const std::vector<vp_surface_voxel>& v = w->surface_by_instance;
  const auto begin = std::lower_bound(
      v.begin(), v.end(), key, [](const vp_surface_voxel& a, int64_t k) { return a.instance < k; });
  const auto end = std::upper_bound(
      begin, v.end(), key, [](int64_t k, const vp_surface_voxel& b) { return k < b.instance; });
  *out = w->surface_by_instance.data() + (begin - w->surface_by_instance.begin());
  *count = uint64_t(end - begin);
  return VP_OK;
}

const vp_objects_ext kObjects = {
    .header = {.struct_size = sizeof(vp_objects_ext), .version = 1},
    .get_instance_surface = GetInstanceSurface,
};

// ---- vp.task 1. -------------------------------------------------------------------------------

vp_status AddTaskExt(vp_plan_output* o, uint32_t robot, const vp_task* task,
                     const vp_task_ext* ext) {
  return Guarded([&]() -> vp_status {
    if (!o || robot >= o->result->robots.size() || !task) return VP_ERROR_INVALID_ARGUMENT;
    // Its first field says how much of the struct the plugin knows.
    if (ext && ext->struct_size < sizeof(uint32_t)) return VP_ERROR_STRUCT_SIZE;
    RobotPlan& plan = o->result->robots[robot];
    if (plan.tasks.size() >= kMaxTasksPerRobot) return VP_ERROR_LIMIT;
    PlannerTask t = FromC(*task);
    if (ext) t.camera = FromC(*ext, ext->struct_size);
    plan.tasks.push_back(t);  // validated after plan() returns
    return VP_OK;
  });
}

vp_status GetRobotQueueExt(const vp_world* w, uint32_t robot, const vp_task_ext** out,
                           uint32_t* count) {
  return Guarded([&]() -> vp_status {
    if (!w || !out || !count || robot >= w->queue_exts.size()) return VP_ERROR_INVALID_ARGUMENT;
    *out = w->queue_exts[robot].data();
    *count = uint32_t(w->queue_exts[robot].size());
    return VP_OK;
  });
}

const vp_task_ext_table kTask = {
    .header = {.struct_size = sizeof(vp_task_ext_table), .version = 1},
    .add_task_ext = AddTaskExt,
    .get_robot_queue_ext = GetRobotQueueExt,
};

// ---- vp.motion 1. -----------------------------------------------------------------------------

vp_status SetPathExt(vp_plan_output* o, uint32_t robot, const vp_path_point* points, uint32_t count,
                     const vp_path_ext* ext) {
  if (ext && ext->struct_size < sizeof(uint32_t)) return VP_ERROR_STRUCT_SIZE;
  const vp_status s = PlannerHostApi().set_path(o, robot, points, count);
  if (s != VP_OK) return s;
  return Guarded([&]() -> vp_status {
    RobotPlan& plan = o->result->robots[robot];  // set_path checked o and robot
    plan.path_continuous = false;
    plan.path_speed_mps.clear();
    if (!ext) return VP_OK;
    if (HasField(*ext, ext->struct_size, ext->flags))
      plan.path_continuous = (ext->flags & VP_PATH_CONTINUOUS) != 0;
    if (HasField(*ext, ext->struct_size, ext->speed_mps) && ext->speed_mps) {
      plan.path_speed_mps.assign(ext->speed_mps, ext->speed_mps + count);  // validated later
    }
    return VP_OK;
  });
}

const vp_motion_ext kMotion = {
    .header = {.struct_size = sizeof(vp_motion_ext), .version = 1},
    .set_path_ext = SetPathExt,
};

// ---- vp.schedule 1. ---------------------------------------------------------------------------

vp_status RequestCall(vp_plan_output* o, double t_s) {
  return Guarded([&]() -> vp_status {
    if (!o || !o->result) return VP_ERROR_INVALID_ARGUMENT;
    o->result->wakeup_t_s = t_s;  // the loop checks it against its clock
    return VP_OK;
  });
}

const vp_schedule_ext kSchedule = {
    .header = {.struct_size = sizeof(vp_schedule_ext), .version = 1},
    .request_call = RequestCall,
};

// ---- The registry. ----------------------------------------------------------------------------

struct Extension {
  std::string_view name;
  const vp_extension_header* table;
};

constexpr Extension kExtensions[] = {
    {VP_EXT_OBJECTS, &kObjects.header},
    {VP_EXT_TASK, &kTask.header},
    {VP_EXT_MOTION, &kMotion.header},
    {VP_EXT_SCHEDULE, &kSchedule.header},
};

}  // namespace

TaskCamera FromC(const vp_task_ext& e, uint32_t size) {
  TaskCamera c;
  // Fields past what the plugin's struct holds keep their defaults.
  const auto has = [&](const auto& field) { return HasField(e, size, field); };
  if (has(e.camera_height_m)) c.height_m = e.camera_height_m;
  if (has(e.camera_offset_m)) c.offset_m = {e.camera_offset_m[0], e.camera_offset_m[1]};
  if (has(e.look_at)) c.look_at = e.look_at != 0;
  if (has(e.look_at_W)) c.look_at_W = {e.look_at_W[0], e.look_at_W[1], e.look_at_W[2]};
  if (has(e.sweep_pitch_step_rad)) {
    c.sweep_pitch_min_rad = e.sweep_pitch_min_rad;
    c.sweep_pitch_max_rad = e.sweep_pitch_max_rad;
    c.sweep_pitch_step_rad = e.sweep_pitch_step_rad;
  }
  if (has(e.object_id)) c.object_id = e.object_id;
  return c;
}

const vp_extension_header* GetExtension(const char* name, uint32_t min_version) {
  if (name == nullptr) return nullptr;
  // Names are short; a plugin passing an unterminated one reads at most this far.
  constexpr size_t kMaxName = 64;
  const std::string_view wanted(name, strnlen(name, kMaxName + 1));
  for (const Extension& e : kExtensions) {
    if (e.name == wanted && e.table->version >= min_version) return e.table;
  }
  return nullptr;
}

}  // namespace voxplan::internal
