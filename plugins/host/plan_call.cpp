// One plan() call: the C handles set up over a PlannerWorld, the plugin's plan() timed, and its
// output validated into a PlanResult.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "plugins/host/host_internal.h"

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

}  // namespace

Result<PlanResult> LoadedPlanner::Plan(const PlannerWorld& world, const PlanRequest& request,
                                       const PlanValidation& validation) {
  PlanResult result;
  vp_world w;
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
    for (const PlannerTask& t : r.queue) queue.push_back(ToC(t));
    w.queues.push_back(std::move(queue));
  }
  result.robots.resize(w.robots.size());
  vp_plan_output out;
  out.result = &result;

  w.clock.Restart();  // the plugin's elapsed time counts from here
  const vp_status status = api_.plan(instance_, &w, &out);
  result.elapsed_ms = ElapsedS(&w) * 1e3;
  if (status != VP_OK) {
    return Status(StatusCode::kInternal,
                  "planner " + name_ + " failed (status " + std::to_string(status) + ", " +
                      StatusName(status) + "): " + (out.error.empty() ? "no message" : out.error));
  }
  if (request.time_budget_s > 0.0 && result.elapsed_ms > request.time_budget_s * 1e3) {
    result.over_budget = true;
    char buf[160];
    std::snprintf(buf, sizeof buf, "planner %s took %.1f ms, over its budget of %.1f ms",
                  name_.c_str(), result.elapsed_ms, request.time_budget_s * 1e3);
    result.log.push_back({VP_LOG_WARNING, buf});
  }
  try {
    Validate(world, w.robots, validation, name_, result);
  } catch (const std::exception& e) {
    return Status(StatusCode::kInternal, std::string("validating the plan failed: ") + e.what());
  }
  return result;
}

}  // namespace voxplan
