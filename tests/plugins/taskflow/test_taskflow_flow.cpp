#include <gtest/gtest.h>

#include "plugins/taskflow/algorithms/flow.h"

namespace voxplan::taskflow {
namespace {

const std::vector<int> kAll{0, 1, 2, 3};

FlowRobot Idle() { return {false, 0}; }
FlowRobot Busy(int queued) { return {true, queued}; }

TEST(TaskflowFlow, AsyncAppendsToEveryRobotWhenOneRunsDry) {
  const std::vector<FlowRobot> robots{Idle(), Busy(3), Busy(1), Busy(0)};
  for (FlowEvent e : {FlowEvent::kRobotIdle, FlowEvent::kTaskFailed, FlowEvent::kStart}) {
    const FlowDecision d = DecideFlow(e, robots, FlowPolicy::kAsync);
    EXPECT_TRUE(d.plan);
    EXPECT_EQ(d.receivers, kAll);
  }
}

TEST(TaskflowFlow, SyncPlansOnlyWhenAllRobotsAreIdle) {
  const std::vector<FlowRobot> some_busy{Idle(), Busy(2), Idle(), Idle()};
  for (FlowEvent e :
       {FlowEvent::kStart, FlowEvent::kRobotIdle, FlowEvent::kTaskFailed, FlowEvent::kInterval}) {
    const FlowDecision d = DecideFlow(e, some_busy, FlowPolicy::kSync);
    EXPECT_FALSE(d.plan);
    EXPECT_TRUE(d.receivers.empty());
  }
  const std::vector<FlowRobot> all_idle(4, Idle());
  const FlowDecision d = DecideFlow(FlowEvent::kRobotIdle, all_idle, FlowPolicy::kSync);
  EXPECT_TRUE(d.plan);
  EXPECT_EQ(d.receivers, kAll);
  // Not executing but with tasks queued is not idle.
  EXPECT_FALSE(DecideFlow(FlowEvent::kRobotIdle, {Idle(), {false, 1}}, FlowPolicy::kSync).plan);
}

TEST(TaskflowFlow, IntervalWithBusyRobotsPlansNothing) {
  const std::vector<FlowRobot> busy{Busy(1), Busy(0), Busy(4), Busy(2)};
  for (FlowPolicy p : {FlowPolicy::kAsync, FlowPolicy::kSync}) {
    const FlowDecision d = DecideFlow(FlowEvent::kInterval, busy, p);
    EXPECT_FALSE(d.plan);
    EXPECT_TRUE(d.receivers.empty());
  }
  // The watchdog: an idle robot without work, yet no idle event came.
  const FlowDecision d =
      DecideFlow(FlowEvent::kInterval, {Busy(1), Idle(), Busy(2), Busy(0)}, FlowPolicy::kAsync);
  EXPECT_TRUE(d.plan);
  EXPECT_EQ(d.receivers, kAll);
}

TEST(TaskflowFlow, NoRobotsNoPlan) {
  EXPECT_FALSE(DecideFlow(FlowEvent::kStart, {}, FlowPolicy::kAsync).plan);
  EXPECT_FALSE(DecideFlow(FlowEvent::kStart, {}, FlowPolicy::kSync).plan);
}

}  // namespace
}  // namespace voxplan::taskflow
