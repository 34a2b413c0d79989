// One plan() call: the C handles set up over a PlannerWorld, the plugin's plan() run on the
// planner thread under its hard limit and timed, and its output validated into a PlanResult.
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "plugins/host/host_internal.h"
#include "plugins/host/planner_thread.h"

namespace voxplan {
namespace {

using internal::ElapsedS;
using internal::ToC;
using internal::Validate;

const char* StatusName(vp_status s) {
  switch (s) {
    case VP_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case VP_ERROR_ABI_MISMATCH:
      return "ABI mismatch";
    case VP_ERROR_STRUCT_SIZE:
      return "struct size";
    case VP_ERROR_NOT_AVAILABLE:
      return "not available";
    case VP_ERROR_LIMIT:
      return "limit";
    case VP_ERROR_PLUGIN:
      return "plugin error";
    case VP_ERROR_INTERNAL:
      return "host error";
    default:
      return "unknown status";
  }
}

// The plugin's status, the budget check and the validation of what it returned.
Result<PlanResult> Finish(const PlannerWorld& world, const PlanValidation& validation,
                          const PlanRequest& request, const std::string& name,
                          internal::PlanCallState& state) {
  PlanResult& result = state.result;
  result.elapsed_ms = ElapsedS(&state.world) * 1e3;
  if (state.status != VP_OK) {
    const std::string& error = state.out.error;
    return Status(StatusCode::kInternal,
                  "planner " + name + " failed (status " + std::to_string(state.status) + ", " +
                      StatusName(state.status) + "): " + (error.empty() ? "no message" : error));
  }
  if (request.time_budget_s > 0.0 && result.elapsed_ms > request.time_budget_s * 1e3) {
    result.over_budget = true;
    char buf[160];
    std::snprintf(buf, sizeof buf, "planner %s took %.1f ms, over its budget of %.1f ms",
                  name.c_str(), result.elapsed_ms, request.time_budget_s * 1e3);
    result.log.push_back({VP_LOG_WARNING, buf});
  }
  try {
    Validate(world, state.world.robots, validation, name, result);
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, std::string("validating the plan failed: ") + e.what());
  }
  return std::move(result);
}

}  // namespace

Result<PlanResult> LoadedPlanner::Plan(const PlannerWorld& world, const PlanRequest& request,
                                       const PlanValidation& validation) {
  if (fault_) {
    return Status(StatusCode::kInternal,
                  "planner " + name_ + " is not called again: " + fault_->Describe(name_));
  }
  // On the heap: a plugin the host gives up on may still write here.
  auto state = std::make_shared<internal::PlanCallState>();
  PlanResult& result = state->result;
  vp_world& w = state->world;
  w.world = &world;
  w.log = &result.log;
  w.call.struct_size = sizeof(w.call);
  w.call.event = int32_t(request.event);
  w.call.event_robot = request.event_robot;
  w.call.call_index = request.call_index;
  w.call.seed = request.seed;
  w.call.time_budget_s = request.time_budget_s;
  w.call.sim_time_s = request.sim_time_s;
  w.call.failed_task = ToC(request.failed_task);
  try {
    w.robots = world.Robots();
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, std::string("world.Robots() failed: ") + e.what());
  }
  for (const PlannerRobot& r : w.robots) {
    std::vector<vp_task> queue;
    std::vector<vp_task_ext> exts;
    for (const PlannerTask& t : r.queue) {
      queue.push_back(ToC(t));
      exts.push_back(ToC(t.camera));
    }
    w.queues.push_back(std::move(queue));
    w.queue_exts.push_back(std::move(exts));
  }
  result.robots.resize(w.robots.size());
  state->out.result = &result;

  w.clock.Restart();  // the plugin's elapsed time counts from here
  internal::PlanCallState* s = state.get();
  const vp_planner_api api = api_;
  vp_planner* instance = instance_;
  PlannerFault where;
  where.call = "plan";
  where.call_index = request.call_index;
  where.event = request.event;
  if (!Supervise([s, api, instance] { s->status = api.plan(instance, &s->world, &s->out); },
                 limits_.For(request.time_budget_s), where)) {
    // A crashed call is over; a hung one may still run: it gets no more of the world.
    internal::Revoke(w, fault_->kind == PlannerFault::Kind::kHung ? 1.0 : 0.0);
    internal::KeepAlive(std::move(state));
    return Status(StatusCode::kInternal, fault_->Describe(name_));
  }
  return Finish(world, validation, request, name_, *state);
}

}  // namespace voxplan
