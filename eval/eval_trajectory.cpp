#include "eval/eval_trajectory.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <sstream>

#include "io/file_util.h"

namespace voxplan {

namespace {

std::string Describe(const TumTrajectory& t, const char* fallback) {
  return t.source.empty() ? std::string(fallback) : t.source;
}

std::string Seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", t);
  return text;
}

struct Stats {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
};

Stats Summarize(std::vector<double> values) {
  Stats s;
  if (values.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
    s.max = std::max(s.max, v);
  }
  const double n = double(values.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  std::sort(values.begin(), values.end());
  const size_t mid = values.size() / 2;
  s.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

// (estimate index, reference index) pairs in estimate time order.
std::vector<std::pair<size_t, size_t>> Associate(const std::vector<double>& estimate_s,
                                                 const std::vector<double>& reference_s,
                                                 double max_dt_s) {
  std::vector<size_t> ref_order(reference_s.size());
  std::iota(ref_order.begin(), ref_order.end(), size_t{0});
  std::stable_sort(ref_order.begin(), ref_order.end(),
                   [&](size_t a, size_t b) { return reference_s[a] < reference_s[b]; });
  struct Candidate {
    double dt;
    size_t est, ref;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < estimate_s.size(); ++i) {
    const double t = estimate_s[i];
    const auto it =
        std::lower_bound(ref_order.begin(), ref_order.end(), t,
                         [&](size_t j, double value) { return reference_s[j] < value; });
    const size_t k = size_t(it - ref_order.begin());
    for (size_t c : {k, k - 1}) {  // k - 1 wraps to a huge value when k == 0
      if (c >= ref_order.size()) continue;
      const double dt = std::abs(reference_s[ref_order[c]] - t);
      // A hair of slack so timestamps written with 6 decimals meet a max_dt_s they equal.
      if (dt <= max_dt_s + 1e-9) candidates.push_back({dt, i, ref_order[c]});
    }
  }
  // Closest pairs first, each pose used once (as TUM's associate.py).
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.dt < b.dt; });
  std::vector<bool> est_used(estimate_s.size()), ref_used(reference_s.size());
  std::vector<std::pair<size_t, size_t>> pairs;
  for (const Candidate& c : candidates) {
    if (est_used[c.est] || ref_used[c.ref]) continue;
    est_used[c.est] = ref_used[c.ref] = true;
    pairs.emplace_back(c.est, c.ref);
  }
  std::sort(pairs.begin(), pairs.end(), [&](const auto& a, const auto& b) {
    return estimate_s[a.first] != estimate_s[b.first] ? estimate_s[a.first] < estimate_s[b.first]
                                                      : a.first < b.first;
  });
  return pairs;
}

}  // namespace

Result<TrajectoryEvalResult> EvaluateTrajectory(const TumTrajectory& estimate,
                                                const TumTrajectory& reference,
                                                const TrajectoryEvalParams& params) {
  const std::string est_name = Describe(estimate, "the estimate");
  const std::string ref_name = Describe(reference, "the reference");
  if (estimate.timestamps_s.size() != estimate.T_W_C.size() ||
      reference.timestamps_s.size() != reference.T_W_C.size()) {
    return InvalidArgument("trajectory with different numbers of timestamps and poses");
  }
  if (estimate.T_W_C.empty() || reference.T_W_C.empty()) {
    return InvalidArgument("empty trajectory: " + (estimate.T_W_C.empty() ? est_name : ref_name));
  }
  if (!(params.max_dt_s >= 0.0)) return InvalidArgument("max_dt_s must be zero or more");

  const auto pairs = Associate(estimate.timestamps_s, reference.timestamps_s, params.max_dt_s);
  if (pairs.empty()) {
    auto span = [](const std::vector<double>& t) {
      const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
      return Seconds(*lo) + " .. " + Seconds(*hi) + " s";
    };
    return InvalidArgument("no overlapping timestamps between estimate " + est_name + " (" +
                           span(estimate.timestamps_s) + ") and reference " + ref_name + " (" +
                           span(reference.timestamps_s) + ") within " +
                           std::to_string(params.max_dt_s) + " s");
  }
  if (pairs.size() < 3) {
    return InvalidArgument("only " + std::to_string(pairs.size()) + " timestamps of estimate " +
                           est_name + " match reference " + ref_name +
                           "; alignment needs at least 3");
  }

  TrajectoryEvalResult r;
  r.pairs = pairs.size();
  Eigen::Matrix3Xd p_est(3, pairs.size()), p_ref(3, pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    p_est.col(Eigen::Index(k)) = estimate.T_W_C[pairs[k].first].translation();
    p_ref.col(Eigen::Index(k)) = reference.T_W_C[pairs[k].second].translation();
  }
  const Eigen::Matrix4d T = Eigen::umeyama(p_est, p_ref, /*with_scaling=*/false);
  if (!T.allFinite()) return InvalidArgument("trajectory alignment failed (degenerate positions)");
  r.T_ref_est.matrix() = T;

  r.ate_errors_m.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    const Eigen::Vector3d aligned = r.T_ref_est * Eigen::Vector3d(p_est.col(Eigen::Index(k)));
    r.ate_errors_m[k] = (aligned - p_ref.col(Eigen::Index(k))).norm();
  }
  const Stats ate = Summarize(r.ate_errors_m);
  r.ate_rmse_m = ate.rmse;
  r.ate_mean_m = ate.mean;
  r.ate_median_m = ate.median;
  r.ate_max_m = ate.max;

  // Relative motions are unchanged by the global alignment, so RPE uses the raw poses.
  std::vector<double> rpe_trans_m, rpe_rot_deg;
  for (size_t k = 0; k + 1 < pairs.size(); ++k) {
    const Pose3d est_delta =
        estimate.T_W_C[pairs[k].first].inverse() * estimate.T_W_C[pairs[k + 1].first];
    const Pose3d ref_delta =
        reference.T_W_C[pairs[k].second].inverse() * reference.T_W_C[pairs[k + 1].second];
    const Pose3d error = ref_delta.inverse() * est_delta;
    rpe_trans_m.push_back(error.translation().norm());
    const Eigen::AngleAxisd angle_axis(Eigen::Quaterniond(error.linear()).normalized());
    rpe_rot_deg.push_back(angle_axis.angle() * 180.0 / std::numbers::pi);
  }
  r.rpe_pairs = rpe_trans_m.size();
  const Stats trans = Summarize(rpe_trans_m), rot = Summarize(rpe_rot_deg);
  r.rpe_trans_rmse_m = trans.rmse;
  r.rpe_trans_mean_m = trans.mean;
  r.rpe_rot_rmse_deg = rot.rmse;
  r.rpe_rot_mean_deg = rot.mean;
  return r;
}

}  // namespace voxplan
