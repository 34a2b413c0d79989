#include "plugins/taskflow/algorithms/flow.h"

#include <algorithm>

namespace voxplan::taskflow {

FlowDecision DecideFlow(FlowEvent event, const std::vector<FlowRobot>& robots, FlowPolicy policy) {
  FlowDecision decision;
  if (robots.empty()) return decision;
  const bool any_idle =
      std::any_of(robots.begin(), robots.end(), [](const FlowRobot& r) { return r.Idle(); });
  const bool all_idle =
      std::all_of(robots.begin(), robots.end(), [](const FlowRobot& r) { return r.Idle(); });
  if (policy == FlowPolicy::kSync) {
    decision.plan = all_idle;
  } else {
    switch (event) {
      case FlowEvent::kStart:
      case FlowEvent::kRobotIdle:
      case FlowEvent::kTaskFailed:
        decision.plan = true;
        break;
      case FlowEvent::kInterval:
        decision.plan = any_idle;
        break;
    }
  }
  if (decision.plan)
    for (int r = 0; r < static_cast<int>(robots.size()); ++r) decision.receivers.push_back(r);
  return decision;
}

}  // namespace voxplan::taskflow
