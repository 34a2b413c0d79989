// Path optimisation of §3.5: eq. 5 over points sampled along the geodesic polyline,
//   Σ 2 / (η(p_i) + η(p_{i+1})) ‖p_i − p_{i+1}‖² + λ Σ_{t ∈ T_r} ‖p_t − p_t⁰‖²,   λ = 10,
// η clamped to [eta_floor_m, eta_cap_m],
// solved with Ceres, then camera yaw by cubic Hermite interpolation between the task views.
#pragma once

#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

struct PathPoint {
  Eigen::Vector2d p_m = Eigen::Vector2d::Zero();
  int task = -1;  // task id when this point is a task view (kept by the λ term), else -1
};

struct SmoothingParams {
  double lambda = 10.0;
  double sample_spacing_m = 0.2;
  // η is floored here so 2 / (η_i + η_{i+1}) stays finite next to (or inside) obstacles.
  double eta_floor_m = 0.02;
  // Our choice: η is truncated here. Past it a point is clear of everything, and the full
  // 1/η weight would bow paths towards the middle of every room they cross (over the suite's
  // runs, planned paths 2.5 % (3 robots) / 3.0 % (6) longer than the geodesics they smooth;
  // 0.1 % / 0.3 % truncated). At least eta_floor_m.
  double eta_cap_m = 0.5;
  // Our addition to eq. 5 (the paper relies on the 1/η barrier alone, which only sees the
  // samples and lets them jump thin walls): a hinge penalty weight · max(0, min_clearance − η)
  // per point, and afterwards a step-back towards the input path until every segment keeps
  // min_clearance. The input path must keep it.
  double min_clearance_m = 0.18;
  double clearance_weight = 10.0;
  int max_iterations = 50;
};

// Uniform samples (about sample_spacing_m apart) along a polyline whose vertices listed in
// task_vertices (vertex index, task id) are kept as task points.
std::vector<PathPoint> SamplePolyline(const std::vector<Eigen::Vector2d>& polyline,
                                      const std::vector<std::pair<int, int>>& task_vertices,
                                      double spacing_m);

// Eq. 5 energy of points against their original positions (the λ term uses task points).
double Eq5Energy(const ClearanceRaster& clearance, const std::vector<PathPoint>& points,
                 const std::vector<PathPoint>& original, const SmoothingParams& params);

// Minimises eq. 5 in place; the first point (the robot) is fixed. On solver failure the points
// are left as given and an error is returned.
Status SmoothPath(const ClearanceRaster& clearance, const SmoothingParams& params,
                  std::vector<PathPoint>* points);

// Camera yaw per point: key yaws at the start (the robot's current yaw, index 0) and at task
// points, unwrapped along the path, interpolated over arc length by a monotone cubic Hermite
// spline (Fritsch–Carlson tangents: no overshoot between keys), held after the last key.
// task_yaw_rad[id] is the yaw of task id. Result wrapped to (-pi, pi].
std::vector<double> InterpolateYaw(const std::vector<PathPoint>& points, double start_yaw_rad,
                                   const std::vector<double>& task_yaw_rad);

// NoPO ablation: each point takes the yaw of the next task view on the path.
std::vector<double> StepYaw(const std::vector<PathPoint>& points, double start_yaw_rad,
                            const std::vector<double>& task_yaw_rad);

double PolylineLength(const std::vector<PathPoint>& points);

}  // namespace voxplan::omt
