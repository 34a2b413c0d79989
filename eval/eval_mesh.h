#pragma once
// Reconstruction vs ground truth, Dong et al. 2019 eq. 9-10 with area-weighted samples:
// accuracy = distances from samples on the reconstruction to the ground-truth surface (mean, RMS),
// completeness = fraction of ground-truth samples within `threshold_m` of the reconstruction.
// Point-to-triangle distances through CGAL AABB trees. An optional filter restricts completeness
// to the ground truth a sensor could have seen (eval/visibility.h builds one from a trajectory).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/status.h"

namespace voxplan {

// Which of a set of world-frame points to keep: one flag (0 or 1) per point, in order. A whole
// set at once, so that a filter can stream through what it needs (eval/visibility.h renders one
// view at a time).
using PointSetFilter =
    std::function<std::vector<uint8_t>(const std::vector<Eigen::Vector3f>& points)>;
// A PointSetFilter asking `keep` point by point, from several threads at once.
PointSetFilter KeepEach(std::function<bool(const Eigen::Vector3f&)> keep);

struct MeshEvalParams {
  float threshold_m = 0.05f;
  float samples_per_m2 = 10000.0f;
  uint64_t seed = 1;
  // Which ground-truth samples count for `completeness`; empty: all of them.
  PointSetFilter ground_truth_filter;
  // Also `completeness_below`: over the kept samples at or below this height (Xu 2017's
  // reference, the surface below the robot); +inf: every kept sample.
  float below_z_m = std::numeric_limits<float>::infinity();
};

struct MeshEvalResult {
  double accuracy_mean_m = 0.0;
  double accuracy_rms_m = 0.0;
  double accuracy_median_m = 0.0;
  double completeness = 0.0;        // 0..1, over the samples ground_truth_filter keeps
  double completeness_all = 0.0;    // 0..1, over every ground-truth sample
  double completeness_below = 0.0;  // 0..1, over the kept samples at or below below_z_m (0: none)
  double reconstruction_area_m2 = 0.0;
  double ground_truth_area_m2 = 0.0;
  size_t reconstruction_samples = 0;
  size_t ground_truth_samples = 0;      // kept by ground_truth_filter
  size_t ground_truth_samples_all = 0;  // before the filter
};

// Refuses empty meshes, and a filter that keeps no ground-truth sample (or answers for another
// number of samples).
Result<MeshEvalResult> EvaluateMesh(const Mesh& reconstruction, const Mesh& ground_truth,
                                    const MeshEvalParams& params = {});

// The building blocks EvaluateMesh uses, shared with per-object evaluation (eval/eval_objects.h).

// Area-weighted uniform surface samples of `mesh`, restricted to the triangles listed in
// `triangles` when it is not empty. count = ceil(area * samples_per_m2), at least min_samples,
// at most 2,000,000. Degenerate triangles are skipped. Refuses an empty mesh or selection,
// indices out of range, non-finite vertices and a selection without area; `what` names the mesh
// in messages. The same arguments give the same samples on every platform.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points;
  double area_m2 = 0.0;  // of the sampled triangles
};
Result<SurfaceSamples> SampleSurface(const Mesh& mesh, double samples_per_m2, uint64_t seed,
                                     const std::vector<uint32_t>& triangles = {},
                                     size_t min_samples = 1, const std::string& what = "mesh");

// Distances from points to a triangle surface, through an AABB tree built once.
class SurfaceDistance {
 public:
  // Refuses what SampleSurface refuses (the whole mesh is used).
  static Result<SurfaceDistance> Build(const Mesh& mesh, const std::string& what = "mesh");
  SurfaceDistance(SurfaceDistance&&) noexcept;
  SurfaceDistance& operator=(SurfaceDistance&&) noexcept;
  ~SurfaceDistance();

  // Distance from each point to the surface, in parallel; with `closest_triangle`, also the
  // index (into the mesh's triangles) of the triangle holding the closest surface point.
  std::vector<double> Distances(const std::vector<Eigen::Vector3d>& points,
                                std::vector<uint32_t>* closest_triangle = nullptr) const;

 private:
  struct Impl;
  explicit SurfaceDistance(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace voxplan
