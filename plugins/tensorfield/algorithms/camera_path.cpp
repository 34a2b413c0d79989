#include "plugins/tensorfield/algorithms/camera_path.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMinDt = 1e-9;  // seconds: coincident samples allow no motion
// A dense sample counts as clamped when it moves more than this; the speed checks allow this
// relative slack (float rounding of a step shortened to exactly the limit).
constexpr float kClampTolM = 1e-5f;
constexpr float kSpeedSlack = 1e-4f;

// To [−π, π]. Differences of wrapped angles need one ±2π at most; std::remainder (slow) is the
// fallback for anything further out.
double WrapPi(double a) {
  if (a > kPi) {
    a -= 2.0 * kPi;
  } else if (a < -kPi) {
    a += 2.0 * kPi;
  }
  return a >= -kPi && a <= kPi ? a : std::remainder(a, 2.0 * kPi);
}
float WrapPiF(float a) { return static_cast<float>(WrapPi(static_cast<double>(a))); }

// Halton radical inverse of i in the given base, in [0, 1).
double RadicalInverse(int i, int base) {
  double inv = 1.0 / base, f = inv, r = 0.0;
  while (i > 0) {
    r += f * (i % base);
    i /= base;
    f *= inv;
  }
  return r;
}

// The chain of eq. 8 in doubles: the samples with candidates, their times and candidates.
struct Chain {
  std::vector<int> sample;  // path sample index of each link
  std::vector<double> time_s;
  std::vector<std::vector<Eigen::Vector3d>> q;
  std::vector<std::vector<double>> yaw, pitch, unary;  // unary: −ω_V V̂ − ω_U U
  std::vector<std::vector<double>> gain, lookat;       // its −ω_V V̂ and −ω_U U parts
};

struct Terms {
  double gain_scale = 0.0;  // 1 / max |V|
  double inv_l2 = 0.0;      // 1 / (v_m Δt̄)²
  double inv_a2 = 0.0;      // 1 / (a_m Δt̄)²
  double v_max = 0.0, a_max = 0.0;
};

Terms MakeTerms(std::span<const double> times_s,
                const std::vector<std::vector<CameraCandidate>>& candidates,
                const CameraSelectionParams& p) {
  Terms t;
  double v_best = 0.0;
  for (const auto& cs : candidates)
    for (const CameraCandidate& c : cs) v_best = std::max(v_best, std::abs(double{c.gain}));
  t.gain_scale = v_best > 0.0 ? 1.0 / v_best : 0.0;
  double dt_mean = 1.0;
  if (times_s.size() >= 2) {
    const double span = times_s.back() - times_s.front();
    if (span > 0.0) dt_mean = span / static_cast<double>(times_s.size() - 1);
  }
  t.v_max = std::max(1e-9, double{p.limits.linear_mps});
  t.a_max = std::max(1e-9, double{p.limits.angular_radps});
  t.inv_l2 = 1.0 / ((t.v_max * dt_mean) * (t.v_max * dt_mean));
  t.inv_a2 = 1.0 / ((t.a_max * dt_mean) * (t.a_max * dt_mean));
  return t;
}

Chain MakeChain(std::span<const double> times_s,
                const std::vector<std::vector<CameraCandidate>>& candidates,
                const CameraSelectionParams& p, const Terms& t) {
  Chain ch;
  const std::size_t n = std::min(times_s.size(), candidates.size());
  for (std::size_t s = 0; s < n; ++s) {
    if (candidates[s].empty()) continue;
    ch.sample.push_back(static_cast<int>(s));
    ch.time_s.push_back(times_s[s]);
    auto& q = ch.q.emplace_back();
    auto& yaw = ch.yaw.emplace_back();
    auto& pitch = ch.pitch.emplace_back();
    auto& unary = ch.unary.emplace_back();
    auto& gain = ch.gain.emplace_back();
    auto& lookat = ch.lookat.emplace_back();
    for (const CameraCandidate& c : candidates[s]) {
      q.push_back(c.position_W.cast<double>());
      yaw.push_back(c.yaw_rad);
      pitch.push_back(c.pitch_rad);
      const double v = -p.weight_gain * t.gain_scale * double{c.gain};
      // Without U the unary is bit for bit what it was before X12.
      const double u = c.lookat != 0.0f ? -p.weight_lookat * double{c.lookat} : 0.0;
      gain.push_back(v);
      lookat.push_back(u);
      unary.push_back(u != 0.0 ? v + u : v);
    }
  }
  return ch;
}

// Normalised excess of a speed over its limit (0 when within).
double Excess(double distance, double dt, double limit) {
  const double speed = distance / std::max(dt, kMinDt);
  return speed > limit ? speed / limit - 1.0 : 0.0;
}

// The speed constraints between links a and b (indices ia, ib): their cost (hard: ∞, else the
// penalty) and, optionally, the violation counts.
struct SpeedCost {
  const Chain& ch;
  const Terms& t;
  double penalty;  // kInf: hard constraints
  double operator()(int a, int ia, int b, int ib, int* lin = nullptr, int* ang = nullptr) const {
    const double dt = ch.time_s[b] - ch.time_s[a];
    const double dq = (ch.q[b][ib] - ch.q[a][ia]).norm();
    const double dy = WrapPi(ch.yaw[b][ib] - ch.yaw[a][ia]);
    const double dp = ch.pitch[b][ib] - ch.pitch[a][ia];
    const double el = Excess(dq, dt, t.v_max);
    const double ea = Excess(std::sqrt(dy * dy + dp * dp), dt, t.a_max);
    if (lin != nullptr && el > 0.0) ++*lin;
    if (ang != nullptr && ea > 0.0) ++*ang;
    if (el <= 0.0 && ea <= 0.0) return 0.0;
    return penalty == kInf ? kInf : penalty * (el + ea);
  }
};

// The step from candidate ia of link a to candidate ib of link b: position and angle differences
// (yaw wrapped), from which the second differences are formed.
struct Step {
  Eigen::Vector3d dq = Eigen::Vector3d::Zero();
  double dy = 0.0, dp = 0.0;
};

Step MakeStep(const Chain& ch, int a, int ia, int b, int ib) {
  return {ch.q[b][ib] - ch.q[a][ia], WrapPi(ch.yaw[b][ib] - ch.yaw[a][ia]),
          ch.pitch[b][ib] - ch.pitch[a][ia]};
}

// ω_L ‖q_k − 2q_i + q_j‖² / L² + ω_A ‖α_k − 2α_i + α_j‖² / A² from the steps k → i and i → j.
double Smoothness(const Step& ki, const Step& ij, const Terms& t, const CameraSelectionParams& p,
                  double* lin = nullptr, double* ang = nullptr) {
  const Eigen::Vector3d d2q = ij.dq - ki.dq;
  const double d2y = ij.dy - ki.dy, d2p = ij.dp - ki.dp;
  const double l = p.weight_linear * d2q.squaredNorm() * t.inv_l2;
  const double a = p.weight_angular * (d2y * d2y + d2p * d2p) * t.inv_a2;
  if (lin != nullptr) *lin += l;
  if (ang != nullptr) *ang += a;
  return l + a;
}

// The exact minimiser of eq. 8 (plus the speed cost) over the chain; empty when every selection
// has infinite cost.
std::vector<int> SolveChain(const Chain& ch, const Terms& t, const CameraSelectionParams& p,
                            double penalty) {
  const int n = static_cast<int>(ch.sample.size());
  const SpeedCost speed{ch, t, penalty};
  const bool adjacent = p.limit_adjacent_steps;
  std::vector<int> sel(static_cast<std::size_t>(n), 0);
  if (n == 0) return sel;
  if (n == 1) {
    const auto& u = ch.unary[0];
    sel[0] = static_cast<int>(std::min_element(u.begin(), u.end()) - u.begin());
    return sel;
  }
  auto size = [&](int m) { return static_cast<int>(ch.q[static_cast<std::size_t>(m)].size()); };
  // Per link m ≥ 1, over (x_{m−1}, x_m) = (i, j): the steps and the adjacent speed cost, so the
  // O(C³) loop only adds.
  std::vector<std::vector<Step>> steps(static_cast<std::size_t>(n));
  std::vector<std::vector<double>> step_cost(static_cast<std::size_t>(n));
  for (int m = 1; m < n; ++m) {
    auto& st = steps[static_cast<std::size_t>(m)];
    auto& sc = step_cost[static_cast<std::size_t>(m)];
    for (int i = 0; i < size(m - 1); ++i) {
      for (int j = 0; j < size(m); ++j) {
        st.push_back(MakeStep(ch, m - 1, i, m, j));
        sc.push_back(adjacent ? speed(m - 1, i, m, j) : 0.0);
      }
    }
  }
  // cost[i * K_m + j]: the best objective over links 0..m with x_{m−1} = i, x_m = j.
  std::vector<double> cost(static_cast<std::size_t>(size(0) * size(1)));
  for (int i = 0; i < size(0); ++i)
    for (int j = 0; j < size(1); ++j)
      cost[static_cast<std::size_t>(i * size(1) + j)] =
          ch.unary[0][i] + ch.unary[1][j] + step_cost[1][static_cast<std::size_t>(i * size(1) + j)];
  std::vector<std::vector<int>> back(static_cast<std::size_t>(n));
  std::vector<double> central;
  for (int m = 2; m < n; ++m) {
    const int kk = size(m - 2), ki = size(m - 1), kj = size(m);
    // The central-difference speed constraint couples x_{m−2} and x_m only.
    central.assign(static_cast<std::size_t>(kk * kj), 0.0);
    for (int k = 0; k < kk; ++k)
      for (int j = 0; j < kj; ++j)
        central[static_cast<std::size_t>(k * kj + j)] = speed(m - 2, k, m, j);
    const std::vector<Step>& prev_steps = steps[static_cast<std::size_t>(m - 1)];
    const std::vector<Step>& cur_steps = steps[static_cast<std::size_t>(m)];
    const std::vector<double>& cur_cost = step_cost[static_cast<std::size_t>(m)];
    std::vector<double> next(static_cast<std::size_t>(ki * kj), kInf);
    std::vector<int>& bp = back[static_cast<std::size_t>(m)];
    bp.assign(static_cast<std::size_t>(ki * kj), 0);
    for (int i = 0; i < ki; ++i) {
      for (int j = 0; j < kj; ++j) {
        const auto ij = static_cast<std::size_t>(i * kj + j);
        double best = kInf;
        int best_k = 0;
        for (int k = 0; k < kk; ++k) {
          const double prev = cost[static_cast<std::size_t>(k * ki + i)];
          if (prev == kInf) continue;
          const double c =
              prev +
              Smoothness(prev_steps[static_cast<std::size_t>(k * ki + i)], cur_steps[ij], t, p) +
              central[static_cast<std::size_t>(k * kj + j)];
          if (c < best) {
            best = c;
            best_k = k;
          }
        }
        next[ij] = best + ch.unary[m][j] + cur_cost[ij];
        bp[ij] = best_k;
      }
    }
    cost.swap(next);
  }
  const int kj = size(n - 1);
  const auto it = std::min_element(cost.begin(), cost.end());
  if (*it == kInf) return {};
  const int at = static_cast<int>(it - cost.begin());
  sel[static_cast<std::size_t>(n - 2)] = at / kj;
  sel[static_cast<std::size_t>(n - 1)] = at % kj;
  for (int m = n - 1; m >= 2; --m) {
    const int kjm = size(m);
    sel[static_cast<std::size_t>(m - 2)] =
        back[static_cast<std::size_t>(m)][static_cast<std::size_t>(
            sel[static_cast<std::size_t>(m - 1)] * kjm + sel[static_cast<std::size_t>(m)])];
  }
  return sel;
}

// A dense sample's place on the base path: interval s, fraction f in [0, 1].
struct DenseArc {
  int s = 0;
  float f = 0.0f;
  float arc_m = 0.0f;
};

std::vector<DenseArc> DenseArcs(std::span<const CameraBaseSample> path, float step_m) {
  std::vector<DenseArc> out;
  if (path.empty()) return out;
  const float step = std::max(step_m, 1e-3f);
  for (std::size_t s = 0; s + 1 < path.size(); ++s) {
    const float a = path[s].arc_length_m, h = path[s + 1].arc_length_m - a;
    const int pieces = h > 0.0f ? std::max(1, static_cast<int>(std::ceil(h / step - 1e-4f))) : 1;
    for (int k = 0; k < pieces; ++k) {
      const float f = static_cast<float>(k) / static_cast<float>(pieces);
      out.push_back({static_cast<int>(s), f, k == 0 ? a : a + h * f});
    }
  }
  const int last = static_cast<int>(path.size()) - 1;
  out.push_back({std::max(0, last - 1), path.size() > 1 ? 1.0f : 0.0f, path.back().arc_length_m});
  return out;
}

CameraBaseSample BaseAt(std::span<const CameraBaseSample> path, const DenseArc& d) {
  const CameraBaseSample& a = path[static_cast<std::size_t>(d.s)];
  if (path.size() < 2) return a;
  const CameraBaseSample& b = path[static_cast<std::size_t>(d.s) + 1];
  if (d.f <= 0.0f) return a;
  if (d.f >= 1.0f) return b;
  CameraBaseSample out;
  out.xy_m = a.xy_m + d.f * (b.xy_m - a.xy_m);
  out.heading_rad = WrapPiF(a.heading_rad + d.f * WrapPiF(b.heading_rad - a.heading_rad));
  out.arc_length_m = d.arc_m;
  return out;
}

float TimeOf(std::span<const CameraBaseSample> path, float arc_m, float base_speed_mps) {
  return (arc_m - path.front().arc_length_m) / std::max(base_speed_mps, 1e-6f);
}

}  // namespace

std::vector<double> CameraSampleTimes(std::span<const CameraBaseSample> path,
                                      float base_speed_mps) {
  std::vector<double> t;
  t.reserve(path.size());
  const double v = std::max(double{base_speed_mps}, 1e-6);
  for (const CameraBaseSample& b : path)
    t.push_back((double{b.arc_length_m} - double{path.front().arc_length_m}) / v);
  return t;
}

Eigen::Vector3f CameraPositionInWorkspace(const CameraBaseSample& base, float reach_m,
                                          float bearing_rad, float height_m, float floor_z_m) {
  const float a = base.heading_rad + bearing_rad;
  return {base.xy_m.x() + reach_m * std::cos(a), base.xy_m.y() + reach_m * std::sin(a),
          floor_z_m + height_m};
}

Eigen::Vector3f CameraOffsetInBase(const Eigen::Vector3f& camera_W, const CameraBaseSample& base,
                                   float floor_z_m) {
  const Eigen::Vector2f d = camera_W.head<2>() - base.xy_m;
  const float c = std::cos(base.heading_rad), s = std::sin(base.heading_rad);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y(), camera_W.z() - floor_z_m};
}

bool InCameraWorkspace(const Eigen::Vector3f& camera_W, const CameraBaseSample& base,
                       const CameraWorkspace& ws, float floor_z_m, float tol_m) {
  const float h = camera_W.z() - floor_z_m;
  if (h < ws.height_min_m - tol_m || h > ws.height_max_m + tol_m) return false;
  const Eigen::Vector2f d = camera_W.head<2>() - base.xy_m;
  const float r = d.norm();
  if (r < ws.reach_min_m - tol_m || r > ws.reach_max_m + tol_m) return false;
  if (r < 1e-6f) return true;  // only when reach_min is (about) 0: every bearing is the centre
  const float bearing = WrapPiF(std::atan2(d.y(), d.x()) - base.heading_rad);
  return std::abs(bearing) <= ws.bearing_half_angle_rad + tol_m;
}

Eigen::Vector3f ClampToCameraWorkspace(const Eigen::Vector3f& camera_W,
                                       const CameraBaseSample& base, const CameraWorkspace& ws,
                                       float floor_z_m) {
  if (InCameraWorkspace(camera_W, base, ws, floor_z_m, 0.0f)) return camera_W;
  const float h = std::clamp(camera_W.z() - floor_z_m, ws.height_min_m, ws.height_max_m);
  const Eigen::Vector2f d = camera_W.head<2>() - base.xy_m;
  const float r = std::clamp(d.norm(), ws.reach_min_m, ws.reach_max_m);
  const float bearing = d.squaredNorm() > 1e-12f
                            ? WrapPiF(std::atan2(d.y(), d.x()) - base.heading_rad)
                            : 0.0f;  // at the centre: push straight ahead
  const float b = std::clamp(bearing, -ws.bearing_half_angle_rad, ws.bearing_half_angle_rad);
  return CameraPositionInWorkspace(base, r, b, h, floor_z_m);
}

std::vector<std::vector<CameraCandidate>> SampleCameraCandidates(
    std::span<const CameraBaseSample> path, const CameraCandidateParams& params,
    const CameraFreeFn& free, const CameraScoreFn& score) {
  const CameraWorkspace& ws = params.workspace;
  const int wanted = std::max(0, params.candidates_per_sample);
  const int tries = std::max(wanted, params.max_tries);
  std::vector<std::vector<CameraCandidate>> out(path.size());
  for (std::size_t s = 0; s < path.size(); ++s) {
    const CameraBaseSample& base = path[s];
    std::vector<CameraCandidate>& cs = out[s];
    // Halton index from 1: point 1 is straight ahead at mid reach, a third of the way up.
    for (int i = 1; i <= tries && static_cast<int>(cs.size()) < wanted; ++i) {
      CameraCandidate c;
      c.bearing_rad =
          static_cast<float>(ws.bearing_half_angle_rad * (2.0 * RadicalInverse(i, 2) - 1.0));
      c.height_m = static_cast<float>(ws.height_min_m +
                                      (ws.height_max_m - ws.height_min_m) * RadicalInverse(i, 3));
      c.reach_m = static_cast<float>(ws.reach_min_m +
                                     (ws.reach_max_m - ws.reach_min_m) * RadicalInverse(i, 5));
      c.position_W =
          CameraPositionInWorkspace(base, c.reach_m, c.bearing_rad, c.height_m, params.floor_z_m);
      if (free && !free(c.position_W)) continue;
      CameraViewScore v;
      if (score) {
        v = score(c.position_W, base);
      } else {
        v.yaw_rad = base.heading_rad;
      }
      c.yaw_rad = WrapPiF(v.yaw_rad);
      c.pitch_rad = std::clamp(v.pitch_rad, -1.5707963f, 1.5707963f);
      c.gain = std::isfinite(v.gain) ? v.gain : 0.0f;
      cs.push_back(c);
    }
  }
  return out;
}

CameraSelection EvaluateCameraSelection(std::span<const double> times_s,
                                        const std::vector<std::vector<CameraCandidate>>& candidates,
                                        std::span<const int> selected,
                                        const CameraSelectionParams& params) {
  const Terms t = MakeTerms(times_s, candidates, params);
  const Chain ch = MakeChain(times_s, candidates, params, t);
  CameraSelection out;
  out.selected.assign(candidates.size(), -1);
  for (const auto& cs : candidates) out.samples_without_candidates += cs.empty() ? 1 : 0;
  const int n = static_cast<int>(ch.sample.size());
  std::vector<int> sel(static_cast<std::size_t>(n));
  for (int m = 0; m < n; ++m) {
    const int s = ch.sample[static_cast<std::size_t>(m)];
    const int x = s < static_cast<int>(selected.size()) ? selected[static_cast<std::size_t>(s)] : 0;
    sel[static_cast<std::size_t>(m)] =
        std::clamp(x, 0, static_cast<int>(ch.q[static_cast<std::size_t>(m)].size()) - 1);
    out.selected[static_cast<std::size_t>(s)] = sel[static_cast<std::size_t>(m)];
  }
  const SpeedCost speed{ch, t, params.violation_penalty};
  CameraSelectionEnergy& e = out.energy;
  auto x = [&](int m) { return sel[static_cast<std::size_t>(m)]; };
  for (int m = 0; m < n; ++m) {
    e.gain += ch.gain[static_cast<std::size_t>(m)][static_cast<std::size_t>(x(m))];
    e.lookat += ch.lookat[static_cast<std::size_t>(m)][static_cast<std::size_t>(x(m))];
    if (m >= 1 && params.limit_adjacent_steps)
      e.penalty += speed(m - 1, x(m - 1), m, x(m), &out.linear_violations, &out.angular_violations);
    if (m >= 2) {
      Smoothness(MakeStep(ch, m - 2, x(m - 2), m - 1, x(m - 1)),
                 MakeStep(ch, m - 1, x(m - 1), m, x(m)), t, params, &e.linear, &e.angular);
      e.penalty += speed(m - 2, x(m - 2), m, x(m), &out.linear_violations, &out.angular_violations);
    }
  }
  e.total = e.gain + e.linear + e.angular + e.lookat;
  out.feasible = out.linear_violations == 0 && out.angular_violations == 0;
  return out;
}

CameraSelection SelectCameraViews(std::span<const double> times_s,
                                  const std::vector<std::vector<CameraCandidate>>& candidates,
                                  const CameraSelectionParams& params) {
  const Terms t = MakeTerms(times_s, candidates, params);
  const Chain ch = MakeChain(times_s, candidates, params, t);
  std::vector<int> sel = SolveChain(ch, t, params, kInf);
  if (sel.empty() && !ch.sample.empty()) sel = SolveChain(ch, t, params, params.violation_penalty);
  std::vector<int> per_sample(candidates.size(), -1);
  for (std::size_t m = 0; m < sel.size(); ++m)
    per_sample[static_cast<std::size_t>(ch.sample[m])] = sel[m];
  return EvaluateCameraSelection(times_s, candidates, per_sample, params);
}

CameraTrajectory InterpolateCameraPath(std::span<const CameraBaseSample> path,
                                       std::span<const CameraCandidate* const> views,
                                       const CameraInterpolationParams& params) {
  CameraTrajectory out;
  if (path.empty()) return out;
  // Knots: the path samples with a view, keyed by base arc length.
  std::vector<float> u;
  std::vector<Eigen::Vector3f> q;
  std::vector<float> yaw, pitch;
  for (std::size_t s = 0; s < path.size() && s < views.size(); ++s) {
    if (views[s] == nullptr) continue;
    u.push_back(path[s].arc_length_m);
    q.push_back(views[s]->position_W);
    yaw.push_back(WrapPiF(views[s]->yaw_rad));
    pitch.push_back(views[s]->pitch_rad);
  }
  const int n = static_cast<int>(u.size());
  if (n == 0) return out;
  // Catmull-Rom tangents dq/du (non-uniform knots; one-sided at the ends). The paper's tangent,
  // the look-at vector × the y axis (X L294), leaves magnitude and sign open, so it is not used.
  std::vector<Eigen::Vector3f> tangent(static_cast<std::size_t>(n), Eigen::Vector3f::Zero());
  for (int m = 0; m < n; ++m) {
    const int a = std::max(0, m - 1), b = std::min(n - 1, m + 1);
    const float du = u[static_cast<std::size_t>(b)] - u[static_cast<std::size_t>(a)];
    if (b > a && du > 0.0f)
      tangent[static_cast<std::size_t>(m)] =
          (q[static_cast<std::size_t>(b)] - q[static_cast<std::size_t>(a)]) / du;
  }
  const CameraWorkspace& ws = params.workspace;
  const float v_max = std::max(0.0f, params.limits.linear_mps);
  const float a_max = std::max(0.0f, params.limits.angular_radps);
  int m = 0;  // knot interval [u_m, u_{m+1}] holding the current arc
  CameraPathSample prev;
  bool first = true;
  for (const DenseArc& d : DenseArcs(path, params.output_step_m)) {
    while (m + 1 < n - 1 && d.arc_m >= u[static_cast<std::size_t>(m) + 1]) ++m;
    CameraPathSample c;
    c.arc_length_m = d.arc_m;
    c.time_s = TimeOf(path, d.arc_m, params.base_speed_mps);
    // The spline, held constant before the first and after the last knot.
    const auto mi = static_cast<std::size_t>(m);
    if (n == 1 || d.arc_m <= u[0]) {
      c.position_W = q[0];
      c.yaw_rad = yaw[0];
      c.pitch_rad = pitch[0];
    } else if (d.arc_m >= u.back()) {
      c.position_W = q.back();
      c.yaw_rad = yaw.back();
      c.pitch_rad = pitch.back();
    } else {
      const float h = u[mi + 1] - u[mi];
      const float x = h > 0.0f ? std::clamp((d.arc_m - u[mi]) / h, 0.0f, 1.0f) : 0.0f;
      const float x2 = x * x, x3 = x2 * x;
      c.position_W = (2 * x3 - 3 * x2 + 1) * q[mi] + (x3 - 2 * x2 + x) * h * tangent[mi] +
                     (-2 * x3 + 3 * x2) * q[mi + 1] + (x3 - x2) * h * tangent[mi + 1];
      // Viewing angles: for a camera without roll the body angular velocity is yaw'·z + pitch'·e
      // with e the horizontal lateral axis ⟂ z, so |ω|² = yaw'² + pitch'²: the (yaw, pitch)
      // cylinder is flat and the minimal-rotation path between two adjacent views (the paper's
      // rotation-minimising frames with those views as boundary conditions) is the straight line
      // in (wrapped yaw, pitch) at constant rate. A full-rotation slerp would roll the camera.
      c.yaw_rad = WrapPiF(yaw[mi] + x * WrapPiF(yaw[mi + 1] - yaw[mi]));
      c.pitch_rad = pitch[mi] + x * (pitch[mi + 1] - pitch[mi]);
    }
    const CameraBaseSample base = BaseAt(path, d);
    c.base = base;
    bool moved = false;
    auto into_workspace = [&](const Eigen::Vector3f& p) {
      const Eigen::Vector3f r = ClampToCameraWorkspace(p, base, ws, params.floor_z_m);
      if ((r - p).norm() > kClampTolM) moved = true;
      return r;
    };
    c.position_W = into_workspace(c.position_W);
    if (!first) {
      const float dt = std::max(c.time_s - prev.time_s, 0.0f);
      const float step_max = v_max * dt;
      const Eigen::Vector3f step = c.position_W - prev.position_W;
      const float len = step.norm();
      if (len > step_max * (1.0f + 1e-6f) + 1e-7f) {
        c.position_W = prev.position_W + step * (step_max / len);
        ++out.linear_speed_clamps;
        c.position_W = into_workspace(c.position_W);  // Ψ wins over the speed limit
      }
      if ((c.position_W - prev.position_W).norm() > step_max * (1.0f + kSpeedSlack) + kClampTolM)
        ++out.speed_violations;
      const float turn_max = a_max * dt;
      const float dy = WrapPiF(c.yaw_rad - prev.yaw_rad), dp = c.pitch_rad - prev.pitch_rad;
      const float turn = std::sqrt(dy * dy + dp * dp);
      if (turn > turn_max * (1.0f + 1e-6f) + 1e-7f) {
        const float k = turn_max / turn;
        c.yaw_rad = WrapPiF(prev.yaw_rad + k * dy);
        c.pitch_rad = prev.pitch_rad + k * dp;
        ++out.angular_speed_clamps;
      }
    }
    if (moved) ++out.workspace_clamps;
    out.samples.push_back(c);
    prev = c;
    first = false;
  }
  return out;
}

std::vector<CameraLookAtTarget> FindLookAtTargets(std::span<const Eigen::Vector2f> line,
                                                  float touch_m, float step_m, float height_m,
                                                  const NearestUnknownFn& nearest_unknown) {
  std::vector<CameraLookAtTarget> out;
  if (line.empty() || !nearest_unknown) return out;
  const float step = std::max(step_m, 1e-3f);
  auto visit = [&](const Eigen::Vector2f& p, float arc) {
    const std::optional<Eigen::Vector2f> u = nearest_unknown(p, touch_m);
    if (!u || !u->allFinite()) return;
    const Eigen::Vector3f point(u->x(), u->y(), height_m);
    if (!out.empty() && out.back().point_W == point) return;
    out.push_back({point, arc});
  };
  visit(line[0], 0.0f);
  float arc = 0.0f;
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Eigen::Vector2f a = line[i - 1], b = line[i];
    const float len = (b - a).norm();
    const int pieces = std::max(1, static_cast<int>(std::ceil(len / step - 1e-4f)));
    for (int k = 1; k <= pieces; ++k) {
      const float f = static_cast<float>(k) / static_cast<float>(pieces);
      visit(a + f * (b - a), arc + f * len);
    }
    arc += len;
  }
  return out;
}

std::vector<int> AssignLookAtTargets(std::span<const CameraBaseSample> path,
                                     std::span<const CameraLookAtTarget> targets, float range_m) {
  std::vector<int> out(path.size(), -1);
  constexpr float kArcTolM = 1e-4f;
  for (std::size_t s = 0; s < path.size(); ++s) {
    for (std::size_t k = 0; k < targets.size(); ++k) {
      if (targets[k].arc_length_m < path[s].arc_length_m - kArcTolM) continue;
      if ((targets[k].point_W.head<2>() - path[s].xy_m).norm() < range_m) {
        out[s] = static_cast<int>(k);
        break;
      }
    }
  }
  return out;
}

float LookAtScore(const Eigen::Vector3f& camera_W, float yaw_rad, const Eigen::Vector3f& target_W,
                  float half_fov_rad) {
  const Eigen::Vector2f d = target_W.head<2>() - camera_W.head<2>();
  if (d.squaredNorm() < 1e-12f) return 1.0f;
  const float bearing = std::atan2(d.y(), d.x());
  return std::abs(WrapPiF(bearing - yaw_rad)) <= half_fov_rad ? 1.0f : 0.0f;
}

void AddLookAtViews(std::span<const CameraBaseSample> path, const CameraLookAt& lookat,
                    std::span<const int> target_of_sample,
                    std::vector<std::vector<CameraCandidate>>* candidates) {
  const std::size_t n = std::min({path.size(), target_of_sample.size(), candidates->size()});
  for (std::size_t s = 0; s < n; ++s) {
    const int k = target_of_sample[s];
    std::vector<CameraCandidate>& cs = (*candidates)[s];
    if (k < 0 || k >= static_cast<int>(lookat.targets.size()) || cs.empty()) continue;
    const Eigen::Vector3f& target = lookat.targets[static_cast<std::size_t>(k)].point_W;
    std::size_t nearest = 0;
    for (std::size_t i = 0; i < cs.size(); ++i) {
      cs[i].lookat =
          LookAtScore(cs[i].position_W, cs[i].yaw_rad, target, lookat.params.half_fov_rad);
      if ((cs[i].position_W - target).head<2>().norm() <
          (cs[nearest].position_W - target).head<2>().norm())
        nearest = i;
    }
    CameraCandidate v = cs[nearest];
    const Eigen::Vector2f d = target.head<2>() - v.position_W.head<2>();
    v.yaw_rad = d.squaredNorm() > 1e-12f ? std::atan2(d.y(), d.x()) : path[s].heading_rad;
    v.pitch_rad = 0.0f;
    const float g = lookat.gain ? lookat.gain(v.position_W, v.yaw_rad, v.pitch_rad, path[s]) : 0.0f;
    v.gain = std::isfinite(g) ? g : 0.0f;
    v.lookat = 1.0f;
    v.lookat_view = true;
    cs.push_back(v);
  }
}

namespace {

// The trajectory's pose at time t (linear between its samples, yaw the short way; held outside).
struct PoseAt {
  Eigen::Vector3f q;
  float yaw, pitch;
};
PoseAt TrajectoryAt(const std::vector<CameraPathSample>& tr, float t) {
  if (t <= tr.front().time_s)
    return {tr.front().position_W, tr.front().yaw_rad, tr.front().pitch_rad};
  for (std::size_t i = 1; i < tr.size(); ++i) {
    if (t > tr[i].time_s) continue;
    const float span = tr[i].time_s - tr[i - 1].time_s;
    const float a = span > 0.0f ? (t - tr[i - 1].time_s) / span : 1.0f;
    return {tr[i - 1].position_W + a * (tr[i].position_W - tr[i - 1].position_W),
            WrapPiF(tr[i - 1].yaw_rad + a * WrapPiF(tr[i].yaw_rad - tr[i - 1].yaw_rad)),
            tr[i - 1].pitch_rad + a * (tr[i].pitch_rad - tr[i - 1].pitch_rad)};
  }
  return {tr.back().position_W, tr.back().yaw_rad, tr.back().pitch_rad};
}

float TurnBetween(float yaw_a, float pitch_a, float yaw_b, float pitch_b) {
  return std::hypot(WrapPiF(yaw_b - yaw_a), pitch_b - pitch_a);
}

}  // namespace

CameraConnection ConnectCameraTrajectory(const CameraPose& from, const CameraConnectParams& p,
                                         CameraTrajectory* trajectory) {
  CameraConnection out;
  std::vector<CameraPathSample>& tr = trajectory->samples;
  if (tr.empty() || !std::isfinite(from.yaw_rad) || !std::isfinite(from.pitch_rad)) return out;
  const bool has_q = from.position_W.allFinite();
  const float t0 = tr.front().time_s;
  const float hold = std::max(0.0f, p.hold_s);
  const float v_max = std::max(1e-6f, p.limits.linear_mps);
  const float a_max = std::max(1e-6f, p.limits.angular_radps);
  // The difference to fade out: from the pose to the trajectory where the hold ends.
  const PoseAt join = TrajectoryAt(tr, t0 + hold);
  const float d_yaw = WrapPiF(from.yaw_rad - join.yaw);
  const float d_pitch = from.pitch_rad - join.pitch;
  const Eigen::Vector3f d_q =
      has_q ? Eigen::Vector3f(from.position_W - join.q) : Eigen::Vector3f::Zero();
  out.jump_rad =
      TurnBetween(from.yaw_rad, from.pitch_rad, tr.front().yaw_rad, tr.front().pitch_rad);
  out.jump_m = has_q ? (from.position_W - tr.front().position_W).norm() : 0.0f;
  constexpr float kSameRad = 1e-4f, kSameM = 1e-4f;
  // The smoothstep's steepest slope is 1.5 / blend.
  const float share = std::clamp(p.rate_share, 1e-3f, 1.0f);
  const float blend = std::max({p.min_s, 1.5f * std::hypot(d_yaw, d_pitch) / (share * a_max),
                                1.5f * d_q.norm() / (share * v_max)});
  out.duration_s = hold + blend;
  const float end_t = t0 + out.duration_s;
  // The speeds before: the trajectory as given, its first step taking the jump.
  auto step_speeds = [&](const std::vector<CameraPathSample>& samples, float* radps, float* mps,
                         bool from_pose) {
    *radps = *mps = 0.0f;
    for (std::size_t k = 1; k < samples.size() && samples[k - 1].time_s < end_t; ++k) {
      const float dt = std::max(samples[k].time_s - samples[k - 1].time_s, 1e-6f);
      const bool first = k == 1 && from_pose;
      const float yaw_a = first ? from.yaw_rad : samples[k - 1].yaw_rad;
      const float pitch_a = first ? from.pitch_rad : samples[k - 1].pitch_rad;
      *radps = std::max(*radps,
                        TurnBetween(yaw_a, pitch_a, samples[k].yaw_rad, samples[k].pitch_rad) / dt);
      if (has_q) {
        const Eigen::Vector3f qa = first ? from.position_W : samples[k - 1].position_W;
        *mps = std::max(*mps, (samples[k].position_W - qa).norm() / dt);
      }
    }
  };
  step_speeds(tr, &out.max_radps_before, &out.max_mps_before, true);
  if (std::hypot(d_yaw, d_pitch) <= kSameRad && d_q.norm() <= kSameM && out.jump_rad <= kSameRad &&
      out.jump_m <= kSameM) {
    out.max_radps_after = out.max_radps_before;
    out.max_mps_after = out.max_mps_before;
    return out;
  }
  out.connected = true;
  CameraPathSample prev;
  for (std::size_t k = 0; k < tr.size(); ++k) {
    CameraPathSample& c = tr[k];
    const float tau = c.time_s - t0 - hold;
    if (tau <= 0.0f) {
      c.yaw_rad = from.yaw_rad;
      c.pitch_rad = from.pitch_rad;
      if (has_q) c.position_W = from.position_W;
    } else if (tau < blend) {
      const float x = tau / blend;
      const float keep = 1.0f - x * x * (3.0f - 2.0f * x);
      c.yaw_rad = WrapPiF(c.yaw_rad + keep * d_yaw);
      c.pitch_rad += keep * d_pitch;
      if (has_q) c.position_W += keep * d_q;
    }
    if (has_q) {
      const Eigen::Vector3f r =
          ClampToCameraWorkspace(c.position_W, c.base, p.workspace, p.floor_z_m);
      if ((r - c.position_W).norm() > kClampTolM) ++out.workspace_clamps;
      c.position_W = r;
    }
    if (k > 0) {
      // The forward pass: a step over a limit is shortened; the samples after catch up.
      const float dt = std::max(c.time_s - prev.time_s, 0.0f);
      if (has_q) {
        const float step_max = v_max * dt;
        const Eigen::Vector3f step = c.position_W - prev.position_W;
        const float len = step.norm();
        if (len > step_max * (1.0f + 1e-6f) + 1e-7f) {
          c.position_W = ClampToCameraWorkspace(prev.position_W + step * (step_max / len), c.base,
                                                p.workspace, p.floor_z_m);
          ++out.speed_clamps;
        }
      }
      const float turn_max = a_max * dt;
      const float dy = WrapPiF(c.yaw_rad - prev.yaw_rad), dp = c.pitch_rad - prev.pitch_rad;
      const float turn = std::hypot(dy, dp);
      if (turn > turn_max * (1.0f + 1e-6f) + 1e-7f) {
        const float f = turn_max / turn;
        c.yaw_rad = WrapPiF(prev.yaw_rad + f * dy);
        c.pitch_rad = prev.pitch_rad + f * dp;
        ++out.speed_clamps;
      }
    }
    prev = c;
  }
  step_speeds(tr, &out.max_radps_after, &out.max_mps_after, true);
  return out;
}

CameraPathResult PlanCameraPath(std::span<const CameraBaseSample> path,
                                const CameraPathParams& params, const CameraFreeFn& free,
                                const CameraScoreFn& score) {
  return PlanCameraPath(path, params, free, score, CameraLookAt{});
}

CameraPathResult PlanCameraPath(std::span<const CameraBaseSample> path,
                                const CameraPathParams& params, const CameraFreeFn& free,
                                const CameraScoreFn& score, const CameraLookAt& lookat) {
  CameraPathResult out;
  out.lookat_target.assign(path.size(), -1);
  out.mode = params.mode;
  const CameraWorkspace& ws = params.candidates.workspace;
  const float floor_z = params.candidates.floor_z_m;
  const std::vector<double> times = CameraSampleTimes(path, params.selection.base_speed_mps);
  if (params.mode == CameraMode::kFixed) {
    // A rigid mount: one pose per sample, the dense path follows the base exactly (no clamps; the
    // speed limits are only checked, the base's motion sets them).
    for (const CameraBaseSample& b : path) {
      CameraCandidate c;
      c.reach_m = params.fixed_forward_m;
      c.height_m = params.fixed_height_m;
      c.position_W = CameraPositionInWorkspace(b, c.reach_m, 0.0f, c.height_m, floor_z);
      c.yaw_rad = WrapPiF(b.heading_rad);
      c.pitch_rad = params.fixed_pitch_rad;
      out.candidates.push_back({c});
    }
    const std::vector<int> zeros(path.size(), 0);
    out.selection = EvaluateCameraSelection(times, out.candidates, zeros, params.selection);
    if (path.empty()) return out;
    const float v_max = params.selection.limits.linear_mps;
    const float a_max = params.selection.limits.angular_radps;
    for (const DenseArc& d : DenseArcs(path, params.output_step_m)) {
      const CameraBaseSample b = BaseAt(path, d);
      CameraPathSample c;
      c.base = b;
      c.arc_length_m = d.arc_m;
      c.time_s = TimeOf(path, d.arc_m, params.selection.base_speed_mps);
      c.position_W = CameraPositionInWorkspace(b, params.fixed_forward_m, 0.0f,
                                               params.fixed_height_m, floor_z);
      c.yaw_rad = WrapPiF(b.heading_rad);
      c.pitch_rad = params.fixed_pitch_rad;
      if (!out.trajectory.samples.empty()) {
        const CameraPathSample& p = out.trajectory.samples.back();
        const float dt = c.time_s - p.time_s;
        const bool fast =
            (c.position_W - p.position_W).norm() > v_max * dt * (1.0f + kSpeedSlack) + kClampTolM ||
            std::abs(WrapPiF(c.yaw_rad - p.yaw_rad)) >
                a_max * dt * (1.0f + kSpeedSlack) + kClampTolM;
        out.trajectory.speed_violations += fast ? 1 : 0;
      }
      out.trajectory.samples.push_back(c);
    }
    return out;
  }
  CameraSelectionParams sp = params.selection;
  if (params.mode == CameraMode::kNoLinear) sp.weight_linear = 0.0;
  if (params.mode == CameraMode::kNoAngular) sp.weight_angular = 0.0;
  out.candidates = SampleCameraCandidates(path, params.candidates, free, score);
  std::vector<std::vector<CameraCandidate>> plain;  // without X12, for lookat_changed
  if (!lookat.targets.empty()) {
    out.lookat_target = AssignLookAtTargets(path, lookat.targets, lookat.params.range_m);
    if (std::any_of(out.lookat_target.begin(), out.lookat_target.end(),
                    [](int k) { return k >= 0; })) {
      plain = out.candidates;
      AddLookAtViews(path, lookat, out.lookat_target, &out.candidates);
    }
  }
  if (params.start_from_camera) {
    const auto pin = [&](std::vector<std::vector<CameraCandidate>>* cands) {
      if (cands->empty() || (*cands)[0].empty()) return;
      CameraCandidate c = (*cands)[0][0];
      if (params.start_position_W.allFinite()) c.position_W = params.start_position_W;
      c.yaw_rad = WrapPiF(params.start_yaw_rad);
      c.pitch_rad = params.start_pitch_rad;
      c.gain = 0.0f;
      const int k = out.lookat_target.empty() ? -1 : out.lookat_target[0];
      c.lookat = k >= 0 && !plain.empty()
                     ? LookAtScore(c.position_W, c.yaw_rad,
                                   lookat.targets[static_cast<std::size_t>(k)].point_W,
                                   lookat.params.half_fov_rad)
                     : 0.0f;
      c.lookat_view = false;
      (*cands)[0] = {c};
    };
    pin(&out.candidates);
    if (!plain.empty()) pin(&plain);
  }
  out.selection = SelectCameraViews(times, out.candidates, sp);
  if (!plain.empty()) {
    const CameraSelection without = SelectCameraViews(times, plain, sp);
    for (std::size_t s = 0; s < path.size(); ++s) {
      const int x = out.selection.selected[s];
      if (out.lookat_target[s] < 0 || x < 0) continue;
      ++out.lookat_samples;
      const CameraCandidate& c = out.candidates[s][static_cast<std::size_t>(x)];
      out.lookat_seen += c.lookat > 0.0f ? 1 : 0;
      out.lookat_changed += c.lookat_view || x != without.selected[s] ? 1 : 0;
    }
  }
  std::vector<const CameraCandidate*> views(path.size(), nullptr);
  for (std::size_t s = 0; s < path.size(); ++s) {
    const int x = out.selection.selected[s];
    if (x >= 0) views[s] = &out.candidates[s][static_cast<std::size_t>(x)];
  }
  CameraInterpolationParams ip;
  ip.workspace = ws;
  ip.limits = sp.limits;
  ip.floor_z_m = floor_z;
  ip.base_speed_mps = sp.base_speed_mps;
  ip.output_step_m = params.output_step_m;
  out.trajectory = InterpolateCameraPath(path, views, ip);
  return out;
}

}  // namespace voxplan::tensorfield
