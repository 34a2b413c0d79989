// Space-time interpolation between key frames (X eq. 4-5) and its linear ablation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "plugins/tensorfield/algorithms/tensor_field.h"
#include "tests/plugins/tensorfield/tensor_scenes.h"

namespace voxplan::tensorfield {
namespace {

using omt::Cell;
using test::FillRect;
using test::MakeRaster;

// Two key frames of a room whose inner box moved by 0.4 m: spatially rough near the box and the
// corners, so the space-time solve has something to smooth.
struct KeyFrames {
  TensorRaster previous, next;
};
KeyFrames MovingBox() {
  omt::OccupancyRaster a = MakeRaster(5.0, 4.0, Cell::kOccupied);
  FillRect(&a, 0.5, 0.5, 4.5, 3.5, Cell::kFree);
  omt::OccupancyRaster b = a;
  FillRect(&a, 1.5, 1.5, 2.1, 2.0, Cell::kOccupied);
  FillRect(&b, 1.9, 1.7, 2.5, 2.2, Cell::kOccupied);
  return {KeyFrameField(a, {}), KeyFrameField(b, {})};
}

double MaxDifference(const TensorRaster& a, const TensorRaster& b,
                     std::span<const std::uint8_t> mask) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.tau11.size(); ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    d = std::max({d, std::abs(a.tau11[i] - b.tau11[i]), std::abs(a.tau12[i] - b.tau12[i])});
  }
  return d;
}

// The soft constraints let the end frames move by about |Δᵀ Δ τ| / α: the Laplacian rows are
// O(1) for unit basis tensors, α = 5e3, so 1e-3 leaves a factor of ten (we measure ~1e-4).
constexpr double kEndFrameTolerance = 1e-3;

TEST(SpaceTime, EndFramesMatchTheKeyFramesWithinAlpha) {
  const KeyFrames k = MovingBox();
  const std::vector<std::uint8_t> mask = InterpolationMask(k.previous, k.next, {});
  const SpaceTimeResult r = InterpolateFrames(k.previous, k.next, mask, {});
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  ASSERT_EQ(r.frames.size(), 11u);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(MaxDifference(r.frames.front(), k.previous, mask), kEndFrameTolerance);
  EXPECT_LE(MaxDifference(r.frames.back(), k.next, mask), kEndFrameTolerance);
  // ... and they did move: the constraints are soft (a zero here would mean α was ignored).
  EXPECT_GT(MaxDifference(r.frames.front(), k.previous, mask), 0.0);
}

TEST(SpaceTime, EnergyBelowLinearInterpolation) {
  const KeyFrames k = MovingBox();
  const std::vector<std::uint8_t> mask = InterpolationMask(k.previous, k.next, {});
  const SpaceTimeResult r = InterpolateFrames(k.previous, k.next, mask, {});
  ASSERT_TRUE(r.status.ok());
  EXPECT_GT(r.energy_linear, 0.0);
  // The linear blend is a feasible point of the same energy, so the minimum is at most its
  // energy; on this rough pair it is clearly lower (we measure 0.63 of it).
  EXPECT_LT(r.energy, 0.9 * r.energy_linear) << r.energy << " vs " << r.energy_linear;
}

TEST(SpaceTime, InteriorRowsAreHarmonicWithExactEnds) {
  const KeyFrames k = MovingBox();
  const std::vector<std::uint8_t> mask = InterpolationMask(k.previous, k.next, {});
  SpaceTimeParams params;
  params.rows = SpaceTimeRows::kInteriorFrames;
  params.tolerance = 1e-6;
  const SpaceTimeResult r = InterpolateFrames(k.previous, k.next, mask, params);
  ASSERT_TRUE(r.status.ok());
  EXPECT_EQ(MaxDifference(r.frames.front(), k.previous, mask), 0.0);
  EXPECT_EQ(MaxDifference(r.frames.back(), k.next, mask), 0.0);
  // As many rows as unknowns: the minimum is Δ_ST τ = 0 up to the solver's tolerance.
  EXPECT_GT(r.energy_linear, 0.0);
  EXPECT_LT(r.energy, 1e-6 * r.energy_linear);
}

TEST(SpaceTime, LinearModeReturnsExactBlends) {
  const KeyFrames k = MovingBox();
  SpaceTimeParams params;
  params.mode = InterpolationMode::kLinear;
  params.substeps = 4;
  const SpaceTimeResult r = InterpolateFrames(k.previous, k.next, {}, params);
  ASSERT_TRUE(r.status.ok());
  ASSERT_EQ(r.frames.size(), 5u);
  EXPECT_EQ(r.energy, r.energy_linear);
  for (int j = 0; j <= 4; ++j) {
    const double s = j / 4.0;
    for (std::size_t i = 0; i < k.next.tau11.size(); ++i) {
      ASSERT_NEAR(r.frames[j].tau11[i], (1 - s) * k.previous.tau11[i] + s * k.next.tau11[i], 1e-15);
      ASSERT_NEAR(r.frames[j].tau12[i], (1 - s) * k.previous.tau12[i] + s * k.next.tau12[i], 1e-15);
    }
  }
}

TEST(SpaceTime, CellsOutsideTheWindowKeepTheLinearBlend) {
  const KeyFrames k = MovingBox();
  MaskParams window;
  window.use_window = true;
  window.window_centre_m = {2.0, 1.8};
  window.window_radius_m = 1.0;
  const std::vector<std::uint8_t> mask = InterpolationMask(k.previous, k.next, window);
  SpaceTimeParams linear;
  linear.mode = InterpolationMode::kLinear;
  const SpaceTimeResult lin = InterpolateFrames(k.previous, k.next, mask, linear);
  const SpaceTimeResult st = InterpolateFrames(k.previous, k.next, mask, {});
  ASSERT_TRUE(st.status.ok());
  int inside = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    inside += mask[i];
    const double d = (k.next.geometry.Center(static_cast<int>(i)) - window.window_centre_m).norm();
    if (d > window.window_radius_m) {
      ASSERT_EQ(mask[i], 0);
      ASSERT_EQ(st.frames[5].tau11[i], lin.frames[5].tau11[i]);
      ASSERT_EQ(st.frames[5].tau12[i], lin.frames[5].tau12[i]);
    }
  }
  EXPECT_EQ(st.unknowns, inside * 11);
  EXPECT_GT(MaxDifference(st.frames[5], lin.frames[5], mask), 1e-3);  // the window did change
}

TEST(SpaceTime, RejectsMismatchedKeyFrames) {
  const KeyFrames k = MovingBox();
  TensorRaster other = k.next;
  other.geometry.origin_m.x() += 0.05;
  EXPECT_FALSE(InterpolateFrames(k.previous, other, {}, {}).status.ok());
  SpaceTimeParams none;
  none.substeps = 0;
  EXPECT_FALSE(InterpolateFrames(k.previous, k.next, {}, none).status.ok());
  const std::vector<std::uint8_t> short_mask(10, 1);
  EXPECT_FALSE(InterpolateFrames(k.previous, k.next, short_mask, {}).status.ok());
}

}  // namespace
}  // namespace voxplan::tensorfield
