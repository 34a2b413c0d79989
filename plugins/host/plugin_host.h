#pragma once
// Loads planner plugins (plugins/planner_api.h) and runs their plan calls.
//
//   auto planner = LoadPlanner("omt", {.config_json = "{}", .seed = 1});  // or a path to a .so
//   if (!planner.ok()) return planner.status();   // names both ABI versions on a mismatch
//   Result<PlanResult> plan = (*planner)->Plan(world, {.event = PlanEvent::kStart});
//
// A name is looked up as libvoxplan_planner_<name>.so in the search path: $VOXPLAN_PLANNER_PATH
// (colon-separated) first, then the folder the build puts planners in, or for an installed
// executable the installed planners (lib/voxplan/planners beside its bin/). The host refuses,
// with a Status and never a crash, a file it cannot dlopen, a missing entry symbol, another ABI
// version, a table of the wrong size and a failing create; and, before dlopen, a file that is
// not a whole shared object for this machine (plugins/host/elf_check.h). The plugin's output is
// validated against the world: non-finite numbers, tasks outside the bounds, in or too near an
// obstacle, in unknown space or unreachable are rejected one by one, logged in PlanResult, and
// the rest kept. A plan call slower than its budget is flagged; one slower than its hard limit
// (PlannerLimits) is given up.
//
// Supervision (plugins/host/README.md): every call into the plugin (entry, create, plan,
// destroy) runs on the planner's own thread. A crash there (SIGSEGV, SIGBUS, SIGFPE, SIGILL,
// SIGABRT) or a call past its hard limit makes the call fail with a PlannerFault; the planner
// is dead from then on (fault() says why): never called, destroyed or unloaded again.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/status.h"
#include "plugins/host/planner_world.h"
#include "plugins/planner_api.h"

namespace voxplan {

namespace internal {
class PlannerThread;  // plugins/host/planner_thread.h
}  // namespace internal

// How long the host waits for a call into the plugin before it gives the plugin up.
struct PlannerLimits {
  double budget_factor = 10.0;  // a plan call with a budget: this many budgets ...
  double min_s = 2.0;           // ... but never less than this
  double unbudgeted_s = 60.0;   // a plan call without a budget, and entry / create / destroy
  double For(double budget_s) const;
  // InvalidArgument naming the field unless factor >= 1 and both times are finite and > 0.
  Status Validate() const;
};

// A call the plugin crashed in or overran its hard limit in.
struct PlannerFault {
  enum class Kind { kCrashed, kHung };
  Kind kind = Kind::kCrashed;
  std::string call;                     // "entry", "create", "plan" or "destroy"
  uint32_t call_index = 0;              // plan: PlanRequest::call_index
  PlanEvent event = PlanEvent::kStart;  // plan: PlanRequest::event
  int signal = 0;                       // kCrashed: the signal number
  std::string signal_name;              // kCrashed: "SIGSEGV", ...
  double elapsed_s = 0.0;               // wall time until the crash, or until the host gave up
  double limit_s = 0.0;                 // the call's hard limit
  // "planner_crashed" or "planner_hung".
  const char* Terminated() const;
  // "planner greedy crashed (SIGSEGV) in plan call 3 (interval) after 0.01 s"
  std::string Describe(const std::string& planner) const;
};

struct PlannerLoadOptions {
  std::string config_json = "{}";
  uint64_t seed = 0;
  // Folders searched for a planner given by name; empty means DefaultPlannerSearchPath().
  std::vector<std::filesystem::path> search_path;
  PlannerLimits limits;
};

// $VOXPLAN_PLANNER_PATH entries, then the installed planner folder beside the running executable
// (../lib/voxplan/planners from its bin/) where that exists, else the build's planner folder.
std::vector<std::filesystem::path> DefaultPlannerSearchPath();
// Names of the libvoxplan_planner_<name>.so files in the folders, sorted, without duplicates.
std::vector<std::string> AvailablePlanners(const std::vector<std::filesystem::path>& search_path);

struct PlanRequest {
  PlanEvent event = PlanEvent::kStart;
  int32_t event_robot = -1;  // robot index the event concerns
  uint32_t call_index = 0;
  uint64_t seed = 0;
  double time_budget_s = 0.0;  // <= 0: none
  double sim_time_s = 0.0;
  PlannerTask failed_task;  // for kTaskFailed
};

struct PathPoint {
  Eigen::Vector2f position_m = Eigen::Vector2f::Zero();
  float theta_rad = 0.f;
};
struct CameraSample {
  float t_s = 0.f;
  Eigen::Vector3f position_m = Eigen::Vector3f::Zero();
  float yaw_rad = 0.f, pitch_rad = 0.f;
};

struct RobotPlan {
  TaskPolicy policy = TaskPolicy::kAppend;
  std::vector<PlannerTask> tasks;  // validated, in the plugin's order
  std::vector<PathPoint> path;     // optional dense path
  // vp.motion: driven without stopping (VP_PATH_CONTINUOUS), at these speeds (one per path
  // point, or empty for the mode's speed).
  bool path_continuous = false;
  std::vector<float> path_speed_mps;
  std::vector<CameraSample> camera_trajectory;
};

struct DebugDrawing {
  enum class Kind { kPoints, kPolyline, kLabel };
  Kind kind = Kind::kPoints;
  std::string layer;
  std::vector<Eigen::Vector3f> points;  // one for a label
  std::string text;
  uint32_t rgba = 0xffffffffu;
};

// Something of the plugin's output the host threw away: a task (task >= 0), or a path, camera
// trajectory, diagnostic or drawing (task = -1).
struct Rejection {
  int32_t robot = -1;
  int32_t task = -1;
  std::string reason;
};

struct PlanLogEntry {
  int32_t level = VP_LOG_INFO;
  std::string message;
};

struct PlanResult {
  std::vector<RobotPlan> robots;  // one per robot of the world, by index
  bool done = false;
  std::vector<std::pair<std::string, double>> diagnostics;  // in the order given
  std::vector<DebugDrawing> drawings;
  std::vector<Rejection> rejections;
  std::vector<PlanLogEntry> log;  // the plugin's messages, then the host's rejections
  double elapsed_ms = 0.0;
  bool over_budget = false;
  // vp.schedule: the run time the plugin asked to be called at; NaN when it did not ask.
  double wakeup_t_s = std::numeric_limits<double>::quiet_NaN();
};

struct PlanValidation {
  // A task needs this much clearance beyond the robot's radius.
  float clearance_margin_m = 0.f;
  float max_dwell_s = 600.f;
};

// A loaded plugin with one planner instance; destroys the instance and unloads on destruction
// (unless it faulted: then both are left alone, and a hung thread left running).
class LoadedPlanner {
 public:
  LoadedPlanner(const LoadedPlanner&) = delete;
  LoadedPlanner& operator=(const LoadedPlanner&) = delete;
  ~LoadedPlanner();

  const std::string& name() const { return name_; }
  const std::string& version() const { return version_; }
  const std::filesystem::path& path() const { return path_; }

  // One planning call. An error Status when the plugin's plan fails (with its message); the
  // output's problems are rejections inside the result instead. When the plugin crashes or
  // overruns limits().For(request.time_budget_s), an error and fault() set; every later call
  // fails at once.
  Result<PlanResult> Plan(const PlannerWorld& world, const PlanRequest& request,
                          const PlanValidation& validation = {});

  // The call that killed the planner; null while it is healthy.
  const PlannerFault* fault() const { return fault_ ? &*fault_ : nullptr; }
  const PlannerLimits& limits() const { return limits_; }

 private:
  friend Result<std::unique_ptr<LoadedPlanner>> LoadPlanner(const std::string&,
                                                            const PlannerLoadOptions&,
                                                            PlannerFault*);
  LoadedPlanner();
  // Runs `call` on the planner thread; false (and fault_ set) when it crashed or hung.
  bool Supervise(const std::function<void()>& call, double limit_s, PlannerFault fault);
  Status Negotiate(vp_planner_entry_fn entry, const std::string& label);
  Status Create(const PlannerLoadOptions& options, const std::string& label);

  void* library_ = nullptr;
  vp_planner_api api_{};
  vp_planner* instance_ = nullptr;
  std::string name_, version_;
  std::filesystem::path path_;
  PlannerLimits limits_;
  std::unique_ptr<internal::PlannerThread> thread_;
  std::optional<PlannerFault> fault_;
};

// name_or_path: a path (holds a '/' or ends in ".so") or a planner name. When the plugin
// crashes or hangs in its entry or create, the error says so and *fault (if given) is set.
Result<std::unique_ptr<LoadedPlanner>> LoadPlanner(const std::string& name_or_path,
                                                   const PlannerLoadOptions& options = {},
                                                   PlannerFault* fault = nullptr);

// The host's function table handed to every plugin (static storage).
const vp_host_api& PlannerHostApi();

}  // namespace voxplan
