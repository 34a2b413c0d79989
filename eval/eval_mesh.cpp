#include "eval/eval_mesh.h"

// CGAL is GPL: it stays inside this translation unit, never in a voxplan header.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/parallel.h"

namespace voxplan {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

constexpr size_t kMaxSamples = 2'000'000;  // bounds time and memory on huge meshes
constexpr size_t kQueryGrain = 1024;

// Non-degenerate triangles in double precision with their areas.
struct TriangleSet {
  std::vector<Triangle> triangles;
  std::vector<uint32_t> source;            // index of each triangle in the mesh
  std::vector<double> cumulative_area_m2;  // inclusive prefix sums, for area-weighted sampling
  double area_m2 = 0.0;
};

// The triangles of `mesh` listed in `subset` (all of them when empty). `what` starts messages.
Result<TriangleSet> CollectTriangles(const Mesh& mesh, const std::string& what,
                                     const std::vector<uint32_t>& subset = {}) {
  if (mesh.empty()) return InvalidArgument(what + " is empty");
  const size_t count = subset.empty() ? mesh.num_triangles() : subset.size();
  TriangleSet set;
  set.triangles.reserve(count);
  set.source.reserve(count);
  set.cumulative_area_m2.reserve(count);
  const size_t nv = mesh.num_vertices();
  for (size_t k = 0; k < count; ++k) {
    const size_t t = subset.empty() ? k : size_t(subset[k]);
    if (t >= mesh.num_triangles())
      return InvalidArgument(what + ": triangle " + std::to_string(t) + " is out of range");
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv)
      return InvalidArgument(what + " triangle " + std::to_string(t) + " indexes a missing vertex");
    const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[tri[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[tri[2]].cast<double>();
    if (!a.allFinite() || !b.allFinite() || !c.allFinite())
      return InvalidArgument(what + " triangle " + std::to_string(t) + " has a non-finite vertex");
    const double area = 0.5 * (b - a).cross(c - a).norm();
    // Degenerate triangles carry no surface and upset CGAL's point-triangle distance.
    if (!(area > 0.0)) continue;
    set.triangles.emplace_back(Point(a.x(), a.y(), a.z()), Point(b.x(), b.y(), b.z()),
                               Point(c.x(), c.y(), c.z()));
    set.source.push_back(uint32_t(t));
    set.area_m2 += area;
    set.cumulative_area_m2.push_back(set.area_m2);
  }
  if (set.triangles.empty()) return InvalidArgument(what + " has no triangle with area");
  return set;
}

// Uniform double in [0, 1) from 53 random bits: the same on every standard library,
// unlike std::uniform_real_distribution.
double Uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Area-weighted uniform samples on the surface: a fixed count, triangles drawn by area.
std::vector<Point> SamplePoints(const TriangleSet& set, double samples_per_m2, uint64_t seed,
                                size_t min_samples = 1) {
  const double wanted =
      std::max(double(std::max<size_t>(min_samples, 1)), std::ceil(set.area_m2 * samples_per_m2));
  const size_t count = size_t(std::min(double(kMaxSamples), wanted));
  std::mt19937_64 rng(seed);
  std::vector<Point> samples;
  samples.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const double pick = Uniform01(rng) * set.area_m2;
    size_t t = size_t(
        std::upper_bound(set.cumulative_area_m2.begin(), set.cumulative_area_m2.end(), pick) -
        set.cumulative_area_m2.begin());
    t = std::min(t, set.triangles.size() - 1);
    // Square-root warp gives a uniform density over the triangle.
    const double r1 = std::sqrt(Uniform01(rng)), r2 = Uniform01(rng);
    const double w0 = 1.0 - r1, w1 = r1 * (1.0 - r2), w2 = r1 * r2;
    const Triangle& tri = set.triangles[t];
    samples.emplace_back(w0 * tri[0].x() + w1 * tri[1].x() + w2 * tri[2].x(),
                         w0 * tri[0].y() + w1 * tri[1].y() + w2 * tri[2].y(),
                         w0 * tri[0].z() + w1 * tri[1].z() + w2 * tri[2].z());
  }
  return samples;
}

// A triangle set and its AABB tree; never moves once built, since the tree points into the set.
struct SurfaceTree {
  TriangleSet set;
  Tree tree;

  explicit SurfaceTree(TriangleSet s)
      : set(std::move(s)), tree(set.triangles.begin(), set.triangles.end()) {
    // Build both the tree and its distance search structure now: afterwards queries are const
    // and safe from many threads.
    tree.build();
    tree.accelerate_distance_queries();
    (void)tree.squared_distance(set.triangles.front()[0]);
  }

  // Distance from every sample to the surface, and optionally the mesh index of the closest
  // triangle.
  std::vector<double> Distances(const std::vector<Point>& samples,
                                std::vector<uint32_t>* closest_triangle) const {
    std::vector<double> distances(samples.size());
    if (closest_triangle) closest_triangle->assign(samples.size(), 0);
    ParallelFor(samples.size(), kQueryGrain, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        if (!closest_triangle) {
          distances[i] = std::sqrt(CGAL::to_double(tree.squared_distance(samples[i])));
          continue;
        }
        const auto [point, id] = tree.closest_point_and_primitive(samples[i]);
        distances[i] = std::sqrt(CGAL::to_double(CGAL::squared_distance(samples[i], point)));
        (*closest_triangle)[i] = set.source[size_t(id - set.triangles.begin())];
      }
    });
    return distances;
  }
};

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  if (values.size() % 2 == 1) return values[mid];
  const double upper = values[mid];
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + mid));
}

}  // namespace

PointSetFilter KeepEach(std::function<bool(const Eigen::Vector3f&)> keep) {
  return [keep = std::move(keep)](const std::vector<Eigen::Vector3f>& points) {
    std::vector<uint8_t> kept(points.size(), 0);
    ParallelFor(points.size(), kQueryGrain, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) kept[i] = keep(points[i]) ? 1 : 0;
    });
    return kept;
  };
}

Result<MeshEvalResult> EvaluateMesh(const Mesh& reconstruction, const Mesh& ground_truth,
                                    const MeshEvalParams& params) {
  if (!(params.samples_per_m2 > 0.f) || !std::isfinite(params.samples_per_m2))
    return InvalidArgument("EvaluateMesh: samples_per_m2 must be positive");
  if (!(params.threshold_m >= 0.f) || !std::isfinite(params.threshold_m))
    return InvalidArgument("EvaluateMesh: threshold_m must be non-negative");
  Result<TriangleSet> recon = CollectTriangles(reconstruction, "EvaluateMesh: reconstruction");
  if (!recon.ok()) return recon.status();
  Result<TriangleSet> truth = CollectTriangles(ground_truth, "EvaluateMesh: ground truth");
  if (!truth.ok()) return truth.status();

  // Independent streams for the two surfaces, both fixed by the one seed.
  std::seed_seq recon_seq{params.seed, uint64_t(0)}, truth_seq{params.seed, uint64_t(1)};
  std::mt19937_64 seeder_recon(recon_seq), seeder_truth(truth_seq);
  const std::vector<Point> recon_samples =
      SamplePoints(*recon, params.samples_per_m2, seeder_recon());
  const std::vector<Point> truth_samples =
      SamplePoints(*truth, params.samples_per_m2, seeder_truth());

  MeshEvalResult result;
  result.reconstruction_area_m2 = recon->area_m2;
  result.ground_truth_area_m2 = truth->area_m2;
  result.reconstruction_samples = recon_samples.size();
  result.ground_truth_samples_all = truth_samples.size();

  // Accuracy (eq. 9): reconstruction samples to the ground-truth surface. Samples are equal-area,
  // so the area weights of the paper become a plain mean.
  // One tree at a time (each built from a set it then owns), to bound peak memory on large meshes.
  const std::vector<double> accuracy =
      SurfaceTree(std::move(*truth)).Distances(recon_samples, nullptr);
  double sum = 0.0, sum_sq = 0.0;
  for (double d : accuracy) {
    sum += d;
    sum_sq += d * d;
  }
  result.accuracy_mean_m = sum / double(accuracy.size());
  result.accuracy_rms_m = std::sqrt(sum_sq / double(accuracy.size()));
  result.accuracy_median_m = Median(accuracy);

  // Completeness (eq. 10-11): share of ground-truth samples with a reconstruction within
  // threshold_m, over all of them and over those the filter keeps (the observable surface).
  std::vector<uint8_t> kept(truth_samples.size(), 1);
  if (params.ground_truth_filter) {
    std::vector<Eigen::Vector3f> points;
    points.reserve(truth_samples.size());
    for (const Point& p : truth_samples)
      points.emplace_back(float(p.x()), float(p.y()), float(p.z()));
    kept = params.ground_truth_filter(points);
    if (kept.size() != points.size())
      return InvalidArgument("EvaluateMesh: ground_truth_filter answered for " +
                             std::to_string(kept.size()) + " of " + std::to_string(points.size()) +
                             " samples");
    for (uint8_t& k : kept) k = k ? 1 : 0;
  }
  const size_t kept_count = size_t(std::count(kept.begin(), kept.end(), uint8_t(1)));
  if (kept_count == 0)
    return InvalidArgument("EvaluateMesh: ground_truth_filter keeps no ground-truth sample");
  const std::vector<double> coverage =
      SurfaceTree(std::move(*recon)).Distances(truth_samples, nullptr);
  const double threshold = double(params.threshold_m);
  size_t covered = 0, covered_kept = 0, below = 0, covered_below = 0;
  for (size_t i = 0; i < coverage.size(); ++i) {
    const bool low = kept[i] && float(truth_samples[i].z()) <= params.below_z_m;
    below += low;
    if (!(coverage[i] < threshold)) continue;
    ++covered;
    covered_kept += kept[i];
    covered_below += low;
  }
  result.ground_truth_samples = kept_count;
  result.completeness = double(covered_kept) / double(kept_count);
  result.completeness_all = double(covered) / double(coverage.size());
  result.completeness_below = below > 0 ? double(covered_below) / double(below) : 0.0;
  return result;
}

Result<SurfaceSamples> SampleSurface(const Mesh& mesh, double samples_per_m2, uint64_t seed,
                                     const std::vector<uint32_t>& triangles, size_t min_samples,
                                     const std::string& what) {
  if (!(samples_per_m2 > 0.0) || !std::isfinite(samples_per_m2))
    return InvalidArgument("SampleSurface: samples_per_m2 must be positive");
  Result<TriangleSet> set = CollectTriangles(mesh, what, triangles);
  if (!set.ok()) return set.status();
  SurfaceSamples samples;
  samples.area_m2 = set->area_m2;
  const std::vector<Point> points = SamplePoints(*set, samples_per_m2, seed, min_samples);
  samples.points.reserve(points.size());
  for (const Point& p : points) samples.points.emplace_back(p.x(), p.y(), p.z());
  return samples;
}

struct SurfaceDistance::Impl {
  explicit Impl(TriangleSet set) : surface(std::move(set)) {}
  SurfaceTree surface;
};

SurfaceDistance::SurfaceDistance(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SurfaceDistance::SurfaceDistance(SurfaceDistance&&) noexcept = default;
SurfaceDistance& SurfaceDistance::operator=(SurfaceDistance&&) noexcept = default;
SurfaceDistance::~SurfaceDistance() = default;

Result<SurfaceDistance> SurfaceDistance::Build(const Mesh& mesh, const std::string& what) {
  Result<TriangleSet> set = CollectTriangles(mesh, what);
  if (!set.ok()) return set.status();
  return SurfaceDistance(std::make_unique<Impl>(std::move(*set)));
}

std::vector<double> SurfaceDistance::Distances(const std::vector<Eigen::Vector3d>& points,
                                               std::vector<uint32_t>* closest_triangle) const {
  std::vector<Point> samples;
  samples.reserve(points.size());
  for (const Eigen::Vector3d& p : points) samples.emplace_back(p.x(), p.y(), p.z());
  return impl_->surface.Distances(samples, closest_triangle);
}

}  // namespace voxplan
