// The detector model (sim/detector.h) on hand-made label images whose answers are known.
#include <gtest/gtest.h>

#include <set>

#include "sim/detector.h"

namespace voxplan {
namespace {

// 320 x 240, a wall (id 1, structure) behind two touching boxes: id 2 at x 40..119, id 3 at
// x 120..199 (rows 60..179), and a small object id 4 (10 x 10 = 100 pixels) far from both.
LabelImage Scene() {
  LabelImage labels(320, 240);
  for (int y = 0; y < 240; ++y)
    for (int x = 0; x < 320; ++x) {
      uint32_t id = 1;
      if (y >= 60 && y < 180 && x >= 40 && x < 120) id = 2;
      if (y >= 60 && y < 180 && x >= 120 && x < 200) id = 3;
      if (y >= 20 && y < 30 && x >= 280 && x < 290) id = 4;
      labels.at(x, y) = id;
    }
  return labels;
}

const std::vector<uint8_t> kStructure = {0, 1};  // id 1 is the wall

std::set<uint32_t> Ids(const LabelImage& labels) {
  return std::set<uint32_t>(labels.data.begin(), labels.data.end());
}

DetectorParams Only() {  // every effect off; tests turn one on
  DetectorParams p;
  p.dropout = 0.f;
  p.erosion_px = 0;
  p.merge_probability = 0.f;
  p.min_pixels = 0;
  return p;
}

TEST(Detector, WithoutNoiseTheLabelsAreTheRenderersAndTheStatsCountObjects) {
  LabelImage labels = Scene();
  DetectorParams p;
  p.noise = false;
  const DetectorStats stats = ApplyDetector(labels, kStructure, p, 1, 0);
  EXPECT_EQ(labels.data, Scene().data);
  EXPECT_EQ(stats.objects_in, 3u);  // the wall is no object
  EXPECT_EQ(stats.objects_out, 3u);
  LabelImage same = Scene();
  ApplyDetector(same, kStructure, Only(), 1, 0);
  EXPECT_EQ(same.data, Scene().data);  // noise on, every effect at zero
}

TEST(Detector, ErosionClearsABandOfItsWidthAlongEveryBoundary) {
  LabelImage labels = Scene();
  DetectorParams p = Only();
  p.erosion_px = 2;
  ApplyDetector(labels, kStructure, p, 1, 0);
  // Box 2 spans x 40..119: within 2 px of x 40 (the wall) and of x 119|120 (box 3) it is gone.
  EXPECT_EQ(labels.at(41, 100), 0u);
  EXPECT_EQ(labels.at(42, 100), 2u);
  EXPECT_EQ(labels.at(117, 100), 2u);
  EXPECT_EQ(labels.at(118, 100), 0u);
  EXPECT_EQ(labels.at(122, 100), 3u);
  EXPECT_EQ(labels.at(121, 100), 0u);
  // The wall erodes too, beside the boxes; far from them it stays.
  EXPECT_EQ(labels.at(38, 100), 0u);
  EXPECT_EQ(labels.at(10, 100), 1u);
}

TEST(Detector, ObjectsBelowTheMinimumSizeAreMissedAndTheMinimumScalesWithTheImage) {
  LabelImage labels = Scene();
  DetectorParams p = Only();
  p.min_pixels = 300;  // object 4 has 100 pixels
  const DetectorStats stats = ApplyDetector(labels, kStructure, p, 1, 0);
  EXPECT_EQ(Ids(labels), (std::set<uint32_t>{0, 1, 2, 3}));  // 0: its pixels, unlabelled
  EXPECT_EQ(stats.too_small, 1u);
  EXPECT_EQ(stats.objects_out, 2u);
  // At 160 x 120 the same 300 means 75 pixels: a 10 x 10 object passes.
  LabelImage small(160, 120);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) small.at(x, y) = 4;
  ApplyDetector(small, kStructure, p, 1, 0);
  EXPECT_EQ(small.at(5, 5), 4u);
}

TEST(Detector, DropoutAndMergesHappenAtTheirRatesAndNeverTouchStructure) {
  DetectorParams p = Only();
  p.dropout = 0.1f;
  p.merge_probability = 0.05f;
  int dropped2 = 0, merged = 0, wall_lost = 0;
  constexpr int kFrames = 2000;
  for (int f = 0; f < kFrames; ++f) {
    LabelImage labels = Scene();
    const DetectorStats stats = ApplyDetector(labels, kStructure, p, 7, uint64_t(f));
    const std::set<uint32_t> ids = Ids(labels);
    merged += int(stats.merged);
    if (stats.merged) {
      // Box 3 takes box 2's id (they are the same size: the lower id wins) or both are gone.
      EXPECT_FALSE(ids.count(3));
    } else {
      dropped2 += !ids.count(2);
    }
    wall_lost += !ids.count(1);
  }
  EXPECT_EQ(wall_lost, 0);
  // Binomial: 2000 x 0.05 = 100 +- 10; dropout over ~1900 unmerged frames: 190 +- 13. 4 sigma.
  EXPECT_NEAR(merged, 100, 40);
  EXPECT_NEAR(dropped2, 0.1 * (kFrames - merged), 55);
}

TEST(Detector, TheSameFrameGivesTheSameLabelsAndAnotherFrameItsOwn) {
  DetectorParams p;  // the defaults: every effect on
  LabelImage a = Scene(), b = Scene();
  ApplyDetector(a, kStructure, p, 3, 42);
  ApplyDetector(b, kStructure, p, 3, 42);
  EXPECT_EQ(a.data, b.data);
  bool differs = false;
  for (uint64_t f = 0; f < 64 && !differs; ++f) {
    LabelImage c = Scene();
    ApplyDetector(c, kStructure, p, 3, f);
    differs = c.data != a.data;
  }
  EXPECT_TRUE(differs);
}

TEST(Detector, ParametersOutOfBoundsAreRefused) {
  DetectorParams p;
  EXPECT_TRUE(p.Validate().ok());
  p.dropout = 1.5f;
  EXPECT_FALSE(p.Validate().ok());
  p = {};
  p.erosion_px = -1;
  EXPECT_FALSE(p.Validate().ok());
  p = {};
  p.min_pixels = 1 << 20;
  EXPECT_FALSE(p.Validate().ok());
  EXPECT_TRUE(IsStructureClass("wall"));
  EXPECT_FALSE(IsStructureClass("chair"));
}

}  // namespace
}  // namespace voxplan
