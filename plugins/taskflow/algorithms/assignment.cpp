#include "plugins/taskflow/algorithms/assignment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

namespace voxplan::taskflow {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;
// Stands in for unreachable pairs where finite numbers are needed (the TSP solver, k-medoids).
constexpr double kUnreachable = 1e9;

bool Forced(ModePolicy p) {
  return p == ModePolicy::kForceExplorer || p == ModePolicy::kForceReconstructor;
}

// The per-call view of the problem: speeds per node and the shared capacity C_r.
struct Problem {
  const AssignmentInput& in;
  const AssignmentParams& params;
  int num_robots = 0;
  int num_tasks = 0;
  double capacity = 0.0;
  std::vector<double> task_speed;  // v(T_k)
  std::vector<double> end_speed;   // v(T_r^end)

  Problem(const AssignmentInput& input, const AssignmentParams& p) : in(input), params(p) {
    num_robots = static_cast<int>(in.robots.size());
    num_tasks = static_cast<int>(in.tasks.size());
    double total = num_tasks;
    for (const AssignRobot& r : in.robots) total += r.rest_count;
    capacity = num_robots > 0 ? total / num_robots : 0.0;
    const auto speed = [&](Mode m) {
      return m == Mode::kExplorer ? in.explorer_speed_mps : in.reconstructor_speed_mps;
    };
    const bool forced = Forced(params.mode_policy);
    const Mode forced_mode =
        params.mode_policy == ModePolicy::kForceExplorer ? Mode::kExplorer : Mode::kReconstructor;
    for (const AssignTask& t : in.tasks)
      task_speed.push_back(speed(forced ? forced_mode : ModeOf(t.type)));
    for (const AssignRobot& r : in.robots)
      end_speed.push_back(speed(forced ? forced_mode : r.mode));
  }

  int TaskNode(int k) const { return num_robots + k; }
  double D(int a, int b) const { return in.distance(a, b); }
  bool Allowed(int k, int r, const std::vector<Mode>& modes) const {
    if (!Forced(params.mode_policy) && modes[r] != ModeOf(in.tasks[k].type)) return false;
    return std::isfinite(D(r, TaskNode(k)));
  }
  // (n_r + |T_r^rest| − C_r)², one robot's term of eq. 3.
  double CapacityTerm(int r, double n) const {
    const double e = n + in.robots[r].rest_count - capacity;
    return e * e;
  }
};

// Robot r's term of eq. 5 with the medoid that minimises it; members ascending. Weights
// (one per task, soft clustering) default to 1.
double Eq5Term(const Problem& pb, int r, const std::vector<int>& members, int* medoid_node,
               const std::vector<double>* weights = nullptr) {
  *medoid_node = r;
  if (members.empty()) return 0.0;
  double best = kInf;
  const auto evaluate = [&](int c) {
    double sum = pb.D(r, c) / pb.end_speed[r];
    for (int k : members) {
      const double w = weights ? (*weights)[k] : 1.0;
      if (w > 0.0) sum += w * pb.D(pb.TaskNode(k), c) / pb.task_speed[k];
    }
    if (sum < best - kEps) {
      best = sum;
      *medoid_node = c;
    }
  };
  evaluate(r);
  for (int k : members) evaluate(pb.TaskNode(k));
  return best;
}

double RobotEnergy(const Problem& pb, int r, const std::vector<int>& members) {
  int medoid = r;
  return Eq5Term(pb, r, members, &medoid) +
         pb.params.lambda_c * pb.CapacityTerm(r, static_cast<double>(members.size()));
}

std::vector<std::vector<int>> Members(const Problem& pb, const std::vector<int>& task_robot) {
  std::vector<std::vector<int>> members(static_cast<std::size_t>(pb.num_robots));
  for (int k = 0; k < pb.num_tasks; ++k)
    if (task_robot[k] >= 0) members[task_robot[k]].push_back(k);
  return members;
}

// k-medoids from the T^end: each task to the allowed robot whose medoid is nearest.
std::vector<int> KMedoids(const Problem& pb, const std::vector<Mode>& modes,
                          std::vector<int>* medoid) {
  std::vector<int> label(static_cast<std::size_t>(pb.num_tasks), -1);
  medoid->resize(static_cast<std::size_t>(pb.num_robots));
  for (int r = 0; r < pb.num_robots; ++r) (*medoid)[r] = r;
  for (int it = 0; it < pb.params.kmeans_iterations; ++it) {
    bool changed = false;
    for (int k = 0; k < pb.num_tasks; ++k) {
      int best = -1;
      double best_d = kInf;
      for (int r = 0; r < pb.num_robots; ++r) {
        if (!pb.Allowed(k, r, modes)) continue;
        double d = pb.D(pb.TaskNode(k), (*medoid)[r]);
        if (!std::isfinite(d)) d = kUnreachable + pb.D(pb.TaskNode(k), r);
        if (d < best_d - kEps) {
          best_d = d;
          best = r;
        }
      }
      changed |= best != label[k];
      label[k] = best;
    }
    const auto members = Members(pb, label);
    for (int r = 0; r < pb.num_robots; ++r) Eq5Term(pb, r, members[r], &(*medoid)[r]);
    if (!changed && it > 0) break;
  }
  return label;
}

// G16: soft assignment with responsibilities ∝ exp(−d²/2σ²)·exp(−(n_r − C_r)²/C_r), n_r the
// robot's load counting the task in question; returns the hard labels (argmax).
std::vector<int> CapacityGmm(const Problem& pb, const std::vector<Mode>& modes,
                             std::vector<int> label, std::vector<int> medoid) {
  const int R = pb.num_robots, K = pb.num_tasks;
  std::vector<std::vector<double>> gamma(static_cast<std::size_t>(R),
                                         std::vector<double>(static_cast<std::size_t>(K), 0.0));
  for (int k = 0; k < K; ++k)
    if (label[k] >= 0) gamma[label[k]][k] = 1.0;
  const double C = std::max(pb.capacity, kEps);
  for (int it = 0; it < pb.params.gmm_iterations; ++it) {
    std::vector<double> spread;
    for (int k = 0; k < K; ++k)
      if (label[k] >= 0) {
        const double d = pb.D(pb.TaskNode(k), medoid[label[k]]);
        if (std::isfinite(d)) spread.push_back(d);
      }
    double sigma = pb.params.gmm_min_sigma_m;
    if (!spread.empty()) {
      std::nth_element(spread.begin(), spread.begin() + spread.size() / 2, spread.end());
      sigma = std::max(sigma, spread[spread.size() / 2]);
    }
    std::vector<double> load(static_cast<std::size_t>(R), 0.0);
    for (int r = 0; r < R; ++r)
      for (int k = 0; k < K; ++k) load[r] += gamma[r][k];
    auto next = gamma;
    for (int k = 0; k < K; ++k) {
      std::vector<double> logit(static_cast<std::size_t>(R), -kInf);
      double top = -kInf;
      for (int r = 0; r < R; ++r) {
        if (!pb.Allowed(k, r, modes)) continue;
        const double d = pb.D(pb.TaskNode(k), medoid[r]);
        if (!std::isfinite(d)) continue;
        const double n = load[r] - gamma[r][k] + 1.0;
        logit[r] = -d * d / (2.0 * sigma * sigma) - pb.CapacityTerm(r, n) / C;
        top = std::max(top, logit[r]);
      }
      if (top == -kInf) continue;
      double sum = 0.0;
      for (int r = 0; r < R; ++r) sum += logit[r] == -kInf ? 0.0 : std::exp(logit[r] - top);
      for (int r = 0; r < R; ++r)
        next[r][k] = logit[r] == -kInf ? 0.0 : std::exp(logit[r] - top) / sum;
    }
    gamma = std::move(next);
    for (int k = 0; k < K; ++k) {
      int best = -1;
      for (int r = 0; r < R; ++r)
        if (gamma[r][k] > 0.0 && (best < 0 || gamma[r][k] > gamma[best][k] + kEps)) best = r;
      if (best >= 0) label[k] = best;
    }
    // M-step: the weighted medoid over r's end and every task it holds some weight of.
    for (int r = 0; r < R; ++r) {
      std::vector<int> support;
      for (int k = 0; k < K; ++k)
        if (gamma[r][k] > 0.0) support.push_back(k);
      Eq5Term(pb, r, support, &medoid[r], &gamma[r]);
    }
  }
  return label;
}

// Single-task moves while the exact E = Σ_r E'_d,r + λ_c·E_c,r decreases.
void Descend(const Problem& pb, const std::vector<Mode>& modes, std::vector<int>* label) {
  auto members = Members(pb, *label);
  std::vector<double> energy(static_cast<std::size_t>(pb.num_robots));
  for (int r = 0; r < pb.num_robots; ++r) energy[r] = RobotEnergy(pb, r, members[r]);
  for (int pass = 0; pass < pb.params.descent_passes; ++pass) {
    bool moved = false;
    for (int k = 0; k < pb.num_tasks; ++k) {
      const int a = (*label)[k];
      if (a < 0) continue;
      std::vector<int> without = members[a];
      without.erase(std::find(without.begin(), without.end(), k));
      const double e_a = RobotEnergy(pb, a, without);
      int best = -1;
      double best_delta = -kEps, best_e_r = 0.0;
      for (int r = 0; r < pb.num_robots; ++r) {
        if (r == a || !pb.Allowed(k, r, modes)) continue;
        std::vector<int> with = members[r];
        with.insert(std::upper_bound(with.begin(), with.end(), k), k);
        const double e_r = RobotEnergy(pb, r, with);
        const double delta = e_a + e_r - energy[a] - energy[r];
        if (delta < best_delta) {
          best_delta = delta;
          best = r;
          best_e_r = e_r;
        }
      }
      if (best < 0) continue;
      members[a] = std::move(without);
      auto& m = members[best];
      m.insert(std::upper_bound(m.begin(), m.end(), k), k);
      energy[a] = e_a;
      energy[best] = best_e_r;
      (*label)[k] = best;
      moved = true;
    }
    if (!moved) break;
  }
}

// The mode vector SA is allowed to change: Switch policy with both task types and >= 2 robots.
bool AnnealModes(const AssignmentInput& input, const AssignmentParams& params) {
  if (params.mode_policy != ModePolicy::kSwitch || input.robots.size() < 2) return false;
  bool has_exp = false, has_rec = false;
  for (const AssignTask& t : input.tasks)
    (t.type == TaskType::kExploration ? has_exp : has_rec) = true;
  return has_exp && has_rec;
}

// Exchange (swap one explorer's and one reconstructor's modes) or Reassign (flip a robot of
// the larger category, keeping one robot per mode); false when neither move exists.
bool Disturb(std::mt19937_64* rng, std::vector<Mode>* modes) {
  std::vector<int> explorers, reconstructors;
  for (int r = 0; r < static_cast<int>(modes->size()); ++r)
    ((*modes)[r] == Mode::kExplorer ? explorers : reconstructors).push_back(r);
  const auto pick = [&](const std::vector<int>& v) {
    return v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(*rng)];
  };
  const std::size_t larger = std::max(explorers.size(), reconstructors.size());
  const bool can_exchange = !explorers.empty() && !reconstructors.empty();
  const bool can_reassign = larger >= 2;
  if (!can_exchange && !can_reassign) return false;
  const bool exchange =
      can_exchange && (!can_reassign || std::uniform_int_distribution<int>(0, 1)(*rng) == 0);
  if (exchange) {
    const int e = pick(explorers), c = pick(reconstructors);
    std::swap((*modes)[e], (*modes)[c]);
    return true;
  }
  bool from_explorers = explorers.size() > reconstructors.size();
  if (explorers.size() == reconstructors.size())
    from_explorers = std::uniform_int_distribution<int>(0, 1)(*rng) == 0;
  const int r = pick(from_explorers ? explorers : reconstructors);
  (*modes)[r] = from_explorers ? Mode::kReconstructor : Mode::kExplorer;
  return true;
}

// Open path from node 0 through all nodes of sub; the end is free, so every node is tried as
// the fixed end of OpenPathChristofides and the shortest path wins (ties: the lower node).
std::vector<int> OpenPathFreeEnd(const omt::DistanceMatrix& sub, const omt::TspParams& params) {
  const int n = sub.rows;
  if (n <= 2) {
    std::vector<int> order(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) order[i] = i;
    return order;
  }
  std::vector<int> best;
  double best_len = kInf;
  for (int end = 1; end < n; ++end) {
    std::vector<int> order = omt::OpenPathChristofides(sub, 0, end, params);
    const double len = omt::PathLength(sub, order);
    if (len < best_len - kEps) {
      best_len = len;
      best = std::move(order);
    }
  }
  return best;
}

}  // namespace

omt::Status ValidateAssignment(const AssignmentInput& input) {
  const auto invalid = [](const char* m) {
    return omt::Status::Error(omt::Status::Code::kInvalidInput, m);
  };
  if (input.robots.empty()) return invalid("no robots");
  const int n = static_cast<int>(input.robots.size() + input.tasks.size());
  if (input.distance.rows != n || input.distance.cols != n ||
      input.distance.values.size() != static_cast<std::size_t>(n) * n)
    return invalid("distance matrix must be (R+K) x (R+K)");
  if (!(input.explorer_speed_mps > 0.0) || !(input.reconstructor_speed_mps > 0.0) ||
      !std::isfinite(input.explorer_speed_mps) || !std::isfinite(input.reconstructor_speed_mps))
    return invalid("mode speeds must be positive");
  for (const AssignRobot& r : input.robots)
    if (r.rest_count < 0) return invalid("negative queue length");
  for (double d : input.distance.values)
    if (std::isnan(d) || d < 0.0) return invalid("distances must be >= 0 or +inf");
  return omt::Status::Ok();
}

std::vector<Mode> InitialModes(const AssignmentInput& input, const AssignmentParams& params) {
  const int R = static_cast<int>(input.robots.size());
  std::vector<Mode> modes;
  for (const AssignRobot& r : input.robots) modes.push_back(r.mode);
  switch (params.mode_policy) {
    case ModePolicy::kForceExplorer:
      return std::vector<Mode>(modes.size(), Mode::kExplorer);
    case ModePolicy::kForceReconstructor:
      return std::vector<Mode>(modes.size(), Mode::kReconstructor);
    case ModePolicy::kFixed:
      for (int r = 0; r < R; ++r)
        modes[r] = r < params.fixed_explorers ? Mode::kExplorer : Mode::kReconstructor;
      return modes;
    case ModePolicy::kSwitch:
      break;
  }
  int num_exp = 0, num_rec = 0;
  for (const AssignTask& t : input.tasks) ++(t.type == TaskType::kExploration ? num_exp : num_rec);
  if (num_exp + num_rec == 0) return modes;
  if (num_rec == 0) return std::vector<Mode>(modes.size(), Mode::kExplorer);
  if (num_exp == 0) return std::vector<Mode>(modes.size(), Mode::kReconstructor);
  if (R == 1) {
    if (num_exp != num_rec) modes[0] = num_exp > num_rec ? Mode::kExplorer : Mode::kReconstructor;
    return modes;
  }
  const int want_exp = std::clamp(
      static_cast<int>(std::lround(static_cast<double>(R) * num_exp / (num_exp + num_rec))), 1,
      R - 1);
  const int have_exp = static_cast<int>(std::count(modes.begin(), modes.end(), Mode::kExplorer));
  if (want_exp == have_exp) return modes;
  // The robots that switch are those nearest the tasks of their new mode.
  const Mode from = want_exp < have_exp ? Mode::kExplorer : Mode::kReconstructor;
  const Mode to = from == Mode::kExplorer ? Mode::kReconstructor : Mode::kExplorer;
  std::vector<std::pair<double, int>> nearest;
  for (int r = 0; r < R; ++r) {
    if (modes[r] != from) continue;
    double d = kInf;
    for (int k = 0; k < static_cast<int>(input.tasks.size()); ++k)
      if (ModeOf(input.tasks[k].type) == to) d = std::min(d, input.distance(r, R + k));
    nearest.push_back({d, r});
  }
  std::sort(nearest.begin(), nearest.end());
  const int flips = std::abs(want_exp - have_exp);
  for (int i = 0; i < flips; ++i) modes[nearest[i].second] = to;
  return modes;
}

Clustering ClusterTasks(const AssignmentInput& input, const std::vector<Mode>& modes,
                        const AssignmentParams& params) {
  const Problem pb(input, params);
  std::vector<int> medoid;
  std::vector<int> label = KMedoids(pb, modes, &medoid);
  if (params.lambda_c > 0.0 && params.gmm_iterations > 0)
    label = CapacityGmm(pb, modes, std::move(label), std::move(medoid));
  Descend(pb, modes, &label);
  Clustering c;
  const auto members = Members(pb, label);
  for (int r = 0; r < pb.num_robots; ++r) {
    int m = r;
    c.energy_d += Eq5Term(pb, r, members[r], &m);
    c.energy_c += pb.CapacityTerm(r, static_cast<double>(members[r].size()));
  }
  const auto unassigned = std::count(label.begin(), label.end(), -1);
  c.energy = c.energy_d + params.lambda_c * c.energy_c +
             params.unassigned_penalty_s * static_cast<double>(unassigned);
  c.task_robot = std::move(label);
  return c;
}

std::size_t EnergyCutPosition(const omt::DistanceMatrix& distance, int start_node,
                              const std::vector<int>& sequence_nodes, double max_hop_m,
                              int cut_from) {
  const std::size_t first = static_cast<std::size_t>(std::max(cut_from, 1) - 1);
  for (std::size_t i = first; i < sequence_nodes.size(); ++i) {
    const int prev = i == 0 ? start_node : sequence_nodes[i - 1];
    if (!(distance(prev, sequence_nodes[i]) <= max_hop_m)) return i;  // +inf is cut too
  }
  return sequence_nodes.size();
}

AssignmentResult AssignTasks(const AssignmentInput& input, const AssignmentParams& params) {
  AssignmentResult result;
  result.status = ValidateAssignment(input);
  if (!result.status.ok()) return result;
  const int R = static_cast<int>(input.robots.size());
  const int K = static_cast<int>(input.tasks.size());

  // (1) InitialClustering, (2) simulated annealing over the modes.
  std::vector<Mode> modes = InitialModes(input, params);
  std::map<std::vector<Mode>, Clustering> seen;
  const auto evaluate = [&](const std::vector<Mode>& m) -> const Clustering& {
    auto it = seen.find(m);
    if (it == seen.end()) it = seen.emplace(m, ClusterTasks(input, m, params)).first;
    return it->second;
  };
  std::vector<Mode> best = modes;
  double best_energy = evaluate(modes).energy;
  if (AnnealModes(input, params)) {
    std::mt19937_64 rng(params.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double current_energy = best_energy;
    double temperature = std::max(params.sa_initial_temperature * current_energy, kEps);
    for (int it = 0; it < params.sa_max_iterations; ++it) {
      if (params.out_of_time && params.out_of_time()) break;
      std::vector<Mode> candidate = modes;
      if (!Disturb(&rng, &candidate)) break;
      ++result.sa_iterations;
      const double e = evaluate(candidate).energy;
      const double delta = e - current_energy;
      if (delta <= 0.0 || unit(rng) < std::exp(-delta / temperature)) {
        modes = std::move(candidate);
        current_energy = e;
        if (e < best_energy - kEps) {
          best_energy = e;
          best = modes;
        }
      }
      temperature *= params.sa_cooling;
    }
  }
  const Clustering& chosen = evaluate(best);
  result.energy_d = chosen.energy_d;
  result.energy_c = chosen.energy_c;
  result.energy = chosen.energy;

  // (3) An open TSP path per robot from its T^end, (4) the traveling-energy cut.
  const Problem pb(input, params);
  const auto members = Members(pb, chosen.task_robot);
  result.robots.resize(static_cast<std::size_t>(R));
  for (int k = 0; k < K; ++k)
    if (chosen.task_robot[k] < 0) result.dropped.push_back(k);
  for (int r = 0; r < R; ++r) {
    RobotPlan& plan = result.robots[r];
    plan.mode = best[r];
    const std::vector<int>& m = members[r];
    if (m.empty()) continue;
    const int n = static_cast<int>(m.size()) + 1;
    std::vector<int> nodes{r};
    for (int k : m) nodes.push_back(pb.TaskNode(k));
    omt::DistanceMatrix sub(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        const double d = input.distance(nodes[a], nodes[b]);
        sub(a, b) = std::isfinite(d) ? d : kUnreachable;
      }
    const std::vector<int> order = OpenPathFreeEnd(sub, params.tsp);
    std::vector<int> sequence;  // matrix nodes after T^end
    for (std::size_t i = 1; i < order.size(); ++i) sequence.push_back(nodes[order[i]]);
    const std::size_t keep =
        params.energy_cut
            ? EnergyCutPosition(input.distance, r, sequence, params.max_hop_m, params.cut_from)
            : sequence.size();
    int prev = r;
    for (std::size_t i = 0; i < sequence.size(); ++i) {
      const int k = sequence[i] - R;
      if (i >= keep) {
        result.dropped.push_back(k);
        continue;
      }
      plan.tasks.push_back(k);
      plan.path_m += input.distance(prev, sequence[i]);
      prev = sequence[i];
    }
    if (plan.mode != input.robots[r].mode) ++result.mode_changes;
  }
  std::sort(result.dropped.begin(), result.dropped.end());
  return result;
}

}  // namespace voxplan::taskflow
