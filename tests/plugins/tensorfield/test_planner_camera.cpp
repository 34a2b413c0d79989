// The tensorfield planner's camera step (plugins/tensorfield/planner_camera.cpp) over plain data:
// a 1 m corridor that opens into unknown space. X12: the path ahead running into the unknown gets
// look-at views at the samples within 2 m, a path that stays in known space none. X5: the camera
// trajectory sent starts where the camera is and keeps the camera's speed limits; at a turn in
// place it starts where the turn leaves the camera, and holds there while the base turns.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/tensorfield/planner.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAngleTolRad = 1e-4;
constexpr double kSpeedTol = 1e-3;

double Wrap(double a) { return std::remainder(a, 2.0 * kPi); }

// 8 m × 4 m at 5 cm: a corridor x in [0.5, 4.5), y in [1.5, 2.5) between walls, closed on the
// left, open on the right into unknown space (its last free column frontier).
FloorInput Corridor() {
  FloorInput f;
  f.geometry.width = 160;
  f.geometry.height = 80;
  f.geometry.resolution_m = 0.05;
  const omt::RasterGeometry& g = f.geometry;
  f.cells.assign(static_cast<std::size_t>(g.NumCells()), kFloorUnknown);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const Eigen::Vector2d c = g.Center(x, y);
      const bool inside = c.x() >= 0.5 && c.x() < 4.5 && c.y() >= 1.5 && c.y() < 2.5;
      const bool wall = c.x() < 4.5 && c.x() >= 0.3 && c.y() >= 1.3 && c.y() < 2.7 && !inside;
      std::uint8_t& code = f.cells[static_cast<std::size_t>(g.Index(x, y))];
      if (inside) code = c.x() >= 4.45 ? kFloorFrontier : kFloorFree;
      if (wall) code = kFloorObstacle;
    }
  // The host's clearance: to the nearest obstacle cell centre (an exact distance transform; a
  // brute-force loop over the obstacles took 15 s instrumented).
  omt::OccupancyRaster occupancy;
  occupancy.geometry = g;
  occupancy.cells.resize(f.cells.size(), omt::Cell::kFree);
  for (std::size_t i = 0; i < f.cells.size(); ++i)
    if (f.cells[i] == kFloorObstacle) occupancy.cells[i] = omt::Cell::kOccupied;
  f.clearance_m = omt::ComputeClearance(occupancy, false).clearance_m;
  return f;
}

RobotInput Robot(double x, double heading_rad, double camera_yaw_rad) {
  RobotInput r;
  r.position_m = {x, 2.0};
  r.heading_rad = heading_rad;
  r.radius_m = 0.2;
  r.fov_rad = 58.0 * kPi / 180.0;
  r.min_range_m = 0.5;
  r.max_range_m = 4.0;
  r.max_speed_mps = 0.3;
  r.camera_yaw_rad = camera_yaw_rad;
  r.camera_limits.angular_radps = 0.6981317f;
  return r;
}

StepOutput StepOnce(const PlannerOptions& o, const RobotInput& robot) {
  static const FloorInput floor = Corridor();
  RobotPlanner planner(o);
  return planner.Step(floor, robot, 0.0, RouteServices{});
}

TEST(PlannerCamera, LooksIntoTheUnknownThePathRunsInto) {
  const PlannerOptions o;
  // 1.3 m from the open end, facing it: the path runs to the frontier, the body into the unknown.
  const StepOutput near = StepOnce(o, Robot(3.2, 0.0, 0.0));
  ASSERT_GE(near.path.size(), 2u);
  EXPECT_GT(near.diag.lookat_samples, 0);
  EXPECT_GT(near.diag.lookat_m, 1.0);
  EXPECT_LT(near.diag.lookat_m, 2.0);
  // Off: no look-at.
  PlannerOptions off = o;
  off.lookat = false;
  EXPECT_EQ(StepOnce(off, Robot(3.2, 0.0, 0.0)).diag.lookat_samples, 0);
  // 3.2 m from it: the 2 m path ahead stays in known space, nothing to look into.
  const StepOutput far = StepOnce(o, Robot(1.3, 0.0, 0.0));
  ASSERT_GE(far.path.size(), 2u);
  EXPECT_EQ(far.diag.lookat_samples, 0);
  EXPECT_LT(far.diag.lookat_m, 0.0);
}

// The camera trajectory sent: its angular step speeds against the limit.
double MaxRadps(const std::vector<CameraOut>& c) {
  double m = 0.0;
  for (std::size_t k = 1; k < c.size(); ++k) {
    const double dt = c[k].t_s - c[k - 1].t_s;
    if (dt <= 0.0) continue;
    m = std::max(m, std::hypot(Wrap(double{c[k].yaw_rad} - c[k - 1].yaw_rad),
                               double{c[k].pitch_rad} - c[k - 1].pitch_rad) /
                        dt);
  }
  return m;
}

TEST(PlannerCamera, TheTrajectoryStartsWhereTheCameraIs) {
  const PlannerOptions o;
  const RobotInput robot = Robot(1.5, 0.0, 2.0);  // driving along +x, the camera looking back left
  const StepOutput s = StepOnce(o, robot);
  ASSERT_GE(s.camera.size(), 2u);
  EXPECT_TRUE(s.diag.camera_stop);  // the first path of a run
  EXPECT_EQ(s.diag.camera_stops, 1);
  EXPECT_NEAR(Wrap(s.camera.front().yaw_rad - 2.0), 0.0, kAngleTolRad);
  EXPECT_GT(s.diag.camera_jump_deg, 10.0);
  EXPECT_GT(s.diag.camera_radps_before, robot.camera_limits.angular_radps);
  EXPECT_LE(s.diag.camera_radps_after, robot.camera_limits.angular_radps * (1.0 + kSpeedTol));
  EXPECT_LE(MaxRadps(s.camera), robot.camera_limits.angular_radps * (1.0 + kSpeedTol));
  EXPECT_GT(s.diag.camera_connect_s, 0.0);
  // Without the connection the trajectory starts at the optimised first view: the jump.
  PlannerOptions off = o;
  off.connect = CameraConnect::kOff;
  const StepOutput j = StepOnce(off, robot);
  ASSERT_GE(j.camera.size(), 2u);
  EXPECT_NEAR(std::abs(Wrap(j.camera.front().yaw_rad - 2.0)) * 180.0 / kPi, s.diag.camera_jump_deg,
              1e-3);
  EXPECT_EQ(j.diag.camera_radps_after, j.diag.camera_radps_before);
  EXPECT_EQ(j.diag.camera_connect_s, 0.0);
  // With eq. 8 starting from the camera ("selection"), the optimised trajectory itself starts
  // there: no jump left.
  PlannerOptions in_selection = o;
  in_selection.connect = CameraConnect::kInSelection;
  const StepOutput q = StepOnce(in_selection, robot);
  ASSERT_GE(q.camera.size(), 2u);
  EXPECT_NEAR(Wrap(q.camera.front().yaw_rad - 2.0), 0.0, kAngleTolRad);
  EXPECT_LT(q.diag.camera_jump_deg, 1e-3);
  EXPECT_LE(MaxRadps(q.camera), robot.camera_limits.angular_radps * (1.0 + kSpeedTol));
  // Connected or not, the same optimised trajectory beyond the connecting stretch.
  const CameraOut& a = s.camera.back();
  const CameraOut& b = j.camera.back();
  if (a.t_s > s.diag.camera_connect_s) {
    EXPECT_NEAR(Wrap(double{a.yaw_rad} - b.yaw_rad), 0.0, kAngleTolRad);
  }
}

TEST(PlannerCamera, AtATurnInPlaceTheCameraGoesRoundWithTheBase) {
  // Facing the closed end 0.28 m from its wall: the pathline there is too short, so the robot
  // turns round (a stop) and the path's first piece is behind it.
  const PlannerOptions o;
  const RobotInput robot = Robot(0.78, kPi, kPi + 0.3);
  const StepOutput s = StepOnce(o, robot);
  ASSERT_GE(s.path.size(), 2u);
  ASSERT_GE(s.camera.size(), 2u);
  const Eigen::Vector2d d = s.path[1] - s.path[0];
  const double first_turn = Wrap(std::atan2(d.y(), d.x()) - robot.heading_rad);
  ASSERT_GT(std::abs(first_turn), 0.5 * kPi) << "the scene no longer turns the robot round";
  EXPECT_TRUE(s.diag.camera_stop);
  // The host turns the base in place until the piece is within a right angle, the camera with it.
  const double drag = first_turn - std::copysign(0.5 * kPi, first_turn);
  EXPECT_NEAR(Wrap(s.camera.front().yaw_rad - (robot.camera_yaw_rad + drag)), 0.0, kAngleTolRad);
  const double hold = std::abs(drag) / robot.turn_rate_radps;
  for (const CameraOut& c : s.camera) {
    if (c.t_s > hold) break;
    EXPECT_NEAR(Wrap(c.yaw_rad - s.camera.front().yaw_rad), 0.0, kAngleTolRad) << "t " << c.t_s;
  }
  EXPECT_LE(MaxRadps(s.camera), robot.camera_limits.angular_radps * (1.0 + kSpeedTol));
}

}  // namespace
}  // namespace voxplan::tensorfield
