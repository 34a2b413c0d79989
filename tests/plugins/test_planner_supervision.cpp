// Supervised planners (plugins/host/planner_thread.h): a plugin that crashes (NULL write, abort,
// division by zero, stack overflow) or never returns, in plan or in create, is reported as
// crashed / hung with the call that did it, is never called again, and leaves the host usable;
// a hung plugin loses the world it was shown; faults outside a plugin call keep their default.
#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>

#include "core/stopwatch.h"
#include "plugins/host/plugin_host.h"
#include "tests/plugins/fake_world.h"

namespace voxplan {
namespace {

const std::filesystem::path kDir = VOXPLAN_TEST_PLANNER_DIR;

PlannerLoadOptions Options(const std::string& config, PlannerLimits limits = {}) {
  PlannerLoadOptions o;
  o.config_json = config;
  o.search_path = {kDir};
  o.limits = limits;
  return o;
}

PlanRequest Request(PlanEvent event, uint32_t call_index, double budget_s = 0.0) {
  PlanRequest r;
  r.event = event;
  r.call_index = call_index;
  r.time_budget_s = budget_s;
  return r;
}

PlannerLimits Limits(double factor, double min_s, double unbudgeted_s) {
  PlannerLimits l;
  l.budget_factor = factor;
  l.min_s = min_s;
  l.unbudgeted_s = unbudgeted_s;
  return l;
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// A fake world that counts the map-info queries reaching it.
class CountingWorld : public test::FakeWorld {
 public:
  PlannerMapInfo MapInfo() const override {
    ++queries;
    return test::FakeWorld::MapInfo();
  }
  mutable std::atomic<int> queries{0};
};

// After a fault the host still loads and runs a good planner.
void ExpectHostUsable(const PlannerWorld& world) {
  auto good = LoadPlanner("minimal", Options("{}"));
  ASSERT_TRUE(good.ok()) << good.status().message();
  auto plan = (*good)->Plan(world, {});
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  EXPECT_EQ(plan->robots[0].tasks.size(), 1u);
}

// Plans calls 0 .. call; all but the last return, the last crashes with `signal`.
void ExpectCrashOnCall(const std::string& fault, uint32_t call, int signal, const char* name) {
  const test::FakeWorld world;
  auto planner = LoadPlanner(
      "faulty", Options(R"({"fault": ")" + fault + R"(", "call": )" + std::to_string(call) + "}"));
  ASSERT_TRUE(planner.ok()) << planner.status().message();
  for (uint32_t k = 0; k < call; ++k) {
    auto ok = (*planner)->Plan(world, Request(PlanEvent::kInterval, k));
    ASSERT_TRUE(ok.ok()) << ok.status().message();
  }
  EXPECT_EQ((*planner)->fault(), nullptr);
  auto crashed = (*planner)->Plan(world, Request(PlanEvent::kRobotIdle, call));
  ASSERT_FALSE(crashed.ok());
  EXPECT_TRUE(Contains(crashed.status().message(), std::string("planner faulty crashed (") + name +
                                                       ") in plan call " + std::to_string(call) +
                                                       " (robot_idle)"))
      << crashed.status().message();
  const PlannerFault* f = (*planner)->fault();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->kind, PlannerFault::Kind::kCrashed);
  EXPECT_STREQ(f->Terminated(), "planner_crashed");
  EXPECT_EQ(f->call, "plan");
  EXPECT_EQ(f->call_index, call);
  EXPECT_EQ(f->event, PlanEvent::kRobotIdle);
  EXPECT_EQ(f->signal, signal);
  EXPECT_EQ(f->signal_name, name);
  // Dead from now on: refused without calling it (a call would crash again).
  auto again = (*planner)->Plan(world, Request(PlanEvent::kStart, call));
  ASSERT_FALSE(again.ok());
  EXPECT_TRUE(Contains(again.status().message(), "is not called again"))
      << again.status().message();
  planner->reset();  // neither destroyed nor unloaded: no crash here either
  ExpectHostUsable(world);
}

TEST(PlannerSupervision, NullWriteInPlanOnCallKIsReportedAsACrash) {
  ExpectCrashOnCall("null", 2, SIGSEGV, "SIGSEGV");
}

TEST(PlannerSupervision, AbortInPlanIsReportedAsACrash) {
  ExpectCrashOnCall("abort", 0, SIGABRT, "SIGABRT");
}

#if defined(__x86_64__)  // integer division by zero traps on x86 only
TEST(PlannerSupervision, DivisionByZeroInPlanIsReportedAsACrash) {
  ExpectCrashOnCall("fpe", 1, SIGFPE, "SIGFPE");
}
#endif

TEST(PlannerSupervision, StackOverflowInPlanIsCaughtOnTheAlternateStack) {
  ExpectCrashOnCall("stack", 0, SIGSEGV, "SIGSEGV");
}

TEST(PlannerSupervision, CrashInCreateIsReportedWithTheCall) {
  PlannerFault fault;
  auto planner = LoadPlanner("faulty", Options(R"({"fault": "null", "in": "create"})"), &fault);
  ASSERT_FALSE(planner.ok());
  EXPECT_TRUE(Contains(planner.status().message(), "planner faulty ("))
      << planner.status().message();
  EXPECT_TRUE(Contains(planner.status().message(), "crashed (SIGSEGV) in create"))
      << planner.status().message();
  EXPECT_EQ(fault.kind, PlannerFault::Kind::kCrashed);
  EXPECT_EQ(fault.call, "create");
  EXPECT_EQ(fault.signal, SIGSEGV);
  ExpectHostUsable(test::FakeWorld());
}

TEST(PlannerSupervision, PlanPastItsHardLimitIsGivenUp) {
  const test::FakeWorld world;
  auto planner =
      LoadPlanner("faulty", Options(R"({"fault": "loop", "call": 1})", Limits(4.0, 0.3, 60.0)));
  ASSERT_TRUE(planner.ok()) << planner.status().message();
  ASSERT_TRUE((*planner)->Plan(world, Request(PlanEvent::kStart, 0, 0.05)).ok());
  const Stopwatch clock;
  auto hung = (*planner)->Plan(world, Request(PlanEvent::kInterval, 1, 0.05));
  const double waited_s = clock.ElapsedS();
  ASSERT_FALSE(hung.ok());
  EXPECT_GE(waited_s, 0.3);  // max(4 x 0.05, 0.3)
  EXPECT_LT(waited_s, 1.5);
  EXPECT_TRUE(Contains(hung.status().message(),
                       "planner faulty hung in plan call 1 (interval): no return within its hard "
                       "limit of 0.300 s"))
      << hung.status().message();
  const PlannerFault* f = (*planner)->fault();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->kind, PlannerFault::Kind::kHung);
  EXPECT_STREQ(f->Terminated(), "planner_hung");
  EXPECT_EQ(f->call_index, 1u);
  EXPECT_DOUBLE_EQ(f->limit_s, 0.3);
  EXPECT_GE(f->elapsed_s, 0.3);
  EXPECT_FALSE((*planner)->Plan(world, Request(PlanEvent::kInterval, 2)).ok());
  planner->reset();  // returns at once: the spinning thread is left alone
  ExpectHostUsable(world);
}

TEST(PlannerSupervision, HangInCreateIsGivenUp) {
  PlannerFault fault;
  auto planner = LoadPlanner(
      "faulty", Options(R"({"fault": "loop", "in": "create"})", Limits(10, 2, 0.2)), &fault);
  ASSERT_FALSE(planner.ok());
  EXPECT_TRUE(Contains(planner.status().message(), "hung in create")) << planner.status().message();
  EXPECT_EQ(fault.kind, PlannerFault::Kind::kHung);
  EXPECT_EQ(fault.call, "create");
  ExpectHostUsable(test::FakeWorld());
}

TEST(PlannerSupervision, AHungPlannerNoLongerReachesTheWorld) {
  auto world = std::make_unique<CountingWorld>();
  auto planner = LoadPlanner("faulty", Options(R"({"fault": "query"})", Limits(10, 0.2, 60)));
  ASSERT_TRUE(planner.ok()) << planner.status().message();
  ASSERT_FALSE((*planner)->Plan(*world, Request(PlanEvent::kStart, 0, 0.01)).ok());
  ASSERT_NE((*planner)->fault(), nullptr);
  const int seen = world->queries.load();
  EXPECT_GT(seen, 0);  // it was asking until the host gave it up
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(world->queries.load(), seen);  // still spinning, but refused
  world.reset();                           // the world may go: the plugin cannot touch it
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

TEST(PlannerSupervision, HardLimitsAreAMultipleOfTheBudgetWithAFloor) {
  const PlannerLimits limits;
  EXPECT_DOUBLE_EQ(limits.For(1.0), 10.0);
  EXPECT_DOUBLE_EQ(limits.For(0.05), 2.0);
  EXPECT_DOUBLE_EQ(limits.For(0.0), 60.0);
  for (const PlannerLimits& bad :
       {Limits(0.5, 2, 60), Limits(10, 0, 60), Limits(10, 2, -1), Limits(NAN, 2, 60)}) {
    EXPECT_FALSE(bad.Validate().ok());
    auto refused = LoadPlanner("minimal", Options("{}", bad));
    ASSERT_FALSE(refused.ok());
    EXPECT_TRUE(Contains(refused.status().message(), "planner hard limit"));
  }
}

// The handlers only catch faults of a plugin call on its thread: elsewhere a fault still kills
// the process by its signal (a death test: the child process dies, not this one).
TEST(PlannerSupervisionDeathTest, FaultsOutsideAPluginCallKeepTheirDefault) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto planner = LoadPlanner("minimal", Options("{}"));  // installs the handlers
  ASSERT_TRUE(planner.ok());
  EXPECT_EXIT(raise(SIGSEGV), testing::KilledBySignal(SIGSEGV), "");
  EXPECT_EXIT(std::abort(), testing::KilledBySignal(SIGABRT), "");
  EXPECT_EXIT(std::thread([] { raise(SIGBUS); }).join(), testing::KilledBySignal(SIGBUS), "");
}

}  // namespace
}  // namespace voxplan
