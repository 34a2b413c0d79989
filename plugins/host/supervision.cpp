// What the host does when a plugin crashes or hangs (plugin_host.h, "Supervision"): the hard
// limits, the fault record, and the memory a given-up plugin may still touch.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

#include "core/stopwatch.h"
#include "plugins/host/host_internal.h"
#include "plugins/host/planner_thread.h"

namespace voxplan {

double PlannerLimits::For(double budget_s) const {
  return budget_s > 0.0 ? std::max(budget_factor * budget_s, min_s) : unbudgeted_s;
}

Status PlannerLimits::Validate() const {
  if (!(budget_factor >= 1.0) || !std::isfinite(budget_factor))
    return InvalidArgument("planner hard limit: the budget factor must be a number >= 1");
  if (!(min_s > 0.0) || !std::isfinite(min_s))
    return InvalidArgument("planner hard limit: the minimum must be a number of seconds > 0");
  if (!(unbudgeted_s > 0.0) || !std::isfinite(unbudgeted_s))
    return InvalidArgument(
        "planner hard limit: the limit without a budget must be a number of "
        "seconds > 0");
  return Status::Ok();
}

const char* PlannerFault::Terminated() const {
  return kind == Kind::kCrashed ? "planner_crashed" : "planner_hung";
}

std::string PlannerFault::Describe(const std::string& planner) const {
  static const char* const kEvents[] = {"start", "interval", "robot_idle", "task_failed"};
  const int e = int(event);
  std::string where = call;
  if (call == "plan")
    where += " call " + std::to_string(call_index) + " (" +
             (e >= 0 && e < 4 ? kEvents[e] : "unknown") + ")";
  char times[96];
  if (kind == Kind::kCrashed) {
    std::snprintf(times, sizeof times, " after %.3f s", elapsed_s);
    return "planner " + planner + " crashed (" + signal_name + ") in " + where + times;
  }
  std::snprintf(times, sizeof times, ": no return within its hard limit of %.3f s", limit_s);
  return "planner " + planner + " hung in " + where + times;
}

bool LoadedPlanner::Supervise(const std::function<void()>& call, double limit_s,
                              PlannerFault fault) {
  const internal::CallOutcome outcome = thread_->Run(call, limit_s);
  if (outcome.kind == internal::CallOutcome::Kind::kReturned) return true;
  fault.kind = outcome.kind == internal::CallOutcome::Kind::kCrashed ? PlannerFault::Kind::kCrashed
                                                                     : PlannerFault::Kind::kHung;
  fault.signal = outcome.signal;
  if (outcome.signal != 0) fault.signal_name = internal::SignalName(outcome.signal);
  fault.elapsed_s = outcome.elapsed_s;
  fault.limit_s = limit_s;
  fault_ = fault;
  return false;
}

namespace internal {

void Revoke(const vp_world& w, double wait_s) {
  w.gate.fetch_sub(kRevoked);
  const Stopwatch clock;
  while (w.gate.load() != -kRevoked && clock.ElapsedS() < wait_s)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void KeepAlive(std::shared_ptr<void> memory) {
  static std::mutex mutex;
  static auto* kept = new std::vector<std::shared_ptr<void>>();  // never destroyed
  const std::lock_guard lock(mutex);
  kept->push_back(std::move(memory));
}

}  // namespace internal
}  // namespace voxplan
