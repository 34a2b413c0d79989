// OMT task assignment (§3.3–3.4, §4): minimise eq. 4 — compactness Σ γ(T_k, ω_r), distance
// γ(R_r, ω_r) and capacity (|Ω_r| - C_r)² — by Lloyd-style alternation with a capacity
// relaxation, optionally with the compactness-based clustering refinement (δ = 1 m).
//
// γ is a geodesic distance given as matrices, so the centroid ω_r is taken as the medoid: the
// assigned task minimising compactness + distance (the discrete centroid on the scene graph).
#pragma once

#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

struct AssignmentProblem {
  int num_robots = 0;
  int num_tasks = 0;
  DistanceMatrix task_task;      // K × K, symmetric
  DistanceMatrix robot_task;     // R × K
  std::vector<double> capacity;  // C_r, one per robot
};

// C_r = K / R · v_r / v_max (§3.4).
std::vector<double> RobotCapacities(int num_tasks, const std::vector<double>& speeds_mps);

// §3.4's C_r shared only among the robots that can start on the work soon: a robot whose
// nearest task lies more than reach_m[r] beyond the nearest robot's gets C_r = 0, the others
// split K by RobotCapacities. §5.5: with more robots than the work needs, "the extra robots do
// not receive any task but stay still"; with K / R for everyone, eq. 4's capacity term instead
// pulls robots across the scene to tasks others stand next to.
std::vector<double> ReachCapacities(const AssignmentProblem& problem,
                                    const std::vector<double>& speeds_mps,
                                    const std::vector<double>& reach_m);

// §5.5 also when the views are few for the team: K views keep at most ⌈K / views_per_robot⌉
// robots busy. Of the robots with capacity in problem.capacity, those with the smallest load —
// driven_weight × driven_m (distance so far) plus the distance to their nearest task, ties to
// the lower index — share K by RobotCapacities; the others get C_r = 0 and stay still (unless
// BalanceLoads hands one a task set, which it does only where that lowers the larger load).
// Unchanged when views_per_robot <= 0 or no more robots have capacity than that.
std::vector<double> TeamCapacities(const AssignmentProblem& problem,
                                   const std::vector<double>& speeds_mps,
                                   const std::vector<double>& driven_m, double views_per_robot,
                                   double driven_weight);

struct AssignmentParams {
  bool refine = true;    // clustering refinement; off = NoRefine ablation (K = R clusters)
  double delta_m = 1.0;  // a task farther than δ from its cluster centre seeds a new cluster
  int max_iterations = 30;
  // NoRefine only: after Lloyd, move/swap tasks between robots while exact eq. 4 decreases.
  bool polish = true;
};

struct Assignment {
  std::vector<int> task_robot;    // robot per task, -1 when left unassigned (refinement)
  std::vector<int> task_cluster;  // final cluster per task
  // Robot each cluster goes to: its seed, or the robot HandOutUnassigned gave it to; -1 for
  // task-seeded ones left unassigned.
  std::vector<int> cluster_robot;
  int iterations = 0;
  bool converged = false;
  double cost = 0.0;       // eq. 4 over robot clusters
  int load_exchanges = 0;  // task-set exchanges BalanceLoads made
};

// Robots `a` leaves without a task (in index order) each take the unassigned cluster whose
// nearest task is nearest to them, of those nearer than unreachable_m: a robot does not stand
// still while work waits. Clusters stay whole (the refinement made them compact).
// With reach_m (one per robot), a robot skips tasks another robot is more than reach_m[r] nearer
// to: that one takes them when it is free (-inf: it takes none, +inf: any).
void HandOutUnassigned(const AssignmentProblem& problem, double unreachable_m, Assignment* a,
                       const std::vector<double>& reach_m = {});

// Eq. 4 balances task counts, not distances: two robots behind the same work pay the same
// Σ distance whichever of them takes the far cluster. Exchanges the task sets of two robots when
// eq. 4 (their two robot terms) grows by at most tolerance_m and the larger of their loads —
// driven_m (distance so far) plus the distance to the medoid — shrinks by more than
// kMinLoadGainM. Load balance is the paper's COV of distance per robot (§5.2).
inline constexpr double kMinLoadGainM = 0.1;
void BalanceLoads(const AssignmentProblem& problem, const std::vector<double>& driven_m,
                  double tolerance_m, Assignment* a);

// Eq. 4 for a labelling (unassigned tasks, -1, do not enter), each ω_r the best medoid.
double Eq4Cost(const AssignmentProblem& problem, const std::vector<int>& task_robot);

// Matrix and capacity sizes agree with num_robots / num_tasks.
Status ValidateProblem(const AssignmentProblem& problem);

// An invalid problem (see ValidateProblem) yields every task unassigned, converged = false.
Assignment AssignTasks(const AssignmentProblem& problem, const AssignmentParams& params);

// Exact minimum of eq. 4 over all R^K labellings with every task assigned; for tests. Returns
// an empty assignment when R^K exceeds max_labellings or the problem is invalid.
Assignment BruteForceAssignment(const AssignmentProblem& problem, long max_labellings = 5000000);

}  // namespace voxplan::omt
