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

// ---- The registry. ----------------------------------------------------------------------------

struct Extension {
  std::string_view name;
  const vp_extension_header* table;
};

constexpr Extension kExtensions[] = {
    {VP_EXT_OBJECTS, &kObjects.header},
};

}  // namespace

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
