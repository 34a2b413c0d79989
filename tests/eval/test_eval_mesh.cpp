// EvaluateMesh on hand-made meshes whose accuracy and completeness are known exactly.
#include <gtest/gtest.h>

#include "core/parallel.h"
#include "eval/eval_mesh.h"

namespace voxplan {
namespace {

constexpr double kDistanceTolerance_m = 1e-4;
// 10,000 samples on a unit square: the binomial standard deviation of a 0.5 share is 0.005.
constexpr double kShareTolerance = 0.02;

// Axis-aligned rectangle in the plane z = z0, two triangles facing +z.
Mesh Rectangle(float x0, float y0, float x1, float y1, float z0) {
  Mesh mesh;
  mesh.positions = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}
Mesh UnitSquare(float z0 = 0.f) { return Rectangle(0.f, 0.f, 1.f, 1.f, z0); }

TEST(EvaluateMesh, IdenticalMeshesArePerfect) {
  auto result = EvaluateMesh(UnitSquare(), UnitSquare());
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_NEAR(result->accuracy_mean_m, 0.0, 1e-6);
  EXPECT_NEAR(result->accuracy_rms_m, 0.0, 1e-6);
  EXPECT_NEAR(result->accuracy_median_m, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(result->completeness, 1.0);
  EXPECT_NEAR(result->reconstruction_area_m2, 1.0, 1e-9);
  EXPECT_NEAR(result->ground_truth_area_m2, 1.0, 1e-9);
  EXPECT_EQ(result->reconstruction_samples, 10000u);  // ceil(area * samples_per_m2)
  EXPECT_EQ(result->ground_truth_samples, 10000u);
  EXPECT_EQ(result->ground_truth_samples_all, 10000u);
  EXPECT_DOUBLE_EQ(result->completeness_all, 1.0);
}

TEST(EvaluateMesh, ShiftAlongNormalIsTheAccuracy) {
  MeshEvalParams params;
  params.threshold_m = 0.05f;
  auto near = EvaluateMesh(UnitSquare(0.02f), UnitSquare(), params);
  ASSERT_TRUE(near.ok()) << near.status().message();
  EXPECT_NEAR(near->accuracy_mean_m, 0.02, kDistanceTolerance_m);
  EXPECT_NEAR(near->accuracy_rms_m, 0.02, kDistanceTolerance_m);
  EXPECT_NEAR(near->accuracy_median_m, 0.02, kDistanceTolerance_m);
  EXPECT_DOUBLE_EQ(near->completeness, 1.0);

  params.threshold_m = 0.01f;
  auto strict = EvaluateMesh(UnitSquare(0.02f), UnitSquare(), params);
  ASSERT_TRUE(strict.ok());
  EXPECT_NEAR(strict->accuracy_mean_m, 0.02, kDistanceTolerance_m);
  EXPECT_DOUBLE_EQ(strict->completeness, 0.0);
}

TEST(EvaluateMesh, HalfReconstructionIsHalfComplete) {
  // A small threshold so the strip of width threshold_m beside the half adds little.
  MeshEvalParams params;
  params.threshold_m = 0.005f;
  auto result = EvaluateMesh(Rectangle(0.f, 0.f, 0.5f, 1.f, 0.f), UnitSquare(), params);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_NEAR(result->completeness, 0.5, kShareTolerance);
  EXPECT_NEAR(result->accuracy_mean_m, 0.0, 1e-6);  // all of it lies on the truth
  EXPECT_EQ(result->reconstruction_samples, 5000u);

  // The reverse: a full reconstruction of half the truth is complete but half of it is extra,
  // at a mean distance of 0.25 m from the truth.
  auto extra = EvaluateMesh(UnitSquare(), Rectangle(0.f, 0.f, 0.5f, 1.f, 0.f), params);
  ASSERT_TRUE(extra.ok());
  EXPECT_DOUBLE_EQ(extra->completeness, 1.0);
  EXPECT_NEAR(extra->accuracy_mean_m, 0.125, 0.01);
}

TEST(EvaluateMesh, CompletenessBelowCountsTheKeptSamplesUnderTheHeight) {
  // Truth: a floor square at z = 0 and a ceiling square at z = 2; only the floor reconstructed.
  Mesh truth = UnitSquare(0.f);
  const Mesh ceiling = UnitSquare(2.f);
  for (const auto& t : ceiling.triangles) truth.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  truth.positions.insert(truth.positions.end(), ceiling.positions.begin(), ceiling.positions.end());
  MeshEvalParams params;
  params.threshold_m = 0.005f;
  auto all = EvaluateMesh(UnitSquare(0.f), truth, params);  // below_z_m = +inf: every sample
  ASSERT_TRUE(all.ok()) << all.status().message();
  EXPECT_EQ(all->completeness_below, all->completeness);
  EXPECT_NEAR(all->completeness, 0.5, kShareTolerance);
  params.below_z_m = 1.8f;  // the floor only
  auto low = EvaluateMesh(UnitSquare(0.f), truth, params);
  ASSERT_TRUE(low.ok());
  EXPECT_DOUBLE_EQ(low->completeness_below, 1.0);
  EXPECT_EQ(low->completeness, all->completeness);  // the other figures do not change
  // Kept and below together: the filter keeps x < 0.5, of the floor all is covered.
  params.ground_truth_filter = KeepEach([](const Eigen::Vector3f& p) { return p.x() < 0.5f; });
  auto both = EvaluateMesh(UnitSquare(0.f), truth, params);
  ASSERT_TRUE(both.ok());
  EXPECT_DOUBLE_EQ(both->completeness_below, 1.0);
  // Nothing below: 0, not an error.
  params.below_z_m = -1.f;
  auto none = EvaluateMesh(UnitSquare(0.f), truth, params);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->completeness_below, 0.0);
}

TEST(EvaluateMesh, GroundTruthFilterRestrictsCompleteness) {
  MeshEvalParams params;
  params.threshold_m = 0.005f;
  const Mesh half = Rectangle(0.f, 0.f, 0.5f, 1.f, 0.f);
  auto unfiltered = EvaluateMesh(half, UnitSquare(), params);
  ASSERT_TRUE(unfiltered.ok()) << unfiltered.status().message();
  EXPECT_EQ(unfiltered->completeness, unfiltered->completeness_all);
  EXPECT_EQ(unfiltered->ground_truth_samples, unfiltered->ground_truth_samples_all);

  // Only the half that was reconstructed counts: complete there, half complete overall.
  params.ground_truth_filter = KeepEach([](const Eigen::Vector3f& p) { return p.x() < 0.5f; });
  auto filtered = EvaluateMesh(half, UnitSquare(), params);
  ASSERT_TRUE(filtered.ok()) << filtered.status().message();
  EXPECT_DOUBLE_EQ(filtered->completeness, 1.0);
  EXPECT_EQ(filtered->completeness_all, unfiltered->completeness_all);
  EXPECT_NEAR(filtered->completeness_all, 0.5, kShareTolerance);
  EXPECT_EQ(filtered->ground_truth_samples_all, 10000u);
  EXPECT_NEAR(double(filtered->ground_truth_samples), 5000.0, 10000.0 * kShareTolerance);
  // Accuracy does not depend on the filter.
  EXPECT_EQ(filtered->accuracy_rms_m, unfiltered->accuracy_rms_m);

  // The other half only: nothing of it was reconstructed.
  params.ground_truth_filter = KeepEach([](const Eigen::Vector3f& p) { return p.x() > 0.51f; });
  auto other = EvaluateMesh(half, UnitSquare(), params);
  ASSERT_TRUE(other.ok());
  EXPECT_DOUBLE_EQ(other->completeness, 0.0);

  params.ground_truth_filter = KeepEach([](const Eigen::Vector3f&) { return false; });
  auto none = EvaluateMesh(half, UnitSquare(), params);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().code(), StatusCode::kInvalidArgument);
}

TEST(EvaluateMesh, RefusesEmptyMeshes) {
  auto no_reconstruction = EvaluateMesh(Mesh{}, UnitSquare());
  ASSERT_FALSE(no_reconstruction.ok());
  EXPECT_EQ(no_reconstruction.status().code(), StatusCode::kInvalidArgument);
  auto no_truth = EvaluateMesh(UnitSquare(), Mesh{});
  ASSERT_FALSE(no_truth.ok());
  EXPECT_EQ(no_truth.status().code(), StatusCode::kInvalidArgument);

  Mesh degenerate = UnitSquare();
  for (auto& p : degenerate.positions) p.y() = 0.f;  // zero area
  EXPECT_FALSE(EvaluateMesh(degenerate, UnitSquare()).ok());
  Mesh bad_index = UnitSquare();
  bad_index.triangles.push_back({0, 1, 9});
  EXPECT_FALSE(EvaluateMesh(bad_index, UnitSquare()).ok());
}

TEST(EvaluateMesh, SameSeedSameResult) {
  MeshEvalParams params;
  params.threshold_m = 0.01f;
  const Mesh recon = Rectangle(0.1f, -0.2f, 0.8f, 0.7f, 0.012f);
  const auto a = EvaluateMesh(recon, UnitSquare(), params);
  const auto b = EvaluateMesh(recon, UnitSquare(), params);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->accuracy_mean_m, b->accuracy_mean_m);
  EXPECT_EQ(a->accuracy_rms_m, b->accuracy_rms_m);
  EXPECT_EQ(a->accuracy_median_m, b->accuracy_median_m);
  EXPECT_EQ(a->completeness, b->completeness);

  {
    ThreadLimit one_thread(1);  // parallel distance queries: same numbers on one thread
    const auto serial = EvaluateMesh(recon, UnitSquare(), params);
    ASSERT_TRUE(serial.ok());
    EXPECT_EQ(a->accuracy_mean_m, serial->accuracy_mean_m);
    EXPECT_EQ(a->accuracy_median_m, serial->accuracy_median_m);
    EXPECT_EQ(a->completeness, serial->completeness);
  }

  params.seed = 7;
  const auto c = EvaluateMesh(recon, UnitSquare(), params);
  ASSERT_TRUE(c.ok());
  EXPECT_NE(a->accuracy_mean_m, c->accuracy_mean_m);  // another seed, other samples
  EXPECT_NEAR(a->accuracy_mean_m, c->accuracy_mean_m, 0.01);
}

}  // namespace
}  // namespace voxplan
