#include "plugins/omt/algorithms/assignment.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <utility>

namespace voxplan::omt {
namespace {

constexpr double kImprovement = 1e-9;  // moves must gain more than rounding noise

// Compactness + distance of one robot's task set with its best medoid; returns the medoid.
double RobotClusterCost(const AssignmentProblem& p, int robot, const std::vector<int>& members,
                        int* medoid) {
  double best = std::numeric_limits<double>::infinity();
  int best_j = -1;
  for (int j : members) {
    double c = robot >= 0 ? p.robot_task(robot, j) : 0.0;
    for (int k : members) c += p.task_task(k, j);
    if (c < best) {
      best = c;
      best_j = j;
    }
  }
  if (medoid) *medoid = best_j;
  return members.empty() ? 0.0 : best;
}

double CapacityTerm(double n, double c) { return (n - c) * (n - c); }

// Eq. 4's term of one robot holding `members`: compactness + distance (best medoid) + capacity.
double RobotTerm(const AssignmentProblem& p, int robot, const std::vector<int>& members,
                 int* medoid) {
  return RobotClusterCost(p, robot, members, medoid) +
         CapacityTerm(static_cast<double>(members.size()),
                      p.capacity[static_cast<std::size_t>(robot)]);
}

// Each robot's tasks (ascending) under a labelling; unassigned tasks (-1) are left out.
std::vector<std::vector<int>> TasksByRobot(const AssignmentProblem& p,
                                           const std::vector<int>& task_robot) {
  std::vector<std::vector<int>> members(static_cast<std::size_t>(p.num_robots));
  for (int k = 0; k < p.num_tasks; ++k) {
    const int r = task_robot[static_cast<std::size_t>(k)];
    if (r >= 0) members[static_cast<std::size_t>(r)].push_back(k);
  }
  return members;
}

struct Cluster {
  int robot = -1;   // seeding robot, -1 for a task seed
  int center = -1;  // medoid task; -1 = the robot's own position (before it has tasks)
};

double DistToCluster(const AssignmentProblem& p, const Cluster& c, int task) {
  return c.center < 0 ? p.robot_task(c.robot, task) : p.task_task(task, c.center);
}

// Capacity relaxation with fixed centres: single moves and pairwise swaps while
// Σ distance-to-centre + Σ capacity terms of robot clusters decreases.
// With refinement on, a task may only move into a medoid-centred cluster within max_join_m
// of its centre: otherwise the relaxation would undo every split the refinement makes.
void Relax(const AssignmentProblem& p, const std::vector<Cluster>& clusters, double max_join_m,
           std::vector<int>* labels) {
  auto may_join = [&](int task, int c) {
    return clusters[c].center < 0 || DistToCluster(p, clusters[c], task) <= max_join_m;
  };
  const int n_clusters = static_cast<int>(clusters.size());
  std::vector<int> sizes(n_clusters, 0);
  for (int l : *labels) ++sizes[l];
  auto cap = [&](int c, int n) {
    return clusters[c].robot >= 0 ? CapacityTerm(n, p.capacity[clusters[c].robot]) : 0.0;
  };
  bool improved = true;
  for (int pass = 0; improved && pass < 100; ++pass) {
    improved = false;
    for (int k = 0; k < p.num_tasks; ++k) {
      const int a = (*labels)[k];
      int best_b = -1;
      double best_delta = -kImprovement;
      for (int b = 0; b < n_clusters; ++b) {
        if (b == a || !may_join(k, b)) continue;
        const double delta = DistToCluster(p, clusters[b], k) - DistToCluster(p, clusters[a], k) +
                             cap(b, sizes[b] + 1) - cap(b, sizes[b]) + cap(a, sizes[a] - 1) -
                             cap(a, sizes[a]);
        if (delta < best_delta) {
          best_delta = delta;
          best_b = b;
        }
      }
      if (best_b >= 0) {
        --sizes[a];
        ++sizes[best_b];
        (*labels)[k] = best_b;
        improved = true;
      }
    }
    for (int k = 0; k < p.num_tasks; ++k) {
      for (int l = k + 1; l < p.num_tasks; ++l) {
        const int a = (*labels)[k];
        const int b = (*labels)[l];
        if (a == b || !may_join(k, b) || !may_join(l, a)) continue;
        const double delta = DistToCluster(p, clusters[b], k) + DistToCluster(p, clusters[a], l) -
                             DistToCluster(p, clusters[a], k) - DistToCluster(p, clusters[b], l);
        if (delta < -kImprovement) {
          (*labels)[k] = b;
          (*labels)[l] = a;
          improved = true;
        }
      }
    }
  }
}

// Exact eq. 4 descent over robot labels: single moves, swaps, cluster exchanges, and, on small
// instances (K²R² <= kPairMoveBudget), any simultaneous move of two tasks, which escapes most of
// the local optima single moves leave.
constexpr long kPairMoveBudget = 40000;

void Polish(const AssignmentProblem& p, std::vector<int>* task_robot) {
  const int R = p.num_robots;
  const int K = p.num_tasks;
  std::vector<int>& labels = *task_robot;
  auto robot_cost = [&](int r) {
    std::vector<int> m;
    for (int k = 0; k < K; ++k)
      if (labels[k] == r) m.push_back(k);
    return RobotTerm(p, r, m, nullptr);
  };
  std::vector<double> cost(R);
  for (int r = 0; r < R; ++r) cost[r] = robot_cost(r);
  // Applies the relabelling (task, robot) pairs if eq. 4 drops; otherwise restores.
  auto try_change = [&](std::initializer_list<std::pair<int, int>> change) {
    int affected[4];
    int n_aff = 0;
    auto add = [&](int r) {
      for (int i = 0; i < n_aff; ++i)
        if (affected[i] == r) return;
      affected[n_aff++] = r;
    };
    int old_label[2];
    int i = 0;
    for (const auto& [k, r] : change) {
      add(labels[k]);
      add(r);
      old_label[i++] = labels[k];
    }
    double before = 0.0;
    for (int a = 0; a < n_aff; ++a) before += cost[affected[a]];
    for (const auto& [k, r] : change) labels[k] = r;
    double after = 0.0;
    double new_cost[4];
    for (int a = 0; a < n_aff; ++a) after += new_cost[a] = robot_cost(affected[a]);
    if (after < before - kImprovement) {
      for (int a = 0; a < n_aff; ++a) cost[affected[a]] = new_cost[a];
      return true;
    }
    i = 0;
    for (const auto& [k, r] : change) labels[k] = old_label[i++];
    return false;
  };
  const bool pairs = static_cast<long>(K) * K * R * R <= kPairMoveBudget;
  bool improved = true;
  for (int pass = 0; improved && pass < 50; ++pass) {
    improved = false;
    for (int k = 0; k < K; ++k) {
      if (labels[k] < 0) continue;
      for (int b = 0; b < R; ++b)
        if (b != labels[k] && try_change({{k, b}})) improved = true;
    }
    for (int k = 0; k < K; ++k) {
      for (int l = k + 1; l < K; ++l) {
        const int a = labels[k];
        const int b = labels[l];
        if (a < 0 || b < 0 || a == b) continue;
        if (try_change({{k, b}, {l, a}})) improved = true;
      }
    }
    // Whole-cluster exchange between two robots: Lloyd keeps clusters but may hand them to the
    // wrong robots.
    for (int a = 0; a < R; ++a) {
      for (int b = a + 1; b < R; ++b) {
        const double before = cost[a] + cost[b];
        for (int& l : labels) l = l == a ? b : (l == b ? a : l);
        const double ca = robot_cost(a);
        const double cb = robot_cost(b);
        if (ca + cb < before - kImprovement) {
          cost[a] = ca;
          cost[b] = cb;
          improved = true;
        } else {
          for (int& l : labels) l = l == a ? b : (l == b ? a : l);
        }
      }
    }
    if (!pairs || improved) continue;
    for (int k = 0; k < K; ++k) {
      for (int l = k + 1; l < K; ++l) {
        if (labels[k] < 0 || labels[l] < 0) continue;
        for (int b = 0; b < R; ++b) {
          for (int c = 0; c < R; ++c) {
            if (b == labels[k] || c == labels[l] || labels[k] < 0 || labels[l] < 0) continue;
            if (try_change({{k, b}, {l, c}})) improved = true;
          }
        }
      }
    }
  }
}

}  // namespace

std::vector<double> RobotCapacities(int num_tasks, const std::vector<double>& speeds_mps) {
  std::vector<double> caps(speeds_mps.size(), 0.0);
  if (speeds_mps.empty()) return caps;
  const double v_max = *std::max_element(speeds_mps.begin(), speeds_mps.end());
  if (v_max <= 0.0) return caps;
  const double share = static_cast<double>(num_tasks) / static_cast<double>(speeds_mps.size());
  for (std::size_t r = 0; r < speeds_mps.size(); ++r) caps[r] = share * speeds_mps[r] / v_max;
  return caps;
}

namespace {

double NearestTaskM(const AssignmentProblem& p, int robot) {
  double nearest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < p.num_tasks; ++k) nearest = std::min(nearest, p.robot_task(robot, k));
  return nearest;
}

// C_r = 0 except for `sharing` (robot indices), which split the tasks by RobotCapacities.
std::vector<double> SharedAmong(const AssignmentProblem& p, const std::vector<double>& speeds_mps,
                                const std::vector<int>& sharing) {
  std::vector<double> speeds;
  for (int r : sharing) speeds.push_back(speeds_mps[static_cast<std::size_t>(r)]);
  const std::vector<double> shared = RobotCapacities(p.num_tasks, speeds);
  std::vector<double> caps(static_cast<std::size_t>(p.num_robots), 0.0);
  for (std::size_t i = 0; i < sharing.size(); ++i)
    caps[static_cast<std::size_t>(sharing[i])] = shared[i];
  return caps;
}

}  // namespace

std::vector<double> ReachCapacities(const AssignmentProblem& p,
                                    const std::vector<double>& speeds_mps,
                                    const std::vector<double>& reach_m) {
  const int R = p.num_robots;
  if (R <= 0 || p.num_tasks <= 0 || speeds_mps.size() != static_cast<std::size_t>(R) ||
      reach_m.size() != static_cast<std::size_t>(R))
    return std::vector<double>(static_cast<std::size_t>(std::max(R, 0)), 0.0);
  std::vector<double> nearest;
  for (int r = 0; r < R; ++r) nearest.push_back(NearestTaskM(p, r));
  const double closest = *std::min_element(nearest.begin(), nearest.end());
  std::vector<int> near;
  for (int r = 0; r < R; ++r)
    if (nearest[r] <= closest + reach_m[r]) near.push_back(r);
  return SharedAmong(p, speeds_mps, near);
}

std::vector<double> TeamCapacities(const AssignmentProblem& p,
                                   const std::vector<double>& speeds_mps,
                                   const std::vector<double>& driven_m, double views_per_robot,
                                   double driven_weight) {
  if (!(views_per_robot > 0.0) || p.num_tasks <= 0 || p.capacity.size() != speeds_mps.size() ||
      p.capacity.size() != driven_m.size())
    return p.capacity;
  std::vector<std::pair<double, int>> busy;  // (load, robot) of the robots with capacity
  for (int r = 0; r < p.num_robots; ++r) {
    if (!(p.capacity[static_cast<std::size_t>(r)] > 0.0)) continue;
    busy.emplace_back(driven_weight * driven_m[static_cast<std::size_t>(r)] + NearestTaskM(p, r),
                      r);
  }
  const auto keep = static_cast<std::size_t>(std::ceil(p.num_tasks / views_per_robot));
  if (busy.size() <= keep) return p.capacity;
  std::sort(busy.begin(), busy.end());
  std::vector<int> kept;
  for (std::size_t i = 0; i < keep; ++i) kept.push_back(busy[i].second);
  return SharedAmong(p, speeds_mps, kept);
}

double Eq4Cost(const AssignmentProblem& p, const std::vector<int>& task_robot) {
  const std::vector<std::vector<int>> members = TasksByRobot(p, task_robot);
  double cost = 0.0;
  for (int r = 0; r < p.num_robots; ++r) cost += RobotTerm(p, r, members[r], nullptr);
  return cost;
}

Status ValidateProblem(const AssignmentProblem& p) {
  const int K = p.num_tasks;
  const int R = p.num_robots;
  if (K < 0 || R < 0 || p.task_task.rows != K || p.task_task.cols != K ||
      p.task_task.values.size() != static_cast<std::size_t>(K) * K || p.robot_task.rows != R ||
      p.robot_task.cols != K || p.robot_task.values.size() != static_cast<std::size_t>(R) * K ||
      p.capacity.size() != static_cast<std::size_t>(R))
    return Status::Error(Status::Code::kInvalidInput, "assignment problem sizes disagree");
  return Status::Ok();
}

Assignment AssignTasks(const AssignmentProblem& p, const AssignmentParams& params) {
  Assignment out;
  const int K = std::max(0, p.num_tasks);
  const int R = p.num_robots;
  out.task_robot.assign(K, -1);
  out.task_cluster.assign(K, -1);
  if (!ValidateProblem(p).ok()) return out;
  if (R <= 0 || K <= 0) {
    out.converged = true;
    return out;
  }
  // K-means seeded by the robots (K = R initially, §4).
  std::vector<Cluster> clusters(R);
  for (int r = 0; r < R; ++r) clusters[r].robot = r;
  std::vector<int> labels(K, -1);
  std::vector<int> previous;
  for (int it = 0; it < params.max_iterations; ++it) {
    out.iterations = it + 1;
    // Assignment step: nearest centre, ties to the lower cluster index.
    for (int k = 0; k < K; ++k) {
      double best = std::numeric_limits<double>::infinity();
      for (int c = 0; c < static_cast<int>(clusters.size()); ++c) {
        const double d = DistToCluster(p, clusters[c], k);
        if (d < best) {
          best = d;
          labels[k] = c;
        }
      }
    }
    Relax(p, clusters, params.refine ? params.delta_m : std::numeric_limits<double>::infinity(),
          &labels);
    // Update step: medoids; task-seeded clusters that lost every task disappear.
    std::vector<std::vector<int>> members(clusters.size());
    for (int k = 0; k < K; ++k) members[labels[k]].push_back(k);
    std::vector<Cluster> next;
    std::vector<int> remap(clusters.size(), -1);
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      if (members[c].empty() && clusters[c].robot < 0) continue;
      Cluster cl = clusters[c];
      if (members[c].empty()) {
        cl.center = -1;
      } else {
        RobotClusterCost(p, cl.robot, members[c], &cl.center);
      }
      remap[c] = static_cast<int>(next.size());
      next.push_back(cl);
    }
    for (int& l : labels) l = remap[l];
    // Refinement: the most off-centre task of a non-compact or over-capacity cluster seeds a
    // new cluster for the next iteration.
    bool split = false;
    if (params.refine) {
      const std::size_t n_before = next.size();
      std::vector<std::vector<int>> m2(n_before);
      for (int k = 0; k < K; ++k) m2[labels[k]].push_back(k);
      for (std::size_t c = 0; c < n_before; ++c) {
        if (m2[c].size() < 2) continue;
        int far = -1;
        double far_d = -1.0;
        for (int k : m2[c]) {
          const double d = p.task_task(k, next[c].center);
          if (d > far_d) {
            far_d = d;
            far = k;
          }
        }
        const bool over_capacity =
            next[c].robot >= 0 &&
            static_cast<double>(m2[c].size()) > std::ceil(p.capacity[next[c].robot] - 1e-9);
        if (far_d > params.delta_m || over_capacity) {
          next.push_back({-1, far});
          split = true;
        }
      }
    }
    clusters = std::move(next);
    const bool stable = labels == previous;
    previous = labels;
    if (stable && !split) {
      out.converged = true;
      break;
    }
  }
  out.cluster_robot.resize(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) out.cluster_robot[c] = clusters[c].robot;
  out.task_cluster = labels;
  for (int k = 0; k < K; ++k) out.task_robot[k] = clusters[labels[k]].robot;
  if (!params.refine && params.polish) Polish(p, &out.task_robot);
  out.cost = Eq4Cost(p, out.task_robot);
  return out;
}

void HandOutUnassigned(const AssignmentProblem& problem, double unreachable_m, Assignment* a,
                       const std::vector<double>& reach_m) {
  std::vector<int> tasks_of(static_cast<std::size_t>(problem.num_robots), 0);
  for (int r : a->task_robot)
    if (r >= 0) ++tasks_of[static_cast<std::size_t>(r)];
  bool changed = false;
  for (int r = 0; r < problem.num_robots; ++r) {
    if (tasks_of[static_cast<std::size_t>(r)] > 0) continue;
    int best_cluster = -1;
    double best_m = unreachable_m;  // unreachable tasks are not handed out
    for (int k = 0; k < problem.num_tasks; ++k) {
      if (a->task_robot[static_cast<std::size_t>(k)] >= 0) continue;
      if (!reach_m.empty()) {
        double other_m = unreachable_m;
        for (int q = 0; q < problem.num_robots; ++q)
          if (q != r) other_m = std::min(other_m, problem.robot_task(q, k));
        if (problem.robot_task(r, k) > other_m + reach_m[static_cast<std::size_t>(r)]) continue;
      }
      if (problem.robot_task(r, k) < best_m) {
        best_m = problem.robot_task(r, k);
        best_cluster = a->task_cluster[static_cast<std::size_t>(k)];
      }
    }
    if (best_cluster < 0) continue;  // none it can reach
    for (int k = 0; k < problem.num_tasks; ++k) {
      if (a->task_cluster[static_cast<std::size_t>(k)] == best_cluster)
        a->task_robot[static_cast<std::size_t>(k)] = r;
    }
    a->cluster_robot[static_cast<std::size_t>(best_cluster)] = r;
    changed = true;
  }
  if (changed) a->cost = Eq4Cost(problem, a->task_robot);
}

void BalanceLoads(const AssignmentProblem& p, const std::vector<double>& driven_m,
                  double tolerance_m, Assignment* a) {
  const int R = p.num_robots;
  if (static_cast<int>(driven_m.size()) != R) return;
  std::vector<std::vector<int>> members = TasksByRobot(p, a->task_robot);
  // Eq. 4's robot term and the load of robot r holding task set m, from one medoid search.
  struct Eval {
    double cost;
    double load_m;
  };
  auto eval = [&](int r, const std::vector<int>& m) {
    int medoid = -1;
    const double cost = RobotTerm(p, r, m, &medoid);
    return Eval{
        cost, driven_m[static_cast<std::size_t>(r)] + (m.empty() ? 0.0 : p.robot_task(r, medoid))};
  };
  std::vector<Eval> own;  // each robot with its current task set; updated on exchange
  for (int r = 0; r < R; ++r) own.push_back(eval(r, members[static_cast<std::size_t>(r)]));
  bool changed = false;
  bool improved = true;
  for (int pass = 0; improved && pass < 10; ++pass) {
    improved = false;
    for (int x = 0; x < R; ++x) {
      for (int y = x + 1; y < R; ++y) {
        std::vector<int>& mx = members[static_cast<std::size_t>(x)];
        std::vector<int>& my = members[static_cast<std::size_t>(y)];
        if (mx.empty() && my.empty()) continue;
        Eval& own_x = own[static_cast<std::size_t>(x)];
        Eval& own_y = own[static_cast<std::size_t>(y)];
        const Eval new_x = eval(x, my), new_y = eval(y, mx);
        if (new_x.cost + new_y.cost > own_x.cost + own_y.cost + tolerance_m) continue;
        if (std::max(new_x.load_m, new_y.load_m) >=
            std::max(own_x.load_m, own_y.load_m) - kMinLoadGainM)
          continue;
        std::swap(mx, my);
        own_x = new_x;
        own_y = new_y;
        ++a->load_exchanges;
        improved = changed = true;
      }
    }
  }
  if (!changed) return;
  for (int r = 0; r < R; ++r)
    for (int k : members[static_cast<std::size_t>(r)])
      a->task_robot[static_cast<std::size_t>(k)] = r;
  // A cluster goes with its tasks.
  for (std::size_t k = 0; k < a->task_robot.size(); ++k)
    if (a->task_robot[k] >= 0 && a->task_cluster[k] >= 0)
      a->cluster_robot[static_cast<std::size_t>(a->task_cluster[k])] = a->task_robot[k];
  a->cost = Eq4Cost(p, a->task_robot);
}

Assignment BruteForceAssignment(const AssignmentProblem& p, long max_labellings) {
  Assignment out;
  const int K = p.num_tasks;
  const int R = p.num_robots;
  if (R <= 0 || !ValidateProblem(p).ok()) return out;
  double count = std::pow(static_cast<double>(R), K);
  if (count > static_cast<double>(max_labellings)) return out;
  std::vector<int> labels(K, 0);
  std::vector<int> best = labels;
  double best_cost = Eq4Cost(p, labels);
  while (true) {
    int i = 0;  // odometer increment over R^K labellings
    while (i < K && ++labels[i] == R) labels[i++] = 0;
    if (i == K) break;
    const double c = Eq4Cost(p, labels);
    if (c < best_cost - kImprovement) {
      best_cost = c;
      best = labels;
    }
  }
  out.task_robot = best;
  out.task_cluster = best;
  out.cluster_robot.resize(R);
  for (int r = 0; r < R; ++r) out.cluster_robot[r] = r;
  out.converged = true;
  out.cost = best_cost;
  return out;
}

}  // namespace voxplan::omt
