#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "plugins/taskflow/algorithms/assignment.h"

namespace voxplan::taskflow {
namespace {

constexpr double kTol = 1e-9;
constexpr int kBalancedMax = 3;  // brief: 8 tasks, 4 robots, λ_c large → at most ~3 each

using E = TaskType;

// Euclidean distances over [robots' T^end..., tasks...], as a stand-in for the host's
// geodesic matrix in an empty room.
AssignmentInput Problem(const std::vector<AssignRobot>& robots,
                        const std::vector<AssignTask>& tasks) {
  AssignmentInput in;
  in.robots = robots;
  in.tasks = tasks;
  std::vector<Eigen::Vector2d> p;
  for (const AssignRobot& r : robots) p.push_back(r.end_xy_m);
  for (const AssignTask& t : tasks) p.push_back(t.xy_m);
  const int n = static_cast<int>(p.size());
  in.distance = omt::DistanceMatrix(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) in.distance(a, b) = (p[a] - p[b]).norm();
  return in;
}

AssignRobot Robot(double x, double y, Mode mode = Mode::kExplorer, int rest = 0) {
  return {{x, y}, rest, mode};
}

AssignmentInput RandomProblem(std::uint64_t seed, int robots, int exp_tasks, int rec_tasks) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(0.0, 12.0);
  std::vector<AssignRobot> r;
  for (int i = 0; i < robots; ++i)
    r.push_back(Robot(coord(rng), coord(rng), i % 2 ? Mode::kReconstructor : Mode::kExplorer,
                      static_cast<int>(rng() % 3)));
  std::vector<AssignTask> t;
  for (int i = 0; i < exp_tasks + rec_tasks; ++i)
    t.push_back({{coord(rng), coord(rng)}, i < exp_tasks ? E::kExploration : E::kReconstruction});
  return Problem(r, t);
}

// Every task in exactly one sequence or in dropped; unless forced, sequences of one type
// matching the robot's mode.
void ExpectConsistent(const AssignmentInput& in, const AssignmentResult& res, bool forced) {
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  ASSERT_EQ(res.robots.size(), in.robots.size());
  std::vector<int> seen(in.tasks.size(), 0);
  for (const RobotPlan& plan : res.robots) {
    for (int k : plan.tasks) {
      ++seen[static_cast<std::size_t>(k)];
      // One mode forced on all: no switching to avoid, so sequences may mix types.
      if (!forced) {
        EXPECT_EQ(ModeOf(in.tasks[k].type), plan.mode);
        EXPECT_EQ(in.tasks[k].type, in.tasks[plan.tasks.front()].type);
      }
    }
  }
  for (int k : res.dropped) ++seen[static_cast<std::size_t>(k)];
  for (int s : seen) EXPECT_EQ(s, 1);
}

int CountMode(const AssignmentResult& res, Mode m) {
  return static_cast<int>(std::count_if(res.robots.begin(), res.robots.end(),
                                        [m](const RobotPlan& p) { return p.mode == m; }));
}

TEST(TaskflowAssignment, BothTypesGiveEachModeARobotAndOneTypePerSequence) {
  AssignmentParams params;
  params.energy_cut = false;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    // Skewed counts: the proportion alone would give the minority type no robot.
    const AssignmentInput in = RandomProblem(seed, 4, 9, 1);
    const AssignmentResult res = AssignTasks(in, params);
    ExpectConsistent(in, res, false);
    EXPECT_GE(CountMode(res, Mode::kExplorer), 1);
    EXPECT_GE(CountMode(res, Mode::kReconstructor), 1);
    EXPECT_TRUE(res.dropped.empty());
    EXPECT_GT(res.sa_iterations, 0);
  }
}

TEST(TaskflowAssignment, OneTaskTypeSendsEveryRobotToItsMode) {
  const AssignmentInput in = RandomProblem(3, 4, 0, 6);
  const AssignmentResult res = AssignTasks(in, AssignmentParams{});
  ExpectConsistent(in, res, false);
  EXPECT_EQ(CountMode(res, Mode::kReconstructor), 4);
  EXPECT_EQ(res.sa_iterations, 0);  // nothing for the annealing to move
}

TEST(TaskflowAssignment, InitialModesKeepCurrentModesWhenTheProportionAllows) {
  AssignmentInput in = RandomProblem(5, 4, 4, 4);  // robots alternate E, R, E, R
  EXPECT_EQ(InitialModes(in, AssignmentParams{}),
            (std::vector<Mode>{Mode::kExplorer, Mode::kReconstructor, Mode::kExplorer,
                               Mode::kReconstructor}));
  // 6 : 2 needs three explorers: one reconstructor switches, the one nearest an exp. task.
  in = Problem({Robot(0, 0), Robot(10, 0, Mode::kReconstructor), Robot(0, 10),
                Robot(20, 0, Mode::kReconstructor)},
               {{{11, 0}, E::kExploration},
                {{12, 0}, E::kExploration},
                {{1, 0}, E::kExploration},
                {{0, 11}, E::kExploration},
                {{0, 12}, E::kExploration},
                {{2, 0}, E::kExploration},
                {{21, 0}, E::kReconstruction},
                {{22, 0}, E::kReconstruction}});
  const std::vector<Mode> modes = InitialModes(in, AssignmentParams{});
  EXPECT_EQ(modes, (std::vector<Mode>{Mode::kExplorer, Mode::kExplorer, Mode::kExplorer,
                                      Mode::kReconstructor}));
}

TEST(TaskflowAssignment, CapacityTermBalancesTaskCounts) {
  std::vector<AssignTask> tasks;
  for (int i = 0; i < 8; ++i)  // one tight cluster next to robot 0
    tasks.push_back({{0.3 * (i % 4), 0.3 * (i / 4) + 0.5}, E::kExploration});
  const AssignmentInput in = Problem({Robot(0, 0), Robot(6, 0), Robot(0, 6), Robot(6, 6)}, tasks);
  AssignmentParams params;
  params.energy_cut = false;
  params.lambda_c = 10.0;
  const AssignmentResult balanced = AssignTasks(in, params);
  ExpectConsistent(in, balanced, false);
  for (const RobotPlan& p : balanced.robots)
    EXPECT_LE(static_cast<int>(p.tasks.size()), kBalancedMax);
  params.lambda_c = 0.0;
  const AssignmentResult greedy = AssignTasks(in, params);
  ExpectConsistent(in, greedy, false);
  EXPECT_EQ(greedy.robots[0].tasks.size(), 8u);
  EXPECT_LT(greedy.energy_d, balanced.energy_d);
  EXPECT_GT(greedy.energy_c, balanced.energy_c);
}

TEST(TaskflowAssignment, CapacityCountsUnfinishedQueues) {
  // Robot 0 still has 6 queued tasks: the 4 new ones go to the idle robot next to it.
  std::vector<AssignTask> tasks;
  for (int i = 0; i < 4; ++i) tasks.push_back({{0.3 * i, 0.5}, E::kExploration});
  const AssignmentInput in = Problem({Robot(0, 0, Mode::kExplorer, 6), Robot(1, 0)}, tasks);
  const AssignmentResult res = AssignTasks(in, AssignmentParams{});
  ExpectConsistent(in, res, false);
  EXPECT_TRUE(res.robots[0].tasks.empty());
  EXPECT_EQ(res.robots[1].tasks.size(), 4u);
}

TEST(TaskflowAssignment, FixedSplitIsHonoured) {
  for (int explorers = 1; explorers <= 3; ++explorers) {
    const AssignmentInput in = RandomProblem(7, 4, 1, 7);
    AssignmentParams params;
    params.mode_policy = ModePolicy::kFixed;
    params.fixed_explorers = explorers;
    const AssignmentResult res = AssignTasks(in, params);
    ExpectConsistent(in, res, false);
    for (int r = 0; r < 4; ++r)
      EXPECT_EQ(res.robots[r].mode, r < explorers ? Mode::kExplorer : Mode::kReconstructor);
    EXPECT_EQ(res.sa_iterations, 0);
  }
}

TEST(TaskflowAssignment, ForcedModeRunsBothTaskTypesInOneMode) {
  for (ModePolicy policy : {ModePolicy::kForceExplorer, ModePolicy::kForceReconstructor}) {
    const AssignmentInput in = RandomProblem(9, 4, 5, 5);
    AssignmentParams params;
    params.mode_policy = policy;
    params.energy_cut = false;
    const AssignmentResult res = AssignTasks(in, params);
    ExpectConsistent(in, res, true);
    const Mode m = policy == ModePolicy::kForceExplorer ? Mode::kExplorer : Mode::kReconstructor;
    EXPECT_EQ(CountMode(res, m), 4);
    EXPECT_TRUE(res.dropped.empty());
  }
}

TEST(TaskflowAssignment, EnergyCutDropsTheFirstLongHopAndItsSuccessorsFromIndexTwo) {
  // A line: node 0 is the start, then nodes 1..4 at x = 20, 21, 40, 41.
  const std::vector<double> x{0, 20, 21, 40, 41};
  omt::DistanceMatrix d(5, 5);
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b) d(a, b) = std::abs(x[a] - x[b]);
  // The 20 m first hop is never checked; 21 → 40 is.
  EXPECT_EQ(EnergyCutPosition(d, 0, {1, 2, 3, 4}, 8.0, 2), 2u);
  EXPECT_EQ(EnergyCutPosition(d, 0, {1, 2}, 8.0, 2), 2u);  // nothing cut
  EXPECT_EQ(EnergyCutPosition(d, 0, {1, 2}, 8.0, 1), 0u);  // checked from the first task
  EXPECT_EQ(EnergyCutPosition(d, 0, {1, 2, 3, 4}, 30.0, 2), 4u);

  // End to end: one explorer, tasks at 1, 2, 20, 21 m: the sequence keeps 1, 2.
  const AssignmentInput in = Problem({Robot(0, 0)}, {{{1, 0}, E::kExploration},
                                                     {{20, 0}, E::kExploration},
                                                     {{2, 0}, E::kExploration},
                                                     {{21, 0}, E::kExploration}});
  const AssignmentResult res = AssignTasks(in, AssignmentParams{});
  ExpectConsistent(in, res, false);
  EXPECT_EQ(res.robots[0].tasks, (std::vector<int>{0, 2}));
  EXPECT_EQ(res.dropped, (std::vector<int>{1, 3}));
  EXPECT_NEAR(res.robots[0].path_m, 2.0, kTol);
  AssignmentParams off;
  off.energy_cut = false;
  EXPECT_EQ(AssignTasks(in, off).robots[0].tasks, (std::vector<int>{0, 2, 1, 3}));
  // A far first task alone is kept: the robot has nothing nearer to do.
  const AssignmentInput far =
      Problem({Robot(0, 0)}, {{{20, 0}, E::kExploration}, {{21, 0}, E::kExploration}});
  EXPECT_EQ(AssignTasks(far, AssignmentParams{}).robots[0].tasks, (std::vector<int>{0, 1}));
}

TEST(TaskflowAssignment, UnreachableTasksAreDropped) {
  AssignmentInput in = Problem({Robot(0, 0), Robot(5, 0, Mode::kReconstructor)},
                               {{{1, 0}, E::kExploration}, {{6, 0}, E::kReconstruction}});
  for (int r = 0; r < 2; ++r) {  // task 1 (node 3) is out of reach
    in.distance(r, 3) = std::numeric_limits<double>::infinity();
    in.distance(3, r) = std::numeric_limits<double>::infinity();
  }
  in.distance(2, 3) = in.distance(3, 2) = std::numeric_limits<double>::infinity();
  const AssignmentResult res = AssignTasks(in, AssignmentParams{});
  ExpectConsistent(in, res, false);
  EXPECT_EQ(res.dropped, (std::vector<int>{1}));
}

TEST(TaskflowAssignment, DeterministicForASeed) {
  const AssignmentInput in = RandomProblem(11, 4, 7, 6);
  AssignmentParams params;
  params.seed = 42;
  const AssignmentResult a = AssignTasks(in, params);
  const AssignmentResult b = AssignTasks(in, params);
  ASSERT_EQ(a.robots.size(), b.robots.size());
  for (std::size_t r = 0; r < a.robots.size(); ++r) {
    EXPECT_EQ(a.robots[r].mode, b.robots[r].mode);
    EXPECT_EQ(a.robots[r].tasks, b.robots[r].tasks);
  }
  EXPECT_EQ(a.dropped, b.dropped);
  EXPECT_EQ(a.energy, b.energy);
  EXPECT_EQ(a.sa_iterations, b.sa_iterations);
  EXPECT_EQ(a.mode_changes, b.mode_changes);
}

TEST(TaskflowAssignment, AnnealingNeverEndsAboveTheInitialClustering) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const AssignmentInput in = RandomProblem(seed, 4, 6, 6);
    const AssignmentParams params;
    const Clustering initial = ClusterTasks(in, InitialModes(in, params), params);
    const AssignmentResult res = AssignTasks(in, params);
    EXPECT_LE(res.energy, initial.energy + kTol);
    EXPECT_NEAR(res.energy, res.energy_d + params.lambda_c * res.energy_c, 1e-6);
  }
}

TEST(TaskflowAssignment, DeadlineStopsTheAnnealing) {
  const AssignmentInput in = RandomProblem(2, 4, 6, 6);
  AssignmentParams params;
  int calls = 0;
  params.out_of_time = [&calls] { return ++calls > 3; };
  EXPECT_EQ(AssignTasks(in, params).sa_iterations, 3);
}

TEST(TaskflowAssignment, RejectsMismatchedMatrix) {
  AssignmentInput in = RandomProblem(1, 2, 2, 2);
  in.distance = omt::DistanceMatrix(3, 3);
  const AssignmentResult res = AssignTasks(in, AssignmentParams{});
  EXPECT_FALSE(res.status.ok());
  EXPECT_TRUE(res.robots.empty());
}

}  // namespace
}  // namespace voxplan::taskflow
