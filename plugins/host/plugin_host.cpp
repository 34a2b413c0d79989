// Finding, opening and negotiating with planner plugins (Vulkan-loader style: one well-known
// symbol, a version handshake, refusal with a message instead of a crash).
#include "plugins/host/plugin_host.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <set>
#include <system_error>
#include <utility>

#include "plugins/host/elf_check.h"
#include "plugins/host/host_internal.h"
#include "plugins/host/planner_thread.h"

#ifndef VOXPLAN_PLANNER_BUILD_DIR
#define VOXPLAN_PLANNER_BUILD_DIR ""
#endif
#ifndef VOXPLAN_PLANNER_INSTALL_REL_DIR
#define VOXPLAN_PLANNER_INSTALL_REL_DIR ""
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

// A name or version string from the plugin's static storage, read at most this far.
std::string BoundedName(const char* s) { return std::string(s, strnlen(s, 256)); }

// Closes the library unless released: every early return below unloads it.
struct LibraryGuard {
  void* handle;
  ~LibraryGuard() {
    if (handle) dlclose(handle);
  }
};

// The installed planner folder beside the running executable (bin/voxplan ->
// lib/voxplan/planners), or empty when there is none: an executable in the build tree.
fs::path InstalledPlannerDir() {
  if (!*VOXPLAN_PLANNER_INSTALL_REL_DIR) return {};
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path dir = (exe.parent_path() / VOXPLAN_PLANNER_INSTALL_REL_DIR).lexically_normal();
  return fs::is_directory(dir, ec) ? dir : fs::path();
}

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
  // An installed executable never looks into the build tree it came from.
  if (fs::path installed = InstalledPlannerDir(); !installed.empty()) {
    path.push_back(std::move(installed));
  } else if (*VOXPLAN_PLANNER_BUILD_DIR) {
    path.emplace_back(VOXPLAN_PLANNER_BUILD_DIR);
  }
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

namespace {

// The file a name or path stands for.
Result<fs::path> FindPlanner(const std::string& name_or_path, const PlannerLoadOptions& options) {
  if (IsPath(name_or_path)) {
    if (!fs::exists(name_or_path))
      return NotFound("planner plugin " + name_or_path + " does not exist");
    return fs::path(name_or_path);
  }
  const std::vector<fs::path> search =
      options.search_path.empty() ? DefaultPlannerSearchPath() : options.search_path;
  const std::vector<std::string> available = AvailablePlanners(search);
  if (IsPlannerName(name_or_path) &&
      std::find(available.begin(), available.end(), name_or_path) != available.end()) {
    for (const fs::path& dir : search) {
      const fs::path candidate = dir / (kPrefix + name_or_path + kSuffix);
      if (fs::exists(candidate)) return candidate;
    }
  }
  return NotFound("unknown planner '" + name_or_path +
                  "'; available: " + (available.empty() ? std::string("none") : Join(available)) +
                  " (set VOXPLAN_PLANNER_PATH or pass a path to a .so)");
}

}  // namespace

LoadedPlanner::LoadedPlanner() = default;

// The entry call (on the planner thread) and the checks of the table it returns.
Status LoadedPlanner::Negotiate(vp_planner_entry_fn entry, const std::string& label) {
  vp_planner_api api{};
  api.struct_size = sizeof(api);
  vp_status status = VP_OK;
  vp_planner_api* out = &api;
  vp_status* status_out = &status;
  PlannerFault where;
  where.call = "entry";
  if (!Supervise(
          [entry, out, status_out] {
            *status_out = entry(VP_PLANNER_ABI_VERSION, &PlannerHostApi(), out);
          },
          limits_.unbudgeted_s, where))
    return Status(StatusCode::kInternal, fault_->Describe(label));
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
  api_ = api;
  name_ = BoundedName(api.name);
  version_ = api.version ? BoundedName(api.version) : "";
  return Status::Ok();
}

// The plugin's create (on the planner thread).
Status LoadedPlanner::Create(const PlannerLoadOptions& options, const std::string& label) {
  // On the heap: a create the host gives up on may still write the message.
  auto error = std::make_shared<std::vector<char>>(kErrorChars, '\0');
  auto created = std::make_shared<vp_status>(VP_OK);
  auto instance = std::make_shared<vp_planner*>(nullptr);
  auto config = std::make_shared<std::string>(options.config_json);
  const vp_planner_api api = api_;
  const uint64_t seed = options.seed;
  char* e = error->data();
  vp_status* c = created.get();
  vp_planner** out = instance.get();
  const char* json = config->c_str();
  PlannerFault where;
  where.call = "create";
  if (!Supervise([api, json, seed, out, e,
                  c] { *c = api.create(&PlannerHostApi(), json, seed, out, e, kErrorChars); },
                 limits_.unbudgeted_s, where)) {
    for (const std::shared_ptr<void>& kept :
         {std::shared_ptr<void>(error), std::shared_ptr<void>(created),
          std::shared_ptr<void>(instance), std::shared_ptr<void>(config)})
      internal::KeepAlive(kept);
    return Status(StatusCode::kInternal, fault_->Describe(name_ + " (" + label + ")"));
  }
  e[kErrorChars - 1] = '\0';  // in case the plugin forgot
  if (*c != VP_OK || *out == nullptr) {
    // A failed create owns nothing we may destroy.
    return InvalidArgument("planner " + name_ + " (" + label + ") could not be created (status " +
                           std::to_string(*c) + "): " + (e[0] ? e : "no message"));
  }
  instance_ = *out;
  return Status::Ok();
}

LoadedPlanner::~LoadedPlanner() {
  if (!fault_ && instance_ && api_.destroy) {
    const vp_planner_api api = api_;
    vp_planner* instance = instance_;
    PlannerFault where;
    where.call = "destroy";
    (void)Supervise([api, instance] { api.destroy(instance); }, limits_.unbudgeted_s, where);
  }
  // After a fault the plugin's code may still run (hung) or its state be anything: it stays.
  if (library_ && !fault_) dlclose(library_);
}

Result<std::unique_ptr<LoadedPlanner>> LoadPlanner(const std::string& name_or_path,
                                                   const PlannerLoadOptions& options,
                                                   PlannerFault* fault) {
  VOXPLAN_RETURN_IF_ERROR(options.limits.Validate());
  Result<fs::path> found = FindPlanner(name_or_path, options);
  if (!found.ok()) return found.status();
  const fs::path path = *found;
  const std::string label = path.string();
  VOXPLAN_RETURN_IF_ERROR(internal::CheckSharedObject(label));

  dlerror();  // clear a stale message
  // RTLD_NODELETE: dlclose drops the reference but never unmaps. The libraries a planner links
  // statically (Ceres, glog) set up state in their static initialisers and may register exit
  // handlers; unmapping them would orphan that memory (LeakSanitizer reports it) or leave a
  // handler pointing at unmapped code. Loading the same file again reuses the mapping.
  LibraryGuard library{dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE)};
  if (!library.handle) return IoError("cannot load planner " + label + ": " + DlError());
  dlerror();
  void* symbol = dlsym(library.handle, VP_PLANNER_ENTRY_SYMBOL);
  if (!symbol) {
    return InvalidArgument("planner " + label + " has no " + VP_PLANNER_ENTRY_SYMBOL +
                           " symbol; is it a voxplan planner (built with VP_PLANNER_EXPORT)?");
  }
  Result<std::unique_ptr<internal::PlannerThread>> thread = internal::PlannerThread::Start();
  if (!thread.ok()) return thread.status();
  std::unique_ptr<LoadedPlanner> planner(new LoadedPlanner());
  planner->path_ = path;
  planner->name_ = path.filename().string();  // until the plugin names itself
  planner->limits_ = options.limits;
  planner->thread_ = std::move(thread).value();
  planner->library_ = library.handle;  // from here the planner decides whether to unload
  library.handle = nullptr;
  Status negotiated = planner->Negotiate(reinterpret_cast<vp_planner_entry_fn>(symbol), label);
  if (negotiated.ok()) negotiated = planner->Create(options, label);
  if (negotiated.ok()) return planner;
  if (planner->fault_ && fault) *fault = *planner->fault_;
  return negotiated;
}

}  // namespace voxplan
