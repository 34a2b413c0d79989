#pragma once
// What the host's three plan-call files share: the memory behind the opaque C handles and the
// small conversions both the C table and the validation use. Not for use outside plugins/host.
#include <atomic>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "core/stopwatch.h"
#include "plugins/host/plugin_host.h"

// Host memory handed to the plugin lives here until the call returns.
struct vp_world {
  const voxplan::PlannerWorld* world = nullptr;
  vp_call_info call{};
  voxplan::Stopwatch clock;  // since the call began
  std::vector<voxplan::PlanLogEntry>* log = nullptr;

  mutable bool have_frontier = false, have_surface = false, have_instances = false;
  mutable std::vector<float> frontier_xyz;
  mutable std::vector<vp_surface_voxel> surface;
  mutable bool have_surface_by_instance = false;
  mutable std::vector<vp_surface_voxel> surface_by_instance;  // stable-sorted by instance
  mutable std::vector<std::string> instance_labels;
  mutable std::vector<vp_instance> instances;
  mutable std::vector<std::vector<float>> buffers;  // fields, matrices, paths; never reused
  std::vector<voxplan::PlannerRobot> robots;
  std::vector<std::vector<vp_task>> queues;
  std::vector<std::vector<vp_task_ext>> queue_exts;  // the same tasks' camera parts
  // Host functions inside `world` now; kRevoked added once the host gave the plugin up.
  mutable std::atomic<int> gate{0};
};

struct vp_plan_output {
  voxplan::PlanResult* result = nullptr;
  std::string error;
  size_t debug_points = 0;
};

namespace voxplan::internal {

inline constexpr int kRevoked = 1 << 30;
inline constexpr size_t kMaxTasksPerRobot = 100000;  // per robot and plan call

// A host function's body: an exception (bad_alloc, a throwing PlannerWorld) becomes a status.
template <class F>
vp_status Guarded(F&& f) noexcept {
  try {
    return f();
  } catch (...) {
    return VP_ERROR_INTERNAL;
  }
}

// One host function's use of w->world: ok() is false once the host revoked the handle.
class WorldEntry {
 public:
  explicit WorldEntry(const vp_world& w) : w_(w), ok_(w.gate.fetch_add(1) >= 0) {}
  ~WorldEntry() { w_.gate.fetch_sub(1); }
  bool ok() const { return ok_; }

 private:
  const vp_world& w_;
  bool ok_;
};

// Stops every later host function from reading w.world, and waits (at most wait_s) for those
// inside it to leave. The host functions are short: a plugin stuck inside one is a host bug.
void Revoke(const vp_world& w, double wait_s);

// Memory a crashed or hung plugin may still touch: never freed, and still reachable (so leak
// checkers do not report it).
void KeepAlive(std::shared_ptr<void> memory);

// One plan() call's host memory, on the heap so it can outlive the call when the plugin does.
struct PlanCallState {
  voxplan::PlanResult result;
  vp_world world;
  vp_plan_output out;
  vp_status status = VP_OK;
};

inline vp_task ToC(const PlannerTask& t) {
  return {t.position_m.x(),   t.position_m.y(), t.theta_rad, t.camera_yaw_rad,
          t.camera_pitch_rad, t.dwell_s,        t.mode,      t.tag};
}
inline PlannerTask FromC(const vp_task& t) {
  PlannerTask p;
  p.position_m = {t.x_m, t.y_m};
  p.theta_rad = t.theta_rad;
  p.camera_yaw_rad = t.camera_yaw_rad;
  p.camera_pitch_rad = t.camera_pitch_rad;
  p.dwell_s = t.dwell_s;
  p.mode = t.mode;
  p.tag = t.tag;
  return p;
}

inline vp_task_ext ToC(const TaskCamera& c) {
  vp_task_ext e{};
  e.struct_size = sizeof(e);
  e.camera_height_m = c.height_m;
  e.camera_offset_m[0] = c.offset_m.x();
  e.camera_offset_m[1] = c.offset_m.y();
  e.look_at = c.look_at ? 1 : 0;
  for (int k = 0; k < 3; ++k) e.look_at_W[k] = c.look_at_W[k];
  e.sweep_pitch_min_rad = c.sweep_pitch_min_rad;
  e.sweep_pitch_max_rad = c.sweep_pitch_max_rad;
  e.sweep_pitch_step_rad = c.sweep_pitch_step_rad;
  e.object_id = c.object_id;
  return e;
}
// A plugin's vp_task_ext of `size` bytes (it may be older and shorter): what it lacks keeps the
// defaults.
TaskCamera FromC(const vp_task_ext& e, uint32_t size);

inline bool AllFinite(std::initializer_list<float> values) {
  for (float v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

inline double ElapsedS(const vp_world* w) {
  if (w == nullptr) return 0.0;
  return w->clock.ElapsedS();
}

// vp_host_api.get_extension (host_extensions.cpp).
const vp_extension_header* GetExtension(const char* name, uint32_t min_version);

// Checks what the plugin returned against the world; drops and logs what cannot be executed.
void Validate(const PlannerWorld& world, const std::vector<PlannerRobot>& robots,
              const PlanValidation& v, const std::string& planner, PlanResult& result);

}  // namespace voxplan::internal
