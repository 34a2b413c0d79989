#pragma once
// What the host's three plan-call files share: the memory behind the opaque C handles and the
// small conversions both the C table and the validation use. Not for use outside plugins/host.
#include <cmath>
#include <initializer_list>
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
  mutable std::vector<std::string> instance_labels;
  mutable std::vector<vp_instance> instances;
  mutable std::vector<std::vector<float>> buffers;  // fields, matrices, paths; never reused
  std::vector<voxplan::PlannerRobot> robots;
  std::vector<std::vector<vp_task>> queues;
};

struct vp_plan_output {
  voxplan::PlanResult* result = nullptr;
  std::string error;
  size_t debug_points = 0;
};

namespace voxplan::internal {

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

// Checks what the plugin returned against the world; drops and logs what cannot be executed.
void Validate(const PlannerWorld& world, const std::vector<PlannerRobot>& robots,
              const PlanValidation& v, const std::string& planner, PlanResult& result);

}  // namespace voxplan::internal
