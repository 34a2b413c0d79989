#include "plugins/omt/algorithms/smoothing.h"

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::omt {
namespace {

using Field = ceres::BiCubicInterpolator<ceres::Grid2D<double, 1>>;

// η at a world point through the bicubic interpolator (grid coordinates: row = y, col = x,
// sample (r, c) at the centre of cell (c, r)).
template <typename T>
T Eta(const Field& field, const RasterGeometry& g, const T& x, const T& y) {
  const T col = (x - g.origin_m.x()) / g.resolution_m - 0.5;
  const T row = (y - g.origin_m.y()) / g.resolution_m - 0.5;
  T eta;
  field.Evaluate(row, col, &eta);
  return eta;
}

struct SegmentTerm {
  SegmentTerm(const Field* eta_field, const RasterGeometry* geometry, double eta_floor,
              double eta_cap)
      : field(eta_field), g(geometry), floor(eta_floor), cap(eta_cap) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    const T ea = std::clamp(Eta(*field, *g, a[0], a[1]), T(floor), T(cap));
    const T eb = std::clamp(Eta(*field, *g, b[0], b[1]), T(floor), T(cap));
    const T w = ceres::sqrt(T(2.0) / (ea + eb));
    residual[0] = w * (a[0] - b[0]);
    residual[1] = w * (a[1] - b[1]);
    return true;
  }
  const Field* field;
  const RasterGeometry* g;
  double floor;
  double cap;
};

struct AnchorTerm {
  AnchorTerm(Eigen::Vector2d anchor, double sqrt_lambda) : p0(std::move(anchor)), s(sqrt_lambda) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    residual[0] = T(s) * (p[0] - T(p0.x()));
    residual[1] = T(s) * (p[1] - T(p0.y()));
    return true;
  }
  Eigen::Vector2d p0;
  double s;
};

struct ClearanceTerm {
  ClearanceTerm(const Field* clearance, const RasterGeometry* geometry, double min_clearance,
                double term_weight)
      : field(clearance), g(geometry), min_c(min_clearance), weight(term_weight) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    const T eta = Eta(*field, *g, p[0], p[1]);
    residual[0] = eta < T(min_c) ? T(weight) * (T(min_c) - eta) : T(0.0);
    return true;
  }
  const Field* field;
  const RasterGeometry* g;
  double min_c;
  double weight;
};

bool PathClear(const ClearanceRaster& clearance, const std::vector<PathPoint>& pts,
               double min_clearance) {
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!SegmentClear(clearance, pts[i - 1].p_m, pts[i].p_m, min_clearance)) return false;
  return true;
}

}  // namespace

double PolylineLength(const std::vector<PathPoint>& points) {
  double len = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) len += (points[i].p_m - points[i - 1].p_m).norm();
  return len;
}

std::vector<PathPoint> SamplePolyline(const std::vector<Eigen::Vector2d>& polyline,
                                      const std::vector<std::pair<int, int>>& task_vertices,
                                      double spacing_m) {
  std::vector<PathPoint> out;
  if (polyline.empty()) return out;
  std::vector<int> task_of(polyline.size(), -1);
  for (const auto& [v, id] : task_vertices)
    if (v >= 0 && v < static_cast<int>(polyline.size())) task_of[static_cast<std::size_t>(v)] = id;
  // Pieces between consecutive kept vertices (start, tasks, end) are resampled uniformly.
  std::vector<int> keep{0};
  for (int v = 1; v + 1 < static_cast<int>(polyline.size()); ++v)
    if (task_of[static_cast<std::size_t>(v)] >= 0) keep.push_back(v);
  if (polyline.size() > 1) keep.push_back(static_cast<int>(polyline.size()) - 1);
  out.push_back({polyline[0], task_of[0]});
  for (std::size_t k = 1; k < keep.size(); ++k) {
    const int a = keep[k - 1];
    const int b = keep[k];
    std::vector<double> s{0.0};
    for (int v = a + 1; v <= b; ++v) s.push_back(s.back() + (polyline[v] - polyline[v - 1]).norm());
    const double len = s.back();
    const int n = std::max(1, static_cast<int>(std::lround(len / spacing_m)));
    int seg = 0;
    for (int i = 1; i < n; ++i) {
      const double target = len * i / n;
      while (seg + 1 < static_cast<int>(s.size()) - 1 && s[seg + 1] < target) ++seg;
      const double ds = s[seg + 1] - s[seg];
      const double f = ds > 0.0 ? (target - s[seg]) / ds : 0.0;
      out.push_back({polyline[a + seg] + f * (polyline[a + seg + 1] - polyline[a + seg]), -1});
    }
    if (len > 0.0 || k + 1 == keep.size() || task_of[static_cast<std::size_t>(b)] >= 0)
      out.push_back({polyline[b], task_of[static_cast<std::size_t>(b)]});
  }
  return out;
}

double Eq5Energy(const ClearanceRaster& clearance, const std::vector<PathPoint>& points,
                 const std::vector<PathPoint>& original, const SmoothingParams& params) {
  assert(params.eta_floor_m <= params.eta_cap_m);
  double e = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double ea = std::clamp(ClearanceBilinear(clearance, points[i - 1].p_m),
                                 params.eta_floor_m, params.eta_cap_m);
    const double eb = std::clamp(ClearanceBilinear(clearance, points[i].p_m), params.eta_floor_m,
                                 params.eta_cap_m);
    e += 2.0 / (ea + eb) * (points[i].p_m - points[i - 1].p_m).squaredNorm();
  }
  for (std::size_t i = 0; i < points.size() && i < original.size(); ++i)
    if (points[i].task >= 0) e += params.lambda * (points[i].p_m - original[i].p_m).squaredNorm();
  return e;
}

Status SmoothPath(const ClearanceRaster& clearance, const SmoothingParams& params,
                  std::vector<PathPoint>* points) {
  assert(params.eta_floor_m <= params.eta_cap_m);
  if (points->size() < 3) return Status::Ok();
  const RasterGeometry& g = clearance.geometry;
  if (g.NumCells() == 0) return Status::Error(Status::Code::kInvalidInput, "empty clearance");
  std::vector<double> eta(clearance.clearance_m.begin(), clearance.clearance_m.end());
  ceres::Grid2D<double, 1> grid(eta.data(), 0, g.height, 0, g.width);
  const Field field(grid);
  const std::vector<PathPoint> original = *points;
  std::vector<Eigen::Vector2d> x(points->size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = (*points)[i].p_m;

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (std::size_t i = 1; i < x.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SegmentTerm, 2, 2, 2>(
                                 new SegmentTerm(&field, &g, params.eta_floor_m, params.eta_cap_m)),
                             nullptr, x[i - 1].data(), x[i].data());
  }
  const double sqrt_lambda = std::sqrt(params.lambda);
  for (std::size_t i = 0; i < x.size(); ++i) {
    if ((*points)[i].task >= 0) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<AnchorTerm, 2, 2>(new AnchorTerm(x[i], sqrt_lambda)),
          nullptr, x[i].data());
    }
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ClearanceTerm, 1, 2>(new ClearanceTerm(
                                 &field, &g, params.min_clearance_m, params.clearance_weight)),
                             nullptr, x[i].data());
  }
  problem.SetParameterBlockConstant(x[0].data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = params.max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE) {
    return Status::Error(Status::Code::kSolverFailed, summary.message);
  }
  // Step back towards the (clear) input until every segment keeps the clearance.
  std::vector<PathPoint> trial = original;
  for (double t = 1.0; t > 1.0 / 64.0; t *= 0.5) {
    for (std::size_t i = 0; i < x.size(); ++i)
      trial[i].p_m = original[i].p_m + t * (x[i] - original[i].p_m);
    if (PathClear(clearance, trial, params.min_clearance_m)) {
      *points = trial;
      return Status::Ok();
    }
  }
  *points = original;
  return Status::Ok();
}

std::vector<double> InterpolateYaw(const std::vector<PathPoint>& points, double start_yaw_rad,
                                   const std::vector<double>& task_yaw_rad) {
  const std::size_t n = points.size();
  std::vector<double> out(n, WrapAngle(start_yaw_rad));
  if (n == 0) return out;
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) s[i] = s[i - 1] + (points[i].p_m - points[i - 1].p_m).norm();
  // Keys: (arc length, unwrapped yaw, point index); task yaws unwrapped to the shortest turn.
  std::vector<double> ks{0.0};
  std::vector<double> ky{start_yaw_rad};
  for (std::size_t i = 1; i < n; ++i) {
    if (points[i].task < 0) continue;
    const double yaw = task_yaw_rad[static_cast<std::size_t>(points[i].task)];
    const double unwrapped = ky.back() + WrapAngle(yaw - ky.back());
    if (s[i] <= ks.back() + 1e-9) {  // coincident key: the later one wins
      ky.back() = unwrapped;
      continue;
    }
    ks.push_back(s[i]);
    ky.push_back(unwrapped);
  }
  const std::size_t m = ks.size();
  if (points[0].task >= 0)  // the start itself is a task view
    ky[0] = start_yaw_rad +
            WrapAngle(task_yaw_rad[static_cast<std::size_t>(points[0].task)] - start_yaw_rad);
  std::vector<double> secant(m > 1 ? m - 1 : 0);
  for (std::size_t k = 0; k + 1 < m; ++k) secant[k] = (ky[k + 1] - ky[k]) / (ks[k + 1] - ks[k]);
  std::vector<double> tangent(m, 0.0);
  for (std::size_t k = 1; k + 1 < m; ++k) {
    if (secant[k - 1] * secant[k] > 0.0)  // harmonic mean keeps the spline monotone
      tangent[k] = 2.0 / (1.0 / secant[k - 1] + 1.0 / secant[k]);
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (m == 1 || s[i] >= ks.back()) {
      out[i] = WrapAngle(ky.back());
      continue;
    }
    while (k + 2 < m && s[i] > ks[k + 1]) ++k;
    const double h = ks[k + 1] - ks[k];
    const double t = (s[i] - ks[k]) / h;
    const double t2 = t * t;
    const double t3 = t2 * t;
    const double y = (2 * t3 - 3 * t2 + 1) * ky[k] + (t3 - 2 * t2 + t) * h * tangent[k] +
                     (-2 * t3 + 3 * t2) * ky[k + 1] + (t3 - t2) * h * tangent[k + 1];
    out[i] = WrapAngle(y);
  }
  return out;
}

std::vector<double> StepYaw(const std::vector<PathPoint>& points, double start_yaw_rad,
                            const std::vector<double>& task_yaw_rad) {
  std::vector<double> out(points.size(), WrapAngle(start_yaw_rad));
  double next = start_yaw_rad;  // after the last task view its yaw is held
  for (const PathPoint& p : points)
    if (p.task >= 0) next = task_yaw_rad[static_cast<std::size_t>(p.task)];
  for (std::size_t i = points.size(); i-- > 0;) {
    if (points[i].task >= 0) next = task_yaw_rad[static_cast<std::size_t>(points[i].task)];
    out[i] = WrapAngle(next);
  }
  return out;
}

}  // namespace voxplan::omt
