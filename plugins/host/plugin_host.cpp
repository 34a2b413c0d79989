// Finding, opening and negotiating with planner plugins (Vulkan-loader style: one well-known
// symbol, a version handshake, refusal with a message instead of a crash).
#include "plugins/host/plugin_host.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <system_error>

#ifndef VOXPLAN_PLANNER_BUILD_DIR
#define VOXPLAN_PLANNER_BUILD_DIR ""
#endif

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPrefix = "libvoxplan_planner_";
constexpr const char* kSuffix = ".so";
constexpr uint32_t kErrorChars = 1024;

bool IsPath(const std::string& s) {
  return s.find('/') != std::string::npos ||
         (s.size() > 3 && s.compare(s.size() - 3, 3, kSuffix) == 0);
}

bool IsPlannerName(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

std::string Join(const std::vector<std::string>& items) {
  std::string s;
  for (const std::string& item : items) s += (s.empty() ? "" : ", ") + item;
  return s;
}

std::string DlError() {
  const char* e = dlerror();
  return e ? e : "unknown dlopen error";
}

// Closes the library unless released: every early return below unloads it.
struct LibraryGuard {
  void* handle;
  ~LibraryGuard() {
    if (handle) dlclose(handle);
  }
};

}  // namespace

std::vector<fs::path> DefaultPlannerSearchPath() {
  std::vector<fs::path> path;
  if (const char* env = std::getenv("VOXPLAN_PLANNER_PATH")) {
    std::string s = env;
    size_t begin = 0;
    while (begin <= s.size()) {
      const size_t end = std::min(s.find(':', begin), s.size());
      if (end > begin) path.emplace_back(s.substr(begin, end - begin));
      begin = end + 1;
    }
  }
  if (*VOXPLAN_PLANNER_BUILD_DIR) path.emplace_back(VOXPLAN_PLANNER_BUILD_DIR);
  return path;
}

std::vector<std::string> AvailablePlanners(const std::vector<fs::path>& search_path) {
  std::set<std::string> names;
  const std::string prefix = kPrefix, suffix = kSuffix;
  for (const fs::path& dir : search_path) {
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string file = it->path().filename().string();
      if (file.size() > prefix.size() + suffix.size() && file.starts_with(prefix) &&
          file.ends_with(suffix)) {
        names.insert(file.substr(prefix.size(), file.size() - prefix.size() - suffix.size()));
      }
    }
  }
  return {names.begin(), names.end()};
}

LoadedPlanner::~LoadedPlanner() {
  if (instance_ && api_.destroy) api_.destroy(instance_);
  if (library_) dlclose(library_);
}

Result<std::unique_ptr<LoadedPlanner>> LoadPlanner(const std::string& name_or_path,
                                                   const PlannerLoadOptions& options) {
  fs::path path;
  if (IsPath(name_or_path)) {
    path = name_or_path;
    if (!fs::exists(path)) return NotFound("planner plugin " + name_or_path + " does not exist");
  } else {
    const std::vector<fs::path> search =
        options.search_path.empty() ? DefaultPlannerSearchPath() : options.search_path;
    const std::vector<std::string> available = AvailablePlanners(search);
    if (!IsPlannerName(name_or_path) ||
        std::find(available.begin(), available.end(), name_or_path) == available.end()) {
      return NotFound("unknown planner '" + name_or_path + "'; available: " +
                      (available.empty() ? std::string("none") : Join(available)) +
                      " (set VOXPLAN_PLANNER_PATH or pass a path to a .so)");
    }
    for (const fs::path& dir : search) {
      const fs::path candidate = dir / (kPrefix + name_or_path + kSuffix);
      if (fs::exists(candidate)) {
        path = candidate;
        break;
      }
    }
  }
  const std::string label = path.string();

  dlerror();  // clear a stale message
  LibraryGuard library{dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)};
  if (!library.handle) return IoError("cannot load planner " + label + ": " + DlError());
  dlerror();
  void* symbol = dlsym(library.handle, VP_PLANNER_ENTRY_SYMBOL);
  if (!symbol) {
    return InvalidArgument("planner " + label + " has no " + VP_PLANNER_ENTRY_SYMBOL +
                           " symbol; is it a voxplan planner (built with VP_PLANNER_EXPORT)?");
  }
  vp_planner_entry_fn entry = reinterpret_cast<vp_planner_entry_fn>(symbol);

  vp_planner_api api{};
  api.struct_size = sizeof(api);
  const vp_status status = entry(VP_PLANNER_ABI_VERSION, &PlannerHostApi(), &api);
  if (api.abi_version == 0) {
    return Unsupported("plugin " + label + " did not report its planner ABI version (status " +
                       std::to_string(status) + "); this voxplan speaks ABI " +
                       std::to_string(VP_PLANNER_ABI_VERSION));
  }
  if (api.abi_version != VP_PLANNER_ABI_VERSION) {
    return Unsupported("plugin " + label + " was built for planner ABI " +
                       std::to_string(api.abi_version) + ", this voxplan speaks ABI " +
                       std::to_string(VP_PLANNER_ABI_VERSION) + "; rebuild it against this " +
                       "voxplan's plugins/planner_api.h");
  }
  if (status != VP_OK) {
    return Unsupported("plugin " + label + " refused this host (status " + std::to_string(status) +
                       (status == VP_ERROR_STRUCT_SIZE ? ": host table size mismatch)" : ")"));
  }
  if (api.struct_size != sizeof(vp_planner_api)) {
    return Unsupported("plugin " + label + " returned a planner table of " +
                       std::to_string(api.struct_size) + " bytes, this voxplan expects " +
                       std::to_string(sizeof(vp_planner_api)) + " (ABI " +
                       std::to_string(VP_PLANNER_ABI_VERSION) + ")");
  }
  if (!api.create || !api.plan || !api.destroy || !api.name) {
    return Unsupported("plugin " + label + " returned an incomplete planner table");
  }

  std::unique_ptr<LoadedPlanner> planner(new LoadedPlanner());
  planner->name_ = api.name;
  planner->version_ = api.version ? api.version : "";
  planner->path_ = path;
  planner->api_ = api;
  char error[kErrorChars] = {};
  const vp_status created = api.create(&PlannerHostApi(), options.config_json.c_str(), options.seed,
                                       &planner->instance_, error, kErrorChars);
  error[kErrorChars - 1] = '\0';  // in case the plugin forgot
  if (created != VP_OK || !planner->instance_) {
    planner->instance_ = nullptr;  // a failed create owns nothing we may destroy
    return InvalidArgument("planner " + planner->name_ + " (" + label +
                           ") could not be created (status " + std::to_string(created) +
                           "): " + (error[0] ? error : "no message"));
  }
  planner->library_ = library.handle;
  library.handle = nullptr;
  return planner;
}

}  // namespace voxplan
