// The task-flow trigger (Guo et al. 2022, G§3 L104, G§5.1) and its NoFlow ablation as a pure
// decision: whether this plan() call plans, and which robots get the new tasks appended.
#pragma once

#include <vector>

namespace voxplan::taskflow {

// VP_EVENT_* values of the planner ABI.
enum class FlowEvent { kStart = 0, kInterval = 1, kRobotIdle = 2, kTaskFailed = 3 };

enum class FlowPolicy {
  kAsync,  // the paper: plan when any robot runs dry, append to every robot
  kSync,   // NoFlow: plan only when every robot is idle
};

struct FlowRobot {
  bool executing = false;
  int queued_tasks = 0;
  // Idle: neither executing nor holding queued work.
  bool Idle() const { return !executing && queued_tasks == 0; }
};

struct FlowDecision {
  bool plan = false;
  std::vector<int> receivers;  // robots whose queues get the new tasks, ascending
};

// Async: plans on start, robot idle and task failed; interval calls only as a watchdog (some
// robot idle with nothing queued, e.g. a missed event). New tasks go to EVERY robot, so busy
// robots queue work behind their current tasks and nobody waits (G§3 L104).
// Sync: plans, on any event, only when all robots are idle; all receive. No robots: no plan.
FlowDecision DecideFlow(FlowEvent event, const std::vector<FlowRobot>& robots, FlowPolicy policy);

}  // namespace voxplan::taskflow
