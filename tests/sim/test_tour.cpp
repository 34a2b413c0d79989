// Tours on a hand-made three-room floor plan: every room visited, collision-free frames with
// bounded steps, a full spin at each viewpoint, determinism, and refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim/tour.h"

namespace voxplan {
namespace {

constexpr float kStepTolerance = 1e-3f;  // metres and degrees over the configured steps

// 9 m x 6 m, 5 cm cells. Rooms A = [0,4]x[0,3], B = [4,9]x[0,3], C = [0,9]x[3,6]; 10 cm walls
// around and between them; a door A-B at y in [1, 2], a door B-C at x in [6, 7]. A table
// (obstacle) in C at [1.5, 2.5] x [4, 5]. With `closed_room`, a fourth room D = [9, 12]x[0, 6]
// is added beyond a wall with no door.
struct Layout {
  FloorPlan plan;
  std::vector<Room> rooms;
};

Layout ThreeRooms(bool closed_room = false) {
  Layout l;
  const float res = 0.05f;
  const float width_m = closed_room ? 12.f : 9.f;
  l.plan.resolution_m = res;
  l.plan.width = int(std::lround(width_m / res));
  l.plan.height = int(std::lround(6.f / res));
  l.plan.cells.assign(size_t(l.plan.width) * l.plan.height, PlanCell::kFree);
  for (int y = 0; y < l.plan.height; ++y)
    for (int x = 0; x < l.plan.width; ++x) {
      const Eigen::Vector2f c = l.plan.CellCenter(x, y);
      auto near = [](float v, float at) { return std::abs(v - at) < 0.05f; };
      bool wall = c.x() < 0.1f || c.y() < 0.1f || c.x() > width_m - 0.1f || c.y() > 5.9f;
      wall |= near(c.x(), 4.f) && c.y() < 3.f && !(c.y() > 1.f && c.y() < 2.f);
      wall |= near(c.y(), 3.f) && c.x() < 9.f && !(c.x() > 6.f && c.x() < 7.f);
      wall |= closed_room && near(c.x(), 9.f);
      const bool table = c.x() > 1.5f && c.x() < 2.5f && c.y() > 4.f && c.y() < 5.f;
      if (wall || table) l.plan.cells[size_t(y) * l.plan.width + x] = PlanCell::kObstacle;
    }
  l.rooms = {{"a", Eigen::AlignedBox2f(Eigen::Vector2f(0, 0), Eigen::Vector2f(4, 3))},
             {"b", Eigen::AlignedBox2f(Eigen::Vector2f(4, 0), Eigen::Vector2f(9, 3))},
             {"c", Eigen::AlignedBox2f(Eigen::Vector2f(0, 3), Eigen::Vector2f(9, 6))}};
  if (closed_room)
    l.rooms.push_back({"d", Eigen::AlignedBox2f(Eigen::Vector2f(9, 0), Eigen::Vector2f(12, 6))});
  return l;
}

float HeadingDeg(const Pose3f& T_W_C) {
  const Eigen::Vector3f z = T_W_C.linear().col(2);
  return std::atan2(z.y(), z.x()) * 180.f / std::numbers::pi_v<float>;
}

// Elevation of the optical axis above the horizontal: the camera's pitch.
float ElevationDeg(const Pose3f& T_W_C) {
  return std::asin(std::clamp(T_W_C.linear()(2, 2), -1.f, 1.f)) * 180.f / std::numbers::pi_v<float>;
}

// Widest gap between the camera headings of `frames`, around the circle (360 when empty).
// The tour's frames at viewpoint v (within 0.1 mm) whose elevation is pitch_deg.
std::vector<Pose3f> FramesAt(const Tour& tour, const Eigen::Vector2f& v, float pitch_deg) {
  std::vector<Pose3f> frames;
  for (const Pose3f& T : tour.T_W_C)
    if ((T.translation().head<2>() - v).norm() < 1e-4f &&
        std::abs(ElevationDeg(T) - pitch_deg) < kStepTolerance)
      frames.push_back(T);
  return frames;
}

float WidestHeadingGapDeg(const std::vector<Pose3f>& frames) {
  std::vector<float> headings;
  for (const Pose3f& T : frames) headings.push_back(HeadingDeg(T));
  if (headings.empty()) return 360.f;
  std::sort(headings.begin(), headings.end());
  float gap = 360.f - (headings.back() - headings.front());
  for (size_t k = 1; k < headings.size(); ++k) gap = std::max(gap, headings[k] - headings[k - 1]);
  return gap;
}

float AngleDeg(const Pose3f& a, const Pose3f& b) {
  return Eigen::AngleAxisf(a.linear().transpose() * b.linear()).angle() * 180.f /
         std::numbers::pi_v<float>;
}

void ExpectValidFrames(const Tour& tour, const FloorPlan& plan, const TourParams& params) {
  ASSERT_EQ(tour.timestamps_s.size(), tour.T_W_C.size());
  ASSERT_GT(tour.T_W_C.size(), 10u);
  for (size_t i = 0; i < tour.T_W_C.size(); ++i) {
    const Pose3f& T = tour.T_W_C[i];
    EXPECT_NEAR(T.translation().z(), params.robot.camera_height_m, 1e-5f);
    EXPECT_TRUE(FootprintFree(plan, T.translation().head<2>(), params.robot.radius_m)) << i;
    if (i == 0) continue;
    EXPECT_GT(tour.timestamps_s[i], tour.timestamps_s[i - 1]) << i;
    const Pose3f& P = tour.T_W_C[i - 1];
    EXPECT_LE((T.translation() - P.translation()).norm(), params.frame_step_m + kStepTolerance)
        << i;
    EXPECT_LE(AngleDeg(P, T), params.frame_step_deg + kStepTolerance) << i;
  }
  EXPECT_NEAR(tour.duration_s, tour.timestamps_s.back(), 1.0);  // last spin's dwell after it
}

TEST(Tour, VisitsEveryRoomWithCollisionFreeFrames) {
  const Layout l = ThreeRooms();
  TourParams params;
  auto tour = PlanTour(l.plan, l.rooms, params);
  ASSERT_TRUE(tour.ok()) << tour.status().message();
  ExpectValidFrames(*tour, l.plan, params);
  EXPECT_TRUE(tour->unreachable_rooms.empty());
  EXPECT_GE(tour->coverage, params.min_coverage);
  for (size_t r = 0; r < l.rooms.size(); ++r) {
    const auto it = std::find(tour->viewpoint_room.begin(), tour->viewpoint_room.end(), int(r));
    ASSERT_NE(it, tour->viewpoint_room.end()) << l.rooms[r].name;
    const Eigen::Vector2f p = tour->viewpoints_W[size_t(it - tour->viewpoint_room.begin())];
    EXPECT_TRUE(l.rooms[r].footprint_W.contains(p)) << l.rooms[r].name << " " << p.transpose();
  }
  // A full turn at each viewpoint and spin pitch: camera headings there leave no gap wider
  // than one step.
  for (const Eigen::Vector2f& v : tour->viewpoints_W)
    for (const float pitch_deg : params.spin_pitches_deg) {
      const std::vector<Pose3f> frames = FramesAt(*tour, v, pitch_deg);
      ASSERT_GE(frames.size(), size_t(360.f / params.frame_step_deg)) << pitch_deg;
      EXPECT_LE(WidestHeadingGapDeg(frames), params.frame_step_deg + kStepTolerance)
          << v.transpose() << " at pitch " << pitch_deg;
    }
  // The path is no detour: well under the 2-opt-free worst case, over the door-to-door minimum.
  EXPECT_GT(tour->length_m, 5.0);
  EXPECT_LT(tour->length_m, 40.0);
}

TEST(Tour, SpinsAtEachPitchAndDrivesAtTheDrivingPitch) {
  const Layout l = ThreeRooms();
  TourParams params;
  params.frame_step_deg = 15.f;
  params.camera_pitch_deg = -10.f;
  params.spin_pitches_deg = {20.f, -35.f};
  auto tour = PlanTour(l.plan, l.rooms, params);
  ASSERT_TRUE(tour.ok()) << tour.status().message();
  ExpectValidFrames(*tour, l.plan, params);
  auto at_viewpoint = [&](const Pose3f& T) {
    return std::any_of(
        tour->viewpoints_W.begin(), tour->viewpoints_W.end(),
        [&](const Eigen::Vector2f& v) { return (T.translation().head<2>() - v).norm() < 1e-4f; });
  };
  for (const Eigen::Vector2f& v : tour->viewpoints_W) {
    // No level spin was asked for: no full turn at pitch 0.
    EXPECT_GT(WidestHeadingGapDeg(FramesAt(*tour, v, 0.f)), 90.f) << v.transpose();
    for (const float pitch_deg : params.spin_pitches_deg) {
      const std::vector<Pose3f> frames = FramesAt(*tour, v, pitch_deg);
      EXPECT_LE(WidestHeadingGapDeg(frames), params.frame_step_deg + kStepTolerance)
          << v.transpose() << " at pitch " << pitch_deg;
    }
  }
  // Between viewpoints the camera keeps the driving pitch.
  size_t driving = 0;
  for (const Pose3f& T : tour->T_W_C) {
    if (at_viewpoint(T)) continue;
    ++driving;
    EXPECT_NEAR(ElevationDeg(T), params.camera_pitch_deg, kStepTolerance);
  }
  EXPECT_GT(driving, 10u);

  params.spin_pitches_deg = {};
  EXPECT_FALSE(PlanTour(l.plan, l.rooms, params).ok());
  params.spin_pitches_deg = {0.f, params.robot.max_abs_pitch_deg + 1.f};
  EXPECT_FALSE(PlanTour(l.plan, l.rooms, params).ok());
}

TEST(Tour, CoverAloneReachesEveryRoomAndIsDeterministic) {
  const Layout l = ThreeRooms();
  TourParams params;
  params.start_W = Eigen::Vector2f(1.f, 1.f);
  auto a = PlanTour(l.plan, {}, params);
  auto b = PlanTour(l.plan, {}, params);
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok());
  ExpectValidFrames(*a, l.plan, params);
  EXPECT_TRUE(a->T_W_C.front().translation().head<2>().isApprox(Eigen::Vector2f(1.f, 1.f)));
  ASSERT_EQ(a->T_W_C.size(), b->T_W_C.size());
  for (size_t i = 0; i < a->T_W_C.size(); ++i)
    ASSERT_TRUE(a->T_W_C[i].matrix() == b->T_W_C[i].matrix()) << i;
  EXPECT_EQ(a->timestamps_s, b->timestamps_s);
  for (const Room& room : l.rooms) {
    const bool visited =
        std::any_of(a->viewpoints_W.begin(), a->viewpoints_W.end(),
                    [&](const Eigen::Vector2f& p) { return room.footprint_W.contains(p); });
    EXPECT_TRUE(visited) << room.name;
  }
}

TEST(Tour, ReportsClosedRoomsAndRefusesBadStarts) {
  const Layout l = ThreeRooms(/*closed_room=*/true);
  TourParams params;
  params.start_W = Eigen::Vector2f(1.f, 1.f);
  auto tour = PlanTour(l.plan, l.rooms, params);
  ASSERT_TRUE(tour.ok()) << tour.status().message();
  EXPECT_EQ(tour->unreachable_rooms, std::vector<int>{3});
  for (const Eigen::Vector2f& p : tour->viewpoints_W) EXPECT_LT(p.x(), 9.f);

  params.start_W = Eigen::Vector2f(2.f, 4.5f);  // on the table
  EXPECT_FALSE(PlanTour(l.plan, l.rooms, params).ok());
  params.start_W.reset();
  params.robot.radius_m = 5.f;  // fits nowhere
  EXPECT_FALSE(PlanTour(l.plan, l.rooms, params).ok());
  EXPECT_FALSE(PlanTour(FloorPlan{}, l.rooms, TourParams{}).ok());
}

}  // namespace
}  // namespace voxplan
