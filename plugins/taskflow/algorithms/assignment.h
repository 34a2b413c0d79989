// Mode-aware MDMTSP assignment of the task-flow planner (Guo et al. 2022, §5, Alg. 1):
// InitialClustering, simulated annealing over the robots' modes, an open TSP path per robot
// and the traveling-energy cut. Each new sequence holds one task type (G13).
//
// Nodes of the distance matrix: the robots' T^end first (0 .. R−1), then the new tasks
// (R .. R+K−1). Energies: E'_d of G eq. 5 in seconds, E_c of G eq. 3 in tasks², E = E'_d +
// λ_c·E_c.
//
// Choices where the paper is silent (design doc §1.4):
// - The centroid ω_r of eq. 5 is a medoid: the node of {T_r^end} ∪ cluster minimising r's eq. 5
//   term, because distances are geodesic matrices, not coordinates.
// - Clustering per mode configuration: k-medoids seeded at the T^end, then the capacity GMM
//   (isotropic, σ = median task–medoid distance, responsibilities × exp(−(n_r − C_r)²/C_r),
//   on when λ_c > 0), then single-task moves while the exact E decreases — that last step is
//   where λ_c trades distance against balance, the GMM only gives it a start.
// - The clustering is a function of the modes, so SA moves only modes (Exchange, Reassign) and
//   caches the energy of each mode vector it has seen.
// - Initial modes: the explorer count is round(R·K_E/K) within [1, R−1] (one robot per mode
//   while both task types exist); robots keep their current mode where that count allows, and
//   the robots that must switch are those nearest the other type's tasks (fewer switches than
//   the paper's random draw; SA explores the rest).
// - One robot and both task types: it takes the type with more tasks (ties: its current mode);
//   the others are dropped for the next round.
// - TSP: omt::OpenPathChristofides from T^end, tried with every task as the fixed end (the
//   shortest wins), since the path's end is free.
// - v(T_r^end) is the speed of the robot's current mode, as eq. 5 is written.
// - Forced modes (NoRe / NoEx): every robot runs every task type in the one mode, so there is no
//   switch for G13 to avoid and sequences may mix types; speeds are the forced mode's.
// - RobotPlan.mode is the configuration's mode even for a robot left without new tasks;
//   mode_changes counts only robots whose new tasks make them switch.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "plugins/omt/algorithms/tsp.h"
#include "plugins/omt/algorithms/types.h"

namespace voxplan::taskflow {

// VP_MODE_* values of the planner ABI.
enum class Mode : std::uint8_t { kExplorer = 0, kReconstructor = 1 };
enum class TaskType : std::uint8_t { kExploration = 0, kReconstruction = 1 };

inline Mode ModeOf(TaskType t) {
  return t == TaskType::kExploration ? Mode::kExplorer : Mode::kReconstructor;
}

enum class ModePolicy {
  kSwitch,              // the paper: modes chosen per round
  kFixed,               // NoSw: robots 0 .. fixed_explorers−1 explore, the others reconstruct
  kForceExplorer,       // NoRe: every robot explores; tasks of both types, one mode
  kForceReconstructor,  // NoEx
};

struct AssignTask {
  Eigen::Vector2d xy_m = Eigen::Vector2d::Zero();
  TaskType type = TaskType::kExploration;
};

struct AssignRobot {
  Eigen::Vector2d end_xy_m = Eigen::Vector2d::Zero();  // T^end: last unfinished task or position
  int rest_count = 0;                                  // |T_r^rest|
  Mode mode = Mode::kExplorer;                         // current mode
};

struct AssignmentInput {
  std::vector<AssignTask> tasks;
  std::vector<AssignRobot> robots;
  omt::DistanceMatrix distance;  // (R+K) × (R+K), symmetric, metres, +inf unreachable
  double explorer_speed_mps = 0.5;
  double reconstructor_speed_mps = 0.2;
};

struct AssignmentParams {
  double lambda_c = 10.0;  // seconds per task²
  // Simulated annealing: T₀ = this fraction of the initial energy, T ← cooling·T per iteration.
  double sa_initial_temperature = 0.05;
  double sa_cooling = 0.95;
  int sa_max_iterations = 100;
  std::function<bool()> out_of_time;  // optional: true stops the annealing
  std::uint64_t seed = 1;
  ModePolicy mode_policy = ModePolicy::kSwitch;
  int fixed_explorers = 2;  // kFixed: 3 / 2 / 1 for NoSw(3E1R / 2E2R / 1E3R)
  // Traveling-energy cut (G17): the first hop into a new task at 1-based position >= cut_from
  // that is longer than max_hop_m is removed with all its successors.
  bool energy_cut = true;
  double max_hop_m = 8.0;
  int cut_from = 2;
  int kmeans_iterations = 20;
  int gmm_iterations = 10;
  double gmm_min_sigma_m = 0.5;
  int descent_passes = 20;
  // Energy charged per task a mode vector leaves without a robot (none of its mode reaches it).
  double unassigned_penalty_s = 1000.0;
  omt::TspParams tsp;
};

struct RobotPlan {
  Mode mode = Mode::kExplorer;  // the mode chosen for it; its new tasks are of this mode
  std::vector<int> tasks;       // new task indices in execution order, after the cut
  double path_m = 0.0;          // T^end → tasks, along the distance matrix
};

struct AssignmentResult {
  omt::Status status;
  std::vector<RobotPlan> robots;
  std::vector<int> dropped;  // ascending: unreachable for their mode, or cut (G17)
  double energy_d = 0.0;     // E'_d, s
  double energy_c = 0.0;     // E_c, tasks²
  double energy = 0.0;       // E'_d + λ_c·E_c (+ penalties) of the chosen clustering
  int sa_iterations = 0;
  int mode_changes = 0;  // robots with new tasks in a mode other than their current one
};

// Sizes agree, speeds are positive, counts non-negative, tasks and robots exist.
omt::Status ValidateAssignment(const AssignmentInput& input);

// InitialClustering's modes (see the file comment), with the policy applied.
std::vector<Mode> InitialModes(const AssignmentInput& input, const AssignmentParams& params);

// Cluster-and-assign for fixed modes: robot per task (−1: no robot of its mode reaches it),
// with its energies.
struct Clustering {
  std::vector<int> task_robot;
  double energy_d = 0.0;
  double energy_c = 0.0;
  double energy = 0.0;  // energy_d + λ_c·energy_c + penalties
};
Clustering ClusterTasks(const AssignmentInput& input, const std::vector<Mode>& modes,
                        const AssignmentParams& params);

// G17 on one sequence from start_node (node indices of input.distance): the index in
// `sequence` where the cut starts, or sequence.size() when nothing is cut.
std::size_t EnergyCutPosition(const omt::DistanceMatrix& distance, int start_node,
                              const std::vector<int>& sequence_nodes, double max_hop_m,
                              int cut_from);

// Alg. 1. An invalid input yields the status and no plans.
AssignmentResult AssignTasks(const AssignmentInput& input, const AssignmentParams& params);

}  // namespace voxplan::taskflow
