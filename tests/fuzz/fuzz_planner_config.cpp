// The planners' JSON config (plugins/common/world_input.h JsonOptions, each planner's keys),
// through the planner C ABI exactly as the host calls it: vp_planner_entry, then create() with
// the config text. The first byte picks omt, greedy or voronoi. The three planners are linked in
// (tests/fuzz/CMakeLists.txt renames each one's entry symbol), not dlopened, so the fuzzer sees
// their coverage. create() must succeed or fail with a status and a message; never crash.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "plugins/planner_api.h"

extern "C" {
vp_status vp_planner_entry_omt(uint32_t, const vp_host_api*, vp_planner_api*);
vp_status vp_planner_entry_greedy(uint32_t, const vp_host_api*, vp_planner_api*);
vp_status vp_planner_entry_voronoi(uint32_t, const vp_host_api*, vp_planner_api*);
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const vp_planner_entry_fn kEntries[] = {vp_planner_entry_omt, vp_planner_entry_greedy,
                                                 vp_planner_entry_voronoi};
  // create() reads no host function; a zeroed table of the right size and version is enough.
  vp_host_api host{};
  host.struct_size = sizeof(host);
  host.abi_version = VP_PLANNER_ABI_VERSION;
  vp_planner_api api{};
  api.struct_size = sizeof(api);
  if (kEntries[data[0] % 3](VP_PLANNER_ABI_VERSION, &host, &api) != VP_OK) std::abort();
  const std::string config(reinterpret_cast<const char*>(data + 1), size - 1);
  vp_planner* planner = nullptr;
  char error[512];
  std::memset(error, 'x', sizeof(error));
  const vp_status status = api.create(&host, config.c_str(), 1, &planner, error, sizeof(error));
  if (status == VP_OK) {
    if (planner == nullptr) std::abort();
    api.destroy(planner);
  } else if (planner != nullptr || std::memchr(error, '\0', sizeof(error)) == nullptr ||
             error[0] == '\0') {
    std::abort();  // a refusal leaves no planner and says why
  }
  return 0;
}
