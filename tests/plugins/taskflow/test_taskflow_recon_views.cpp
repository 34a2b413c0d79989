#include <gtest/gtest.h>

#include <cmath>

#include "plugins/taskflow/algorithms/completion.h"
#include "plugins/taskflow/algorithms/recon_views.h"
#include "tests/plugins/taskflow/taskflow_scenes.h"

namespace voxplan::taskflow {
namespace {

using testing::MapQuery;
using testing::Region;
using testing::Surface;
using testing::UnitBox;

constexpr float kRobotClearance = 0.35f;  // base centre to the box, a robot radius and margin
constexpr float kRoomHalf = 3.0f;         // the room around the box
constexpr float kTol = 1e-4f;
constexpr int kObjectId = 5;

// The unit box seen from the front (y <= 0) only, completed.
CompletionResult FrontSeenBox() {
  const Region front = [](const Eigen::Vector3f& p) { return p.y() <= 0.0f; };
  const Surface s = UnitBox().Sample(0.02f, front);
  return CompleteObject(s.points, s.normals, 0.0f, MapQuery(UnitBox(), front), CompletionParams{},
                        7);
}

bool InRoomAndClear(const Eigen::Vector2f& b) {
  const float limit = 0.5f + kRobotClearance;
  const bool clear = std::abs(b.x()) > limit || std::abs(b.y()) > limit;
  return clear && std::abs(b.x()) < kRoomHalf && std::abs(b.y()) < kRoomHalf;
}

void AllVisible(const Eigen::Vector3f&, std::span<const Eigen::Vector3f>,
                std::span<std::uint8_t> visible) {
  std::fill(visible.begin(), visible.end(), std::uint8_t{1});
}

// Every view satisfies the arm workspace and the base pose realises it.
void ExpectReachable(const ReconView& v, const ReconViewParams& p, const TraversableFn& ok) {
  EXPECT_EQ(v.object_id, kObjectId);
  EXPECT_GE(v.camera_height_m, p.arm.camera_height_min_m - kTol);
  EXPECT_LE(v.camera_height_m, p.arm.camera_height_max_m + kTol);
  const float reach = std::hypot(v.camera_forward_m, v.camera_left_m);
  EXPECT_GE(reach, p.arm.reach_min_m - kTol);
  EXPECT_LE(reach, p.arm.reach_max_m + kTol);
  EXPECT_LE(std::abs(std::atan2(v.camera_left_m, v.camera_forward_m)),
            p.arm.reach_half_angle_rad + kTol);
  EXPECT_GE(v.pitch_rad, p.arm.min_pitch_rad - kTol);
  EXPECT_LE(v.pitch_rad, p.arm.max_pitch_rad + kTol);
  EXPECT_TRUE(ok(v.base_xy_m));
  // The base pose and the offset put the camera where the view says.
  const float c = std::cos(v.base_yaw_rad), s = std::sin(v.base_yaw_rad);
  const Eigen::Vector2f cam =
      v.base_xy_m + Eigen::Vector2f(c * v.camera_forward_m - s * v.camera_left_m,
                                    s * v.camera_forward_m + c * v.camera_left_m);
  EXPECT_LT((cam - v.camera_m.head<2>()).norm(), 1e-3f);
  // Yaw and pitch look at the target.
  const Eigen::Vector3f look(std::cos(v.pitch_rad) * std::cos(v.yaw_rad),
                             std::cos(v.pitch_rad) * std::sin(v.yaw_rad), std::sin(v.pitch_rad));
  EXPECT_GT(look.dot((v.target_m - v.camera_m).normalized()), 0.999f);
  EXPECT_GT(v.coverage, 0.0f);
  EXPECT_GT(v.covered_points, 0);
}

TEST(TaskflowReconViews, FrontSeenBoxIsViewedFromBehindWithinTheArmWorkspace) {
  const CompletionResult c = FrontSeenBox();
  ASSERT_TRUE(c.incomplete);
  const ReconViewParams params;
  const TraversableFn ok = InRoomAndClear;
  const std::vector<ReconView> views =
      SelectReconViews(TargetFromCompletion(kObjectId, 0.0f, c), params, ok, AllVisible);
  ASSERT_FALSE(views.empty());
  EXPECT_LE(static_cast<int>(views.size()), params.max_views_per_object);
  const ReconView& best = views.front();
  EXPECT_GT(best.camera_m.y(), 0.5f);                    // behind the box
  EXPECT_LT((best.target_m - best.camera_m).y(), 0.0f);  // looking back at it
  EXPECT_GT(best.target_m.y(), 0.0f);                    // at its hidden half
  for (const ReconView& v : views) ExpectReachable(v, params, ok);
}

TEST(TaskflowReconViews, UntraversableRegionIsAvoided) {
  const CompletionResult c = FrontSeenBox();
  const ReconViewParams params;
  // Nothing may stand on the right (x > 0) or straight behind the box.
  const TraversableFn ok = [](const Eigen::Vector2f& b) {
    return InRoomAndClear(b) && b.x() <= 0.0f && !(b.y() > 0.5f && std::abs(b.x()) < 0.5f);
  };
  const std::vector<ReconView> views =
      SelectReconViews(TargetFromCompletion(kObjectId, 0.0f, c), params, ok, AllVisible);
  ASSERT_FALSE(views.empty());
  for (const ReconView& v : views) {
    ExpectReachable(v, params, ok);
    EXPECT_LE(v.base_xy_m.x(), 0.0f);
  }
  EXPECT_GT(views.front().camera_m.y(), 0.0f);  // still on the hidden side
}

TEST(TaskflowReconViews, NothingVisibleGivesNoViews) {
  const CompletionResult c = FrontSeenBox();
  const auto none = [](const Eigen::Vector3f&, std::span<const Eigen::Vector3f>,
                       std::span<std::uint8_t> visible) {
    std::fill(visible.begin(), visible.end(), std::uint8_t{0});
  };
  EXPECT_TRUE(SelectReconViews(TargetFromCompletion(kObjectId, 0.0f, c), ReconViewParams{},
                               InRoomAndClear, none)
                  .empty());
}

TEST(TaskflowReconViews, ViewsAreDeterministic) {
  const CompletionResult c = FrontSeenBox();
  const ReconTarget t = TargetFromCompletion(kObjectId, 0.0f, c);
  const std::vector<ReconView> a =
      SelectReconViews(t, ReconViewParams{}, InRoomAndClear, AllVisible);
  const std::vector<ReconView> b =
      SelectReconViews(t, ReconViewParams{}, InRoomAndClear, AllVisible);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].camera_m, b[i].camera_m);
    EXPECT_EQ(a[i].base_xy_m, b[i].base_xy_m);
    EXPECT_EQ(a[i].coverage, b[i].coverage);
  }
}

TEST(TaskflowReconViews, NeighbourhoodClosesAfterThreeNoGainRounds) {
  const HistoryParams hp;
  ReconHistory h;
  const Eigen::Vector3f a(1.0f, 1.0f, 1.0f);
  const auto view_at = [](const Eigen::Vector3f& p) {
    ReconView v;
    v.camera_m = p;
    return std::vector<ReconView>{v};
  };
  // Two rounds without gain: still open.
  for (int round = 0; round < 2; ++round) {
    ObserveCompleteness(&h, kObjectId, 100.0, hp);
    RecordViews(&h, kObjectId, view_at(a + Eigen::Vector3f(0.1f * round, 0, 0)), 100.0);
  }
  ObserveCompleteness(&h, kObjectId, 100.0, hp);
  ASSERT_NE(FindHistory(h, kObjectId), nullptr);
  EXPECT_FALSE(NeighbourhoodExhausted(*FindHistory(h, kObjectId), a, hp));
  // The third no-gain round nearby closes it; a place a metre away stays open.
  RecordViews(&h, kObjectId, view_at(a - Eigen::Vector3f(0, 0.2f, 0)), 100.0);
  ObserveCompleteness(&h, kObjectId, 100.0, hp);
  EXPECT_TRUE(NeighbourhoodExhausted(*FindHistory(h, kObjectId), a, hp));
  EXPECT_FALSE(
      NeighbourhoodExhausted(*FindHistory(h, kObjectId), a + Eigen::Vector3f(1, 0, 0), hp));
  // A gain nearby reopens it: the strikes count from the latest round back.
  RecordViews(&h, kObjectId, view_at(a), 100.0);
  ObserveCompleteness(&h, kObjectId, 150.0, hp);
  EXPECT_FALSE(NeighbourhoodExhausted(*FindHistory(h, kObjectId), a, hp));
  EXPECT_EQ(FindHistory(h, 99), nullptr);
}

TEST(TaskflowReconViews, HistoryStopsRepeatedViewsAndMovesElsewhere) {
  const CompletionResult c = FrontSeenBox();
  const ReconTarget t = TargetFromCompletion(kObjectId, 0.0f, c);
  const ReconViewParams params;
  const HistoryParams hp;
  ReconHistory h;
  std::vector<ReconView> first;
  // Three rounds in which the scans add nothing: the same views each time.
  for (int round = 0; round < 3; ++round) {
    ObserveCompleteness(&h, kObjectId, 1000.0, hp);
    const std::vector<ReconView> views =
        SelectReconViews(t, params, InRoomAndClear, AllVisible, FindHistory(h, kObjectId), hp);
    ASSERT_FALSE(views.empty());
    if (round == 0) first = views;
    EXPECT_EQ(views.front().camera_m, first.front().camera_m);
    RecordViews(&h, kObjectId, views, 1000.0);
  }
  ObserveCompleteness(&h, kObjectId, 1000.0, hp);
  const std::vector<ReconView> fourth =
      SelectReconViews(t, params, InRoomAndClear, AllVisible, FindHistory(h, kObjectId), hp);
  ASSERT_FALSE(fourth.empty());  // elsewhere is still allowed
  for (const ReconView& v : fourth) {
    for (const ScanRecord& s : FindHistory(h, kObjectId)->scans)
      EXPECT_GT((v.camera_m - s.camera_m).norm(), hp.neighbourhood_m);
  }
}

}  // namespace
}  // namespace voxplan::taskflow
