#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plugins/omt/algorithms/assignment.h"

namespace voxplan::omt {
namespace {

// Lloyd + relaxation + polish may stop in a local optimum of eq. 4; on these tiny random
// instances it stays within this fraction of the brute-force optimum (worst seen 12.8%)...
constexpr double kLloydOptimalityMargin = 0.15;
// ...and matches it on most of them (56 of 60 seen).
constexpr double kMinExactFraction = 0.85;

AssignmentProblem EuclideanProblem(const std::vector<Eigen::Vector2d>& robots,
                                   const std::vector<Eigen::Vector2d>& tasks) {
  AssignmentProblem p;
  p.num_robots = static_cast<int>(robots.size());
  p.num_tasks = static_cast<int>(tasks.size());
  p.task_task = DistanceMatrix(p.num_tasks, p.num_tasks);
  p.robot_task = DistanceMatrix(p.num_robots, p.num_tasks);
  for (int a = 0; a < p.num_tasks; ++a)
    for (int b = 0; b < p.num_tasks; ++b) p.task_task(a, b) = (tasks[a] - tasks[b]).norm();
  for (int r = 0; r < p.num_robots; ++r)
    for (int k = 0; k < p.num_tasks; ++k) p.robot_task(r, k) = (robots[r] - tasks[k]).norm();
  p.capacity = RobotCapacities(p.num_tasks, std::vector<double>(robots.size(), 0.3));
  return p;
}

TEST(OmtAssignment, CapacitiesFollowSpeeds) {
  const std::vector<double> c = RobotCapacities(10, {0.3, 0.3, 0.15});
  ASSERT_EQ(c.size(), 3u);
  EXPECT_NEAR(c[0], 10.0 / 3.0, 1e-12);
  EXPECT_NEAR(c[2], 10.0 / 6.0, 1e-12);
}

TEST(OmtAssignment, TwoGroupsGoToTheirNearbyRobotsWithinCapacity) {
  // Robot 0 near a group at x = 0, robot 1 near a group at x = 10; three tasks each.
  const std::vector<Eigen::Vector2d> robots{{-1.0, 0.0}, {11.0, 0.0}};
  std::vector<Eigen::Vector2d> tasks;
  for (int i = 0; i < 3; ++i) tasks.emplace_back(0.0, 0.3 * i);
  for (int i = 0; i < 3; ++i) tasks.emplace_back(10.0, 0.3 * i);
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  for (bool refine : {false, true}) {
    AssignmentParams params;
    params.refine = refine;
    const Assignment a = AssignTasks(p, params);
    EXPECT_TRUE(a.converged);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(a.task_robot[k], k < 3 ? 0 : 1) << "refine " << refine;
  }
}

TEST(OmtAssignment, CapacityTermBalancesAnUnevenStart) {
  // Both robots start on the left; eight tasks on a line. Without the capacity term robot 0
  // would take everything; eq. 4 splits them 4 + 4 (C_r = 4).
  const std::vector<Eigen::Vector2d> robots{{-1.0, 0.0}, {-1.0, 0.5}};
  std::vector<Eigen::Vector2d> tasks;
  for (int i = 0; i < 8; ++i) tasks.emplace_back(0.5 * i, 0.0);
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  AssignmentParams params;
  params.refine = false;
  const Assignment a = AssignTasks(p, params);
  std::vector<int> count(2, 0);
  for (int r : a.task_robot) ++count[r];
  EXPECT_NEAR(count[0], p.capacity[0], 1.0);
  EXPECT_NEAR(count[1], p.capacity[1], 1.0);
  const Assignment best = BruteForceAssignment(p);
  EXPECT_LE(a.cost, best.cost * (1.0 + kLloydOptimalityMargin));
}

TEST(OmtAssignment, CapacityTermSendsTheFarRobotToWork) {
  // Six tasks in a 0.5 m row next to robot 0; robot 1 waits 5 m away. Compactness and
  // distance alone give robot 0 everything; the capacity term (C_r = 3: penalty 18 against a
  // ~5.5 m detour) makes robot 1 take three.
  const std::vector<Eigen::Vector2d> robots{{0.0, -0.5}, {5.0, 0.0}};
  std::vector<Eigen::Vector2d> tasks;
  for (int i = 0; i < 6; ++i) tasks.emplace_back(0.1 * i, 0.0);
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  AssignmentParams params;
  params.refine = false;
  const Assignment a = AssignTasks(p, params);
  std::vector<int> count(2, 0);
  for (int r : a.task_robot) ++count[r];
  EXPECT_EQ(count[0], 3);
  EXPECT_EQ(count[1], 3);
  EXPECT_NEAR(a.cost, BruteForceAssignment(p).cost, 1e-9);
}

TEST(OmtAssignment, LloydIsNearTheBruteForceOptimumOnTinyInstances) {
  std::mt19937 rng(20190704);
  std::uniform_real_distribution<double> coord(0.0, 6.0);
  int exact = 0;
  int total = 0;
  double worst_ratio = 1.0;
  for (int trial = 0; trial < 60; ++trial) {
    const int R = 2 + trial % 2;
    const int K = 4 + trial % 5;  // 4..8 tasks: at most 3^8 labellings
    std::vector<Eigen::Vector2d> robots(R), tasks(K);
    for (auto& v : robots) v = {coord(rng), coord(rng)};
    for (auto& v : tasks) v = {coord(rng), coord(rng)};
    const AssignmentProblem p = EuclideanProblem(robots, tasks);
    AssignmentParams params;
    params.refine = false;
    const Assignment a = AssignTasks(p, params);
    const Assignment best = BruteForceAssignment(p);
    ASSERT_EQ(best.task_robot.size(), static_cast<std::size_t>(K));
    for (int r : a.task_robot) EXPECT_GE(r, 0);  // NoRefine assigns every task
    EXPECT_NEAR(a.cost, Eq4Cost(p, a.task_robot), 1e-9);
    EXPECT_GE(a.cost, best.cost - 1e-9);  // brute force is the optimum
    EXPECT_LE(a.cost, best.cost * (1.0 + kLloydOptimalityMargin)) << "trial " << trial;
    worst_ratio = std::max(worst_ratio, a.cost / best.cost);
    exact += a.cost <= best.cost + 1e-9;
    ++total;
  }
  EXPECT_GE(exact, static_cast<int>(kMinExactFraction * total)) << "worst ratio " << worst_ratio;
  RecordProperty("worst_ratio", std::to_string(worst_ratio));
  RecordProperty("exact", std::to_string(exact) + "/" + std::to_string(total));
}

TEST(OmtAssignment, RefinementLeavesScatteredTasksUnassigned) {
  // A compact group near robot 0 and one task 6 m away from everything: with δ = 1 m it
  // forms its own (task-seeded) cluster and is left for a later planning interval.
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {0.5, 0.0}};
  std::vector<Eigen::Vector2d> tasks;
  for (int i = 0; i < 5; ++i) tasks.emplace_back(0.2 * i, 0.5);
  tasks.emplace_back(6.0, 6.0);
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  AssignmentParams params;
  const Assignment refined = AssignTasks(p, params);
  EXPECT_EQ(refined.task_robot.back(), -1);
  for (int k = 0; k < 5; ++k) EXPECT_GE(refined.task_robot[k], 0);
  params.refine = false;
  const Assignment plain = AssignTasks(p, params);
  EXPECT_GE(plain.task_robot.back(), 0);
}

TEST(OmtAssignment, RobotsWithoutTasksTakeTheNearestUnassignedCluster) {
  // Robot 0 holds its cluster; robots 1 and 2 hold nothing. Unassigned: a two-task cluster (3),
  // a single task near robot 1 (4) and one no robot reaches (5).
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {10.0, 0.0}, {20.0, 0.0}};
  const std::vector<Eigen::Vector2d> tasks{{0.0, 1.0},  {0.0, 1.2}, {12.0, 5.0},
                                           {12.0, 5.3}, {9.0, 3.0}, {30.0, 0.0}};
  AssignmentProblem p = EuclideanProblem(robots, tasks);
  constexpr double kUnreachableM = 1e6;
  for (int r = 0; r < 3; ++r) p.robot_task(r, 5) = kUnreachableM;
  Assignment a;
  a.task_robot = {0, 0, -1, -1, -1, -1};
  a.task_cluster = {0, 0, 3, 3, 4, 5};
  a.cluster_robot = {0, 1, 2, -1, -1, -1};
  HandOutUnassigned(p, kUnreachableM, &a);
  // Robot 1 takes the single task 3.2 m away (not the pair 5.4 m away); robot 2 the pair, whole.
  EXPECT_EQ(a.task_robot, (std::vector<int>{0, 0, 2, 2, 1, -1}));
  EXPECT_EQ(a.cluster_robot, (std::vector<int>{0, 1, 2, 2, 1, -1}));
  EXPECT_NEAR(a.cost, Eq4Cost(p, a.task_robot), 1e-9);
  // Nothing changes when every robot holds a task.
  const Assignment before = a;
  HandOutUnassigned(p, kUnreachableM, &a);
  EXPECT_EQ(a.task_robot, before.task_robot);
}

TEST(OmtAssignment, RobotsFarBehindTheWorkGetNoCapacity) {
  // Robots 0 and 1 stand by the tasks; robot 2 is 20 m away, robot 3 just within 3 m (the reach)
  // beyond the nearest robot's distance.
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {1.0, 0.0}, {20.0, 0.0}, {-3.4, 0.0}};
  const std::vector<Eigen::Vector2d> tasks{{0.0, 0.5}, {0.5, 0.5}, {1.0, 0.5},
                                           {0.2, 0.8}, {0.8, 0.8}, {0.5, 1.0}};
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  const std::vector<double> speeds(4, 0.3);
  const std::vector<double> caps = ReachCapacities(p, speeds, std::vector<double>(4, 3.0));
  // Robot 3's nearest task is 3.44 m away, the nearest robot's 0.5 m: 2.94 m beyond, within reach.
  EXPECT_EQ(caps, (std::vector<double>{2.0, 2.0, 0.0, 2.0}));
  // A long enough reach gives back §3.4's K / R for everyone.
  EXPECT_EQ(ReachCapacities(p, speeds, std::vector<double>(4, 100.0)), RobotCapacities(6, speeds));
}

TEST(OmtAssignment, FewViewsKeepOnlyTheLeastLoadedRobotsBusy) {
  // Five tasks in a row 1 m ahead. Robots 0 and 1 stand 1 m from them, robot 2 2.24 m; robot 0
  // has driven 10 m, the others nothing; robot 3 had no capacity to begin with (the reach).
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {1.0, 0.0}, {-2.0, 0.0}, {2.0, 0.0}};
  const std::vector<Eigen::Vector2d> tasks{
      {0.0, 1.0}, {0.5, 1.0}, {1.0, 1.0}, {1.5, 1.0}, {2.0, 1.0}};
  AssignmentProblem p = EuclideanProblem(robots, tasks);
  const std::vector<double> speeds(4, 0.3);
  p.capacity = RobotCapacities(5, std::vector<double>(3, 0.3));
  p.capacity.push_back(0.0);
  const std::vector<double> driven{10.0, 0.0, 0.0, 0.0};
  // 3 views a robot: ⌈5 / 3⌉ = 2 robots, the two least loaded (1 m and 2.24 m against 11 m).
  EXPECT_EQ(TeamCapacities(p, speeds, driven, 3.0, 1.0), (std::vector<double>{0.0, 2.5, 2.5, 0.0}));
  // Enough views for the three with capacity, or no limit: unchanged.
  EXPECT_EQ(TeamCapacities(p, speeds, driven, 5.0 / 3.0, 1.0), p.capacity);
  EXPECT_EQ(TeamCapacities(p, speeds, driven, 0.0, 1.0), p.capacity);
  // The distance driven counts driven_weight times: robot 1, 1 m driven and 1 m from the work,
  // goes before robot 2 (2.24 m away, nothing driven) at weight 1, after it at weight 3.
  const std::vector<double> one_metre{10.0, 1.0, 0.0, 0.0};
  EXPECT_EQ(TeamCapacities(p, speeds, one_metre, 5.0, 1.0),
            (std::vector<double>{0.0, 5.0, 0.0, 0.0}));
  EXPECT_EQ(TeamCapacities(p, speeds, one_metre, 5.0, 3.0),
            (std::vector<double>{0.0, 0.0, 5.0, 0.0}));
  // Equal loads go to the lower index.
  EXPECT_EQ(TeamCapacities(p, speeds, {0.0, 0.0, 0.0, 0.0}, 5.0, 1.0),
            (std::vector<double>{5.0, 0.0, 0.0, 0.0}));
}

TEST(OmtAssignment, WithAReachIdleRobotsLeaveToNearerRobotsWhatTheyAreFarFrom) {
  // Robot 0 holds a cluster next to the unassigned pair (tasks 2, 3); idle robot 1 is 12 m away.
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {12.0, 0.0}};
  const std::vector<Eigen::Vector2d> tasks{{0.0, 1.0}, {0.0, 1.2}, {0.0, -1.0}, {0.0, -1.3}};
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  Assignment a;
  a.task_robot = {0, 0, -1, -1};
  a.task_cluster = {0, 0, 2, 2};
  a.cluster_robot = {0, 1, -1};
  Assignment with_reach = a;
  HandOutUnassigned(p, 1e6, &with_reach, {7.5, 7.5});
  EXPECT_EQ(with_reach.task_robot, a.task_robot);  // robot 1 stays still
  HandOutUnassigned(p, 1e6, &a);
  EXPECT_EQ(a.task_robot, (std::vector<int>{0, 0, 1, 1}));  // without it, robot 1 drives 12 m
}

TEST(OmtAssignment, LoadBalanceGivesTheFarClusterToTheRobotThatDroveLess) {
  // Two robots in a row behind two clusters on the same line: Σ distance is the same whichever
  // robot takes the far cluster, so eq. 4 does not care; the distance driven so far decides.
  const std::vector<Eigen::Vector2d> robots{{0.0, 0.0}, {1.0, 0.0}};
  const std::vector<Eigen::Vector2d> tasks{{5.0, 0.0}, {5.0, 0.2}, {10.0, 0.0}, {10.0, 0.2}};
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  Assignment a;
  a.task_robot = {0, 0, 1, 1};  // robot 0 to the near cluster, robot 1 to the far one
  a.task_cluster = {0, 0, 1, 1};
  a.cluster_robot = {0, 1};
  a.cost = Eq4Cost(p, a.task_robot);
  constexpr double kToleranceM = 1.0;
  // Equal histories: the split already has the smaller larger load (5 and 9, against 10 and 4).
  Assignment same = a;
  BalanceLoads(p, {0.0, 0.0}, kToleranceM, &same);
  EXPECT_EQ(same.task_robot, a.task_robot);
  EXPECT_EQ(same.load_exchanges, 0);
  // Robot 1 has driven 10 m: loads 5 and 19 become 10 and 14.
  Assignment swapped = a;
  BalanceLoads(p, {0.0, 10.0}, kToleranceM, &swapped);
  EXPECT_EQ(swapped.task_robot, (std::vector<int>{1, 1, 0, 0}));
  EXPECT_EQ(swapped.cluster_robot, (std::vector<int>{1, 0}));
  EXPECT_EQ(swapped.load_exchanges, 1);
  EXPECT_NEAR(swapped.cost, a.cost, kToleranceM);
  // An exchange that costs eq. 4 more than the tolerance is not made: robot 1 now stands
  // 8 m off the line, and the exchange costs 1.86 m more.
  AssignmentProblem off = EuclideanProblem({{0.0, 0.0}, {1.0, 8.0}}, tasks);
  Assignment kept = a;
  kept.cost = Eq4Cost(off, a.task_robot);
  BalanceLoads(off, {0.0, 10.0}, kToleranceM, &kept);
  EXPECT_EQ(kept.task_robot, a.task_robot);
  BalanceLoads(off, {0.0, 10.0}, 10.0, &kept);  // a loose tolerance lets it through
  EXPECT_EQ(kept.task_robot, (std::vector<int>{1, 1, 0, 0}));
}

TEST(OmtAssignment, RefinedClustersAreCompact) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(0.0, 8.0);
  std::vector<Eigen::Vector2d> robots(4), tasks(30);
  for (auto& v : robots) v = {coord(rng), coord(rng)};
  for (auto& v : tasks) v = {coord(rng), coord(rng)};
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  AssignmentParams params;
  const Assignment a = AssignTasks(p, params);
  ASSERT_TRUE(a.converged);
  // Every task kept by a robot lies within δ of some medoid-like member: the cluster diameter
  // is at most 2δ.
  for (int k = 0; k < p.num_tasks; ++k) {
    for (int l = 0; l < p.num_tasks; ++l) {
      if (a.task_robot[k] >= 0 && a.task_robot[k] == a.task_robot[l]) {
        EXPECT_LE(p.task_task(k, l), 2.0 * params.delta_m + 1e-9);
      }
    }
  }
  std::vector<int> count(4, 0);
  for (int r : a.task_robot)
    if (r >= 0) ++count[r];
  for (int r = 0; r < 4; ++r) EXPECT_LE(count[r], std::ceil(p.capacity[r]));
}

TEST(OmtAssignment, MismatchedSizesAreRejectedNotRead) {
  AssignmentProblem p = EuclideanProblem({{0.0, 0.0}}, {{1.0, 0.0}, {2.0, 0.0}});
  p.capacity.clear();
  EXPECT_FALSE(ValidateProblem(p).ok());
  const Assignment a = AssignTasks(p, AssignmentParams{});
  EXPECT_FALSE(a.converged);
  EXPECT_EQ(a.task_robot, (std::vector<int>{-1, -1}));
}

TEST(OmtAssignment, DeterministicForTheSameInput) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(0.0, 8.0);
  std::vector<Eigen::Vector2d> robots(5), tasks(30);
  for (auto& v : robots) v = {coord(rng), coord(rng)};
  for (auto& v : tasks) v = {coord(rng), coord(rng)};
  const AssignmentProblem p = EuclideanProblem(robots, tasks);
  const Assignment a = AssignTasks(p, AssignmentParams{});
  const Assignment b = AssignTasks(p, AssignmentParams{});
  EXPECT_EQ(a.task_robot, b.task_robot);
  EXPECT_EQ(a.cost, b.cost);
}

}  // namespace
}  // namespace voxplan::omt
