/* A planner built against the frozen ABI 1.0 header (abi1_0/planner_api.h, a byte copy of
 * plugins/planner_api.h before 1.1 appended to it): the host must keep loading it, give it the
 * 1.0 prefix of every grown struct and run its plans. It reads robot 0 and its reconstructor
 * mode, reports the sizes the host wrote back, and sends robot 0 one task where it stands. */
#include <string.h>

#include "abi1_0/planner_api.h"

struct vp_planner {
  const vp_host_api* host;
};

static struct vp_planner g_planner;

static vp_status Create(const vp_host_api* host, const char* config_json, uint64_t seed,
                        vp_planner** out, char* error, uint32_t error_size) {
  (void)config_json;
  (void)seed;
  (void)error;
  (void)error_size;
  g_planner.host = host;
  *out = &g_planner;
  return VP_OK;
}

static vp_status Plan(vp_planner* self, const vp_world* world, vp_plan_output* out) {
  const vp_host_api* h = self->host;
  vp_robot robot;
  vp_mode_params mode;
  vp_task task;
  vp_status s;
  memset(&robot, 0, sizeof(robot));
  robot.struct_size = sizeof(robot);
  if ((s = h->get_robot(world, 0, &robot)) != VP_OK) return s;
  memset(&mode, 0, sizeof(mode));
  mode.struct_size = sizeof(mode);
  if ((s = h->get_robot_mode(world, 0, VP_MODE_RECONSTRUCTOR, &mode)) != VP_OK) return s;
  h->add_diagnostic(out, "host_table_size", (double)h->struct_size);
  h->add_diagnostic(out, "robot_size_asked", (double)sizeof(robot));
  h->add_diagnostic(out, "robot_size_written", (double)robot.struct_size);
  h->add_diagnostic(out, "mode_size_asked", (double)sizeof(mode));
  h->add_diagnostic(out, "mode_size_written", (double)mode.struct_size);
  h->add_diagnostic(out, "robot0_x", robot.x_m);
  h->add_diagnostic(out, "robot0_pitch_rate", robot.camera_pitch_rate_radps);
  h->add_diagnostic(out, "reconstructor_cy", mode.cy);
  memset(&task, 0, sizeof(task));
  task.x_m = robot.x_m;
  task.y_m = robot.y_m;
  task.theta_rad = robot.theta_rad;
  task.dwell_s = 1.f;
  task.mode = VP_MODE_EXPLORER;
  task.tag = 7;
  if ((s = h->add_task(out, 0, &task)) != VP_OK) return s;
  return h->set_done(out, 0);
}

static void Destroy(vp_planner* self) { (void)self; }

VP_PLANNER_EXPORT_SYMBOL vp_status vp_planner_entry(uint32_t host_abi_version,
                                                    const vp_host_api* host, vp_planner_api* out) {
  vp_planner_api table;
  uint32_t size;
  if (out == NULL || out->struct_size < 8) return VP_ERROR_STRUCT_SIZE;
  out->abi_version = VP_PLANNER_ABI_VERSION;
  if (host_abi_version != VP_PLANNER_ABI_VERSION) return VP_ERROR_ABI_MISMATCH;
  if (host == NULL || host->struct_size < sizeof(vp_host_api)) return VP_ERROR_STRUCT_SIZE;
  memset(&table, 0, sizeof(table));
  table.struct_size = sizeof(table);
  table.abi_version = VP_PLANNER_ABI_VERSION;
  table.name = "abi1_0";
  table.version = "1.0.0";
  table.create = Create;
  table.plan = Plan;
  table.destroy = Destroy;
  size = out->struct_size < sizeof(table) ? out->struct_size : (uint32_t)sizeof(table);
  memcpy(out, &table, size);
  out->struct_size = size;
  return VP_OK;
}
