#include "sim/eval_trajectory.h"

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

// Whitespace-separated tokens of one line, a `#` and what follows dropped.
std::vector<std::string_view> Tokens(std::string_view line) {
  if (const size_t hash = line.find('#'); hash != std::string_view::npos)
    line = line.substr(0, hash);
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

bool ParseDouble(std::string_view token, double* value) {
  // from_chars takes no leading '+'; accept it as strtod would.
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && end == token.data() + token.size() && std::isfinite(*value);
}

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

Result<TumTrajectory> ReadTumTrajectory(const std::string& path) {
  Result<std::string> text = ReadFileToString(path);
  if (!text.ok()) return text.status();
  TumTrajectory trajectory;
  trajectory.source = path;
  std::istringstream lines(*text);
  std::string line;
  for (int line_number = 1; std::getline(lines, line); ++line_number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string_view> tokens = Tokens(line);
    if (tokens.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (tokens.size() != 8) {
      return CorruptData(where + "expected 8 numbers 't tx ty tz qx qy qz qw', got " +
                         std::to_string(tokens.size()) + " fields");
    }
    double v[8];
    for (int i = 0; i < 8; ++i) {
      if (!ParseDouble(tokens[size_t(i)], &v[i])) {
        return CorruptData(where + "not a finite number: '" + std::string(tokens[size_t(i)]) + "'");
      }
    }
    Result<Pose3d> pose =
        PoseFromTranslationQuaternion(Eigen::Vector3d(v[1], v[2], v[3]), v[4], v[5], v[6], v[7]);
    if (!pose.ok()) return CorruptData(where + pose.status().message());
    trajectory.timestamps_s.push_back(v[0]);
    trajectory.T_W_C.push_back(*pose);
  }
  if (trajectory.T_W_C.empty()) return CorruptData(path + ": no poses in the trajectory file");
  return trajectory;
}

Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3d>& T_W_C) {
  if (timestamps_s.size() != T_W_C.size()) {
    return InvalidArgument(path + ": " + std::to_string(timestamps_s.size()) + " timestamps but " +
                           std::to_string(T_W_C.size()) + " poses");
  }
  std::string text = "# timestamp tx ty tz qx qy qz qw (T_W_C, camera-to-world)\n";
  char line[256];
  for (size_t i = 0; i < T_W_C.size(); ++i) {
    Eigen::Quaterniond q(T_W_C[i].linear());
    q.normalize();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // one of the two equal quaternions, stably
    const Eigen::Vector3d& t = T_W_C[i].translation();
    std::snprintf(line, sizeof(line), "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", timestamps_s[i],
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    text += line;
  }
  return WriteAtomically(
      path, [&](const std::string& tmp_path) { return WriteStringToFile(tmp_path, text); });
}

Status WriteTumTrajectory(const std::string& path, const std::vector<double>& timestamps_s,
                          const std::vector<Pose3f>& T_W_C) {
  std::vector<Pose3d> poses;
  poses.reserve(T_W_C.size());
  for (const Pose3f& T : T_W_C) poses.push_back(T.cast<double>());
  return WriteTumTrajectory(path, timestamps_s, poses);
}

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
