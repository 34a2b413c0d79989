/* Pretends to be built for planner ABI 2: it answers the handshake with its version and
 * refuses the host, as a plugin from a newer voxplan would. */
#include "plugins/planner_api.h"

VP_PLANNER_EXPORT_SYMBOL vp_status vp_planner_entry(uint32_t host_abi_version,
                                                    const vp_host_api* host, vp_planner_api* out) {
  (void)host;
  if (out == 0 || out->struct_size < 8) return VP_ERROR_STRUCT_SIZE;
  out->abi_version = 2u;
  return host_abi_version == 2u ? VP_OK : VP_ERROR_ABI_MISMATCH;
}
