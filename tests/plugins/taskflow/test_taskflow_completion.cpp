#include <gtest/gtest.h>

#include <cmath>

#include "plugins/taskflow/algorithms/completion.h"
#include "tests/plugins/taskflow/taskflow_scenes.h"

namespace voxplan::taskflow {
namespace {

using testing::Chair;
using testing::CoveredShare;
using testing::Everywhere;
using testing::LShape;
using testing::MapQuery;
using testing::Region;
using testing::Solid;
using testing::Surface;
using testing::UnitBox;

constexpr float kSpacing = 0.02f;      // observed surface samples, about a 2 cm map voxel
constexpr float kFillRadius = 0.05f;   // a hidden surface point counts as predicted within this
constexpr float kMinFillShare = 0.8f;  // share of hidden surface that must be predicted
constexpr float kAngleTol = 0.02f;     // rad
constexpr std::uint64_t kSeed = 7;

CompletionResult Complete(const Solid& solid, const Region& seen, const SpaceQuery& space,
                          const CompletionParams& params = {}) {
  const Surface s = solid.Sample(kSpacing, seen);
  return CompleteObject(s.points, s.normals, 0.0f, space, params, kSeed);
}

// The front half (y <= 0) of the unit box, the camera's side of space seen, the rest hidden.
CompletionResult HalfSeenBox() {
  const Region front = [](const Eigen::Vector3f& p) { return p.y() <= 0.0f; };
  return Complete(UnitBox(), front, MapQuery(UnitBox(), front));
}

TEST(TaskflowCompletion, FullyObservedBoxIsComplete) {
  const Solid box = UnitBox();
  const CompletionResult r = Complete(box, Everywhere(), MapQuery(box, Everywhere()));
  ASSERT_FALSE(r.predicted.empty());
  EXPECT_EQ(r.observed.size(), 2048u);
  EXPECT_FALSE(r.incomplete);
  EXPECT_EQ(r.incompleteness, 0.0f);
  // Complete by the absolute floor: the mean of a max-normalised score need not be small.
  EXPECT_LT(r.max_distance_m, CompletionParams{}.min_max_distance_m);
}

TEST(TaskflowCompletion, HalfSeenBoxIsIncompleteAndItsBackIsPredicted) {
  const CompletionResult r = HalfSeenBox();
  EXPECT_TRUE(r.incomplete);
  EXPECT_GE(r.mean_score, CompletionParams{}.tau);
  EXPECT_GE(r.max_distance_m, CompletionParams{}.min_max_distance_m);
  EXPECT_GT(r.incompleteness, 0.0f);
  EXPECT_TRUE(r.used_box);
  // The box grew into the hidden half: its back reaches the true back face.
  EXPECT_NEAR(r.box_centre.y(), 0.0f, 0.05f);
  EXPECT_NEAR(r.box_half_extent.y(), 0.5f, 0.05f);
  const Surface back =
      UnitBox().Sample(kSpacing, [](const Eigen::Vector3f& p) { return p.y() >= 0.499f; });
  ASSERT_FALSE(back.points.empty());
  EXPECT_GE(CoveredShare(back.points, r.predicted, kFillRadius), kMinFillShare);
  // Scores: normalised, and the hidden back is where they are high.
  float max_score = 0.0f;
  for (std::size_t i = 0; i < r.score.size(); ++i) {
    EXPECT_GE(r.score[i], 0.0f);
    EXPECT_LE(r.score[i], 1.0f);
    max_score = std::max(max_score, r.score[i]);
    if (r.score[i] > 0.5f) {
      EXPECT_GT(r.predicted[i].y(), 0.0f);
    }
  }
  EXPECT_FLOAT_EQ(max_score, 1.0f);
}

TEST(TaskflowCompletion, SymmetryFillsTheUnseenSideOfASymmetricObject) {
  const Solid chair = Chair();
  const Region left = [](const Eigen::Vector3f& p) { return p.x() <= 0.0f; };
  CompletionParams only_mirror;
  only_mirror.use_box = false;
  only_mirror.use_hull = false;
  const CompletionResult r = Complete(chair, left, MapQuery(chair, left), only_mirror);
  ASSERT_TRUE(r.used_symmetry);
  EXPECT_TRUE(r.symmetry.accepted);
  // The plane found is x = 0 (normal along ±x): the box axes are on the angle grid.
  EXPECT_GT(std::abs(std::cos(r.symmetry.angle_rad)), std::cos(kAngleTol));
  const Surface right =
      chair.Sample(kSpacing, [](const Eigen::Vector3f& p) { return p.x() > 0.02f; });
  EXPECT_GE(CoveredShare(right.points, r.predicted, kFillRadius), kMinFillShare);
  EXPECT_TRUE(r.incomplete);
}

TEST(TaskflowCompletion, MirrorPlaneIsRefusedWhenReflectionsLandInObservedFreeSpace) {
  const Solid chair = Chair();
  const Region left = [](const Eigen::Vector3f& p) { return p.x() <= 0.0f; };
  const Surface seen = chair.Sample(kSpacing, left);
  const CompletionParams params;
  // The other side hidden: the true plane is plausible.
  const MirrorPlaneCheck hidden =
      CheckMirrorPlane(seen.points, Eigen::Vector2f::Zero(), 0.0f, MapQuery(chair, left), params);
  EXPECT_TRUE(hidden.accepted);
  EXPECT_LT(hidden.free_share, params.symmetry_max_free);
  // The other side seen empty (only the left half exists): the same plane is refused.
  Solid half = chair;
  for (Eigen::AlignedBox3f& b : half.boxes) b.max().x() = 0.0f;
  const MirrorPlaneCheck seen_empty = CheckMirrorPlane(seen.points, Eigen::Vector2f::Zero(), 0.0f,
                                                       MapQuery(half, Everywhere()), params);
  EXPECT_FALSE(seen_empty.accepted);
  EXPECT_GE(seen_empty.free_share, params.symmetry_max_free);
}

TEST(TaskflowCompletion, AsymmetricObjectSeenAllRoundHasNoSymmetry) {
  const Solid l = LShape();
  const CompletionResult r = Complete(l, Everywhere(), MapQuery(l, Everywhere()));
  EXPECT_FALSE(r.used_symmetry);
  EXPECT_FALSE(r.symmetry.accepted);
  EXPECT_FALSE(r.incomplete);
}

TEST(TaskflowCompletion, PredictedPointsInObservedFreeSpaceAreDropped) {
  // Only the left half of the chair exists and everything around it was seen: the box top over
  // the seat and the hull's corner over the seat front are in free space.
  Solid half = Chair();
  for (Eigen::AlignedBox3f& b : half.boxes) b.max().x() = 0.0f;
  const SpaceQuery space = MapQuery(half, Everywhere());
  const CompletionResult r = Complete(half, Everywhere(), space);
  EXPECT_GT(r.dropped_free, 0);
  ASSERT_FALSE(r.predicted.empty());
  std::vector<std::uint8_t> state(r.predicted.size());
  space(r.predicted, state);
  for (std::size_t i = 0; i < state.size(); ++i) {
    EXPECT_NE(state[i], kObservedFree) << r.predicted[i].transpose();
  }
}

TEST(TaskflowCompletion, SameInputAndSeedGiveIdenticalOutput) {
  const CompletionResult a = HalfSeenBox();
  const CompletionResult b = HalfSeenBox();
  ASSERT_EQ(a.predicted.size(), b.predicted.size());
  for (std::size_t i = 0; i < a.predicted.size(); ++i) {
    EXPECT_EQ(a.predicted[i], b.predicted[i]);
    EXPECT_EQ(a.normals[i], b.normals[i]);
    EXPECT_EQ(a.score[i], b.score[i]);
  }
  EXPECT_EQ(a.observed, b.observed);
  EXPECT_EQ(a.mean_score, b.mean_score);
  EXPECT_EQ(a.symmetry.angle_rad, b.symmetry.angle_rad);
}

TEST(TaskflowCompletion, HalfSeenBoxRanksAboveAMostlySeenOne) {
  const Solid box = UnitBox();
  // Everything but the lower half of the back face (10 % of the scannable surface); behind the
  // box only the space above that strip was seen.
  const Region mostly = [](const Eigen::Vector3f& p) { return !(p.y() > 0.49f && p.z() < 0.5f); };
  const CompletionResult most = Complete(box, mostly, MapQuery(box, mostly));
  const CompletionResult half = HalfSeenBox();
  EXPECT_GT(half.incompleteness, most.incompleteness);
  EXPECT_GT(half.missing_share, most.missing_share);
  EXPECT_GT(most.missing_share, 0.0f);  // the strip is still found missing
}

TEST(TaskflowCompletion, FarthestPointSamplingSpreadsAndIsSeeded) {
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i <= 100; ++i) line.emplace_back(0.01f * static_cast<float>(i), 0.0f, 0.0f);
  // Ten picks cover the unit line within twice the best possible radius (1 / 18), whatever the
  // seeded start: farthest-point sampling's guarantee.
  const std::vector<int> picks = FarthestPointSample(line, 10, 3);
  ASSERT_EQ(picks.size(), 10u);
  std::vector<Eigen::Vector3f> picked;
  for (const int i : picks) picked.push_back(line[static_cast<std::size_t>(i)]);
  for (const float d : NearestDistances(picked, line)) EXPECT_LE(d, 2.0f / 18.0f + 1e-4f);
  EXPECT_EQ(FarthestPointSample(line, 10, 3), FarthestPointSample(line, 10, 3));
  EXPECT_EQ(FarthestPointSample(line, 500, 3).size(), line.size());
}

TEST(TaskflowCompletion, NearestDistancesMatchBruteForce) {
  std::vector<Eigen::Vector3f> ref, queries;
  for (int i = 0; i < 300; ++i) {
    const float t = static_cast<float>(i);
    ref.emplace_back(std::sin(1.3f * t), std::cos(0.7f * t), std::sin(0.31f * t + 1.0f));
    queries.emplace_back(std::cos(2.1f * t), std::sin(0.9f * t), std::cos(0.53f * t));
  }
  const std::vector<float> d = NearestDistances(ref, queries);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    float best = 1e9f;
    for (const Eigen::Vector3f& p : ref) best = std::min(best, (p - queries[i]).norm());
    EXPECT_FLOAT_EQ(d[i], best);
  }
}

TEST(TaskflowCompletion, ConvexHullIsCounterClockwiseWithoutInteriorPoints) {
  std::vector<Eigen::Vector2f> pts = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 0.5f}, {0.5f, 0}};
  const std::vector<Eigen::Vector2f> hull = ConvexHull2d(pts);
  ASSERT_EQ(hull.size(), 4u);
  float area2 = 0.0f;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f& a = hull[i];
    const Eigen::Vector2f& b = hull[(i + 1) % hull.size()];
    area2 += a.x() * b.y() - a.y() * b.x();
  }
  EXPECT_FLOAT_EQ(area2, 2.0f);  // positive: counter-clockwise
}

TEST(TaskflowCompletion, DegenerateInputsGiveFiniteResults) {
  const SpaceQuery space = MapQuery(UnitBox(), Everywhere());
  const std::vector<Eigen::Vector3f> one = {{0.2f, 0.1f, 0.5f}};
  std::vector<Eigen::Vector3f> line;  // a vertical pole: a zero-area footprint
  for (int i = 0; i < 50; ++i) line.emplace_back(0.0f, 0.0f, 0.02f * static_cast<float>(i));
  const std::vector<Eigen::Vector3f>* cases[] = {&one, &line};
  for (const std::vector<Eigen::Vector3f>* pts : cases) {
    const CompletionResult r = CompleteObject(*pts, {}, 0.0f, space, CompletionParams{}, kSeed);
    EXPECT_EQ(r.observed.size(), pts->size());
    for (std::size_t i = 0; i < r.predicted.size(); ++i) {
      EXPECT_TRUE(r.predicted[i].allFinite());
      EXPECT_TRUE(std::isfinite(r.score[i]));
    }
    EXPECT_TRUE(std::isfinite(r.mean_score));
  }
}

TEST(TaskflowCompletion, EmptyInputIsComplete) {
  const CompletionResult r =
      CompleteObject({}, {}, 0.0f, MapQuery(UnitBox(), Everywhere()), CompletionParams{}, kSeed);
  EXPECT_TRUE(r.predicted.empty());
  EXPECT_FALSE(r.incomplete);
}

}  // namespace
}  // namespace voxplan::taskflow
