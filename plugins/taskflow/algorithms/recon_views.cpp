#include "plugins/taskflow/algorithms/recon_views.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

namespace voxplan::taskflow {
namespace {

constexpr float kPi = 3.14159265358979323846f;

// A reachable camera position with the base pose found for it.
struct Candidate {
  ReconView view;
  std::vector<int> in_cone;  // predicted points in its cone, facing it, with a score
  float optimistic = 0.0f;   // Σ S̄ over in_cone: coverage if everything were visible
};

Eigen::Vector3f ApexAxis(const ReconTarget& t, int q, const Eigen::Vector2f& centre_xy,
                         float max_elevation) {
  const Eigen::Vector3f& p = t.points[static_cast<std::size_t>(q)];
  if (!t.normals.empty()) {
    const Eigen::Vector3f n = t.normals[static_cast<std::size_t>(q)];
    if (n.squaredNorm() > 1e-12f) {
      const Eigen::Vector3f u = n.normalized();
      if (std::abs(u.z()) <= std::sin(max_elevation)) return u;
    }
  }
  const Eigen::Vector2f out = p.head<2>() - centre_xy;
  if (out.squaredNorm() < 1e-12f) return Eigen::Vector3f::UnitX();
  const Eigen::Vector2f d = out.normalized();
  return {d.x(), d.y(), 0.0f};
}

// Directions in q's cone: the axis and cone_tilts rings, the outer one on the cone's surface.
std::vector<Eigen::Vector3f> ConeDirections(const Eigen::Vector3f& axis, float half_angle,
                                            const ReconViewParams& params) {
  const Eigen::Vector3f helper =
      std::abs(axis.z()) < 0.9f ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
  const Eigen::Vector3f e1 = axis.cross(helper).normalized();
  const Eigen::Vector3f e2 = axis.cross(e1);
  std::vector<Eigen::Vector3f> dirs = {axis};
  const int tilts = std::max(0, params.cone_tilts);
  const int azimuths = std::max(1, params.cone_azimuths);
  for (int k = 1; k <= tilts; ++k) {
    const float tilt = half_angle * static_cast<float>(k) / static_cast<float>(tilts);
    for (int j = 0; j < azimuths; ++j) {
      const float phi = 2.0f * kPi * static_cast<float>(j) / static_cast<float>(azimuths);
      dirs.push_back(std::cos(tilt) * axis +
                     std::sin(tilt) * (std::cos(phi) * e1 + std::sin(phi) * e2));
    }
  }
  return dirs;
}

float WrapAngle(float a) { return std::atan2(std::sin(a), std::cos(a)); }

// The base pose for a camera at W looking with `yaw`: the base faces the same way and the arm's
// horizontal offset stays in the workspace. False when no tried base position is traversable.
bool FindBase(const Eigen::Vector3f& camera, float yaw, const ReconViewParams& params,
              const TraversableFn& traversable, ReconView* view) {
  const ArmWorkspace& arm = params.arm;
  const int bearings = std::max(1, params.base_bearings);
  const int reaches = std::max(1, params.base_reaches);
  // Bearings ordered by distance from straight ahead: 0, +δ, -δ, +2δ, ...
  std::vector<float> bearing_order;
  const int half = bearings / 2;
  const float delta = half > 0 ? arm.reach_half_angle_rad / static_cast<float>(half) : 0.0f;
  bearing_order.push_back(0.0f);
  for (int i = 1; i <= half; ++i) {
    bearing_order.push_back(delta * static_cast<float>(i));
    bearing_order.push_back(-delta * static_cast<float>(i));
  }
  for (const float beta : bearing_order) {
    for (int r = 0; r < reaches; ++r) {
      const float reach = reaches == 1 ? 0.5f * (arm.reach_min_m + arm.reach_max_m)
                                       : arm.reach_max_m - (arm.reach_max_m - arm.reach_min_m) *
                                                               static_cast<float>(r) /
                                                               static_cast<float>(reaches - 1);
      const Eigen::Vector2f offset_dir(std::cos(yaw + beta), std::sin(yaw + beta));
      const Eigen::Vector2f base = camera.head<2>() - reach * offset_dir;
      if (!traversable(base)) continue;
      view->base_xy_m = base;
      view->base_yaw_rad = WrapAngle(yaw);
      view->camera_forward_m = reach * std::cos(beta);
      view->camera_left_m = reach * std::sin(beta);
      return true;
    }
  }
  return false;
}

// In the view's cone (half-angle hfov/2 about the direction to its target, within the sensor's
// range) and, when the normal is known, facing the camera.
bool InViewCone(const Eigen::Vector3f& camera, const Eigen::Vector3f& axis, float cos_half,
                const Eigen::Vector3f& p, const Eigen::Vector3f* normal,
                const ReconViewParams& params) {
  const Eigen::Vector3f v = p - camera;
  const float d = v.norm();
  if (d < params.sensor.min_range_m || d > params.sensor.max_range_m) return false;
  if (v.dot(axis) < d * cos_half) return false;
  if (normal != nullptr && params.backface_cull && normal->squaredNorm() > 1e-12f &&
      normal->dot(-v) <= 0.0f)
    return false;
  return true;
}

std::vector<Candidate> MakeCandidates(const ReconTarget& t, int q, const Eigen::Vector2f& centre,
                                      const std::vector<float>& scores,
                                      const ReconViewParams& params,
                                      const TraversableFn& traversable,
                                      const ObjectHistory* history,
                                      const HistoryParams& history_params) {
  const Eigen::Vector3f apex = t.points[static_cast<std::size_t>(q)];
  const float half_angle = 0.5f * params.sensor.hfov_rad;
  const float cos_half = std::cos(half_angle);
  const float apex_range = params.apex_range_factor * params.sensor.max_range_m;
  const Eigen::Vector3f axis = ApexAxis(t, q, centre, params.max_axis_elevation_rad);
  const int n_dist = std::max(1, params.candidate_distances);
  std::vector<Candidate> out;
  for (const Eigen::Vector3f& dir : ConeDirections(axis, half_angle, params)) {
    for (int i = 0; i < n_dist; ++i) {
      const float dist =
          n_dist == 1
              ? params.distance_min_m
              : params.distance_min_m + (params.distance_max_m - params.distance_min_m) *
                                            static_cast<float>(i) / static_cast<float>(n_dist - 1);
      if (dist > apex_range || dist < params.sensor.min_range_m || dist > params.sensor.max_range_m)
        continue;
      Candidate c;
      ReconView& v = c.view;
      v.object_id = t.object_id;
      v.camera_m = apex + dist * dir;
      v.target_m = apex;
      v.camera_height_m = v.camera_m.z() - t.floor_z_m;
      if (v.camera_height_m < params.arm.camera_height_min_m ||
          v.camera_height_m > params.arm.camera_height_max_m)
        continue;
      const Eigen::Vector3f look = apex - v.camera_m;
      const float horizontal = look.head<2>().norm();
      v.pitch_rad = std::atan2(look.z(), horizontal);
      if (v.pitch_rad < params.arm.min_pitch_rad || v.pitch_rad > params.arm.max_pitch_rad)
        continue;
      // Straight down the yaw is free: face the object's centre.
      const Eigen::Vector2f yaw_dir =
          horizontal > 1e-4f ? Eigen::Vector2f(look.head<2>()) : centre - v.camera_m.head<2>();
      v.yaw_rad = std::atan2(yaw_dir.y(), yaw_dir.x());
      if (history != nullptr && NeighbourhoodExhausted(*history, v.camera_m, history_params))
        continue;
      if (!FindBase(v.camera_m, v.yaw_rad, params, traversable, &v)) continue;
      const Eigen::Vector3f view_axis = look.normalized();
      for (std::size_t k = 0; k < t.points.size(); ++k) {
        if (scores[k] <= 0.0f) continue;
        const Eigen::Vector3f* n = t.normals.empty() ? nullptr : &t.normals[k];
        if (!InViewCone(v.camera_m, view_axis, cos_half, t.points[k], n, params)) continue;
        c.in_cone.push_back(static_cast<int>(k));
        c.optimistic += scores[k];
      }
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace

ReconTarget TargetFromCompletion(int object_id, float floor_z_m, const CompletionResult& c) {
  ReconTarget t;
  t.object_id = object_id;
  t.floor_z_m = floor_z_m;
  t.points = c.predicted;
  t.normals = c.normals;
  t.scores = c.score;
  return t;
}

void ObserveCompleteness(ReconHistory* history, int object_id, double completeness,
                         const HistoryParams& params) {
  auto it = history->objects.find(object_id);
  if (it == history->objects.end()) return;
  for (ScanRecord& s : it->second.scans) {
    if (s.outcome != ScanRecord::kPending) continue;
    const double needed = s.completeness_before * (1.0 + params.min_gain_rel) + params.min_gain_abs;
    s.outcome = completeness > needed ? ScanRecord::kGain : ScanRecord::kNoGain;
  }
}

void RecordViews(ReconHistory* history, int object_id, std::span<const ReconView> views,
                 double completeness) {
  ObjectHistory& h = history->objects[object_id];
  const int round = h.rounds++;
  for (const ReconView& v : views) {
    ScanRecord s;
    s.camera_m = v.camera_m;
    s.round = round;
    s.completeness_before = completeness;
    h.scans.push_back(s);
  }
}

const ObjectHistory* FindHistory(const ReconHistory& history, int object_id) {
  const auto it = history.objects.find(object_id);
  return it == history.objects.end() ? nullptr : &it->second;
}

bool NeighbourhoodExhausted(const ObjectHistory& history, const Eigen::Vector3f& camera_m,
                            const HistoryParams& params) {
  if (params.strikes <= 0) return false;
  // Settled rounds with a scan nearby, latest first; a round gained if any of its scans did
  // (they share the object's outcome). Scans are appended in round order.
  const float r2 = params.neighbourhood_m * params.neighbourhood_m;
  std::vector<std::pair<int, bool>> rounds;  // (round, gained), latest first
  for (auto it = history.scans.rbegin(); it != history.scans.rend(); ++it) {
    if (it->outcome == ScanRecord::kPending) continue;
    if ((it->camera_m - camera_m).squaredNorm() > r2) continue;
    const bool gained = it->outcome == ScanRecord::kGain;
    if (rounds.empty() || rounds.back().first != it->round) {
      rounds.emplace_back(it->round, gained);
    } else {
      rounds.back().second = rounds.back().second || gained;
    }
  }
  int strikes = 0;
  for (const std::pair<int, bool>& r : rounds) {
    if (r.second) break;
    if (++strikes >= params.strikes) return true;
  }
  return false;
}

std::vector<ReconView> SelectReconViews(const ReconTarget& target, const ReconViewParams& params,
                                        const TraversableFn& traversable,
                                        const VisibilityFn& visible, const ObjectHistory* history,
                                        const HistoryParams& history_params) {
  std::vector<ReconView> views;
  const std::size_t n = target.points.size();
  if (n == 0 || target.scores.size() != n) return views;
  if (!target.normals.empty() && target.normals.size() != n) return views;

  std::vector<float> scores(target.scores.begin(), target.scores.end());
  Eigen::Vector2f centre = Eigen::Vector2f::Zero();
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    centre += target.points[i].head<2>();
    total += std::max(0.0f, scores[i]);
  }
  centre /= static_cast<float>(n);
  const float threshold =
      std::max(params.min_gain, params.min_gain_fraction * static_cast<float>(total));

  std::vector<Eigen::Vector3f> batch;
  std::vector<std::uint8_t> vis;
  int attempts = 0;
  while (static_cast<int>(views.size()) < params.max_views_per_object &&
         attempts < params.max_apex_attempts) {
    // The apex: the highest remaining score, lowest index on ties.
    int q = -1;
    for (std::size_t i = 0; i < n; ++i)
      if (scores[i] > 0.0f && (q < 0 || scores[i] > scores[static_cast<std::size_t>(q)]))
        q = static_cast<int>(i);
    if (q < 0) break;

    std::vector<Candidate> cands =
        MakeCandidates(target, q, centre, scores, params, traversable, history, history_params);
    // Ray casts are the cost: visit candidates by optimistic coverage and stop once no remaining
    // one could beat the best found (stable order keeps ties deterministic).
    std::vector<int> order(cands.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return cands[static_cast<std::size_t>(a)].optimistic >
             cands[static_cast<std::size_t>(b)].optimistic;
    });
    int best = -1;
    float best_coverage = 0.0f;
    std::vector<int> best_covered, covered;
    for (const int ci : order) {
      Candidate& c = cands[static_cast<std::size_t>(ci)];
      if (c.optimistic <= best_coverage) break;
      batch.clear();
      for (const int k : c.in_cone) batch.push_back(target.points[static_cast<std::size_t>(k)]);
      vis.assign(batch.size(), 0);
      if (!batch.empty()) visible(c.view.camera_m, batch, vis);
      covered.clear();
      float coverage = 0.0f;
      for (std::size_t j = 0; j < batch.size(); ++j) {
        if (!vis[j]) continue;
        covered.push_back(c.in_cone[j]);
        coverage += scores[static_cast<std::size_t>(c.in_cone[j])];
      }
      if (coverage > best_coverage) {
        best = ci;
        best_coverage = coverage;
        best_covered = covered;
      }
    }
    if (best < 0 || best_coverage < threshold) {
      // Nothing worthwhile reaches this apex: leave it and try the next-best point.
      scores[static_cast<std::size_t>(q)] = 0.0f;
      ++attempts;
      continue;
    }
    ReconView v = cands[static_cast<std::size_t>(best)].view;
    v.coverage = best_coverage;
    v.covered_points = static_cast<int>(best_covered.size());
    for (const int k : best_covered) scores[static_cast<std::size_t>(k)] = 0.0f;
    // The apex itself is done too, even if its own ray was blocked.
    scores[static_cast<std::size_t>(q)] = 0.0f;
    views.push_back(v);
  }
  return views;
}

}  // namespace voxplan::taskflow
