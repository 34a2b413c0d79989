/* A planner written in plain C99 against planner_api.h alone: it sets `done` and reports the
 * robot count. Built twice: as c_minimal, and with VP_TEST_BAD_SIZE as a plugin that claims a
 * planner table smaller than ABI 1's (the host must refuse it). */
#include <stdlib.h>
#include <string.h>

#include "plugins/planner_api.h"

struct vp_planner {
  const vp_host_api* host;
  uint64_t seed;
};

static vp_status Create(const vp_host_api* host, const char* config_json, uint64_t seed,
                        vp_planner** out, char* error, uint32_t error_size) {
  vp_planner* p;
  (void)config_json;
  (void)error;
  (void)error_size;
  p = (vp_planner*)malloc(sizeof(vp_planner));
  if (p == NULL) return VP_ERROR_PLUGIN;
  p->host = host;
  p->seed = seed;
  *out = p;
  return VP_OK;
}

static vp_status Plan(vp_planner* self, const vp_world* world, vp_plan_output* out) {
  vp_status s = self->host->add_diagnostic(out, "robots", (double)self->host->robot_count(world));
  if (s != VP_OK) return s;
  return self->host->set_done(out, 1);
}

static void Destroy(vp_planner* self) { free(self); }

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
  table.name = "c_minimal";
  table.version = "1.0.0";
  table.create = Create;
  table.plan = Plan;
  table.destroy = Destroy;
  size = out->struct_size < sizeof(table) ? out->struct_size : (uint32_t)sizeof(table);
  memcpy(out, &table, size);
#ifdef VP_TEST_BAD_SIZE
  out->struct_size = (uint32_t)(sizeof(table) - sizeof(void*)); /* as if built without destroy */
#else
  out->struct_size = size;
#endif
  return VP_OK;
}
