// The tensorfield planner plugin (Xu 2017) through the host, on grid worlds: options refused by
// key and range, the first call's continuous path in free space with a call asked one sub-step
// later, a corridor followed along its direction over a short simulated loop, termination only
// once no frontier is left, the fixed camera looking along the path, determinism; topology
// control's counters.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "plugins/host/plugin_host.h"
#include "tests/plugins/fake_world.h"

namespace voxplan {
namespace {

constexpr float kRadius = 0.2f;

std::unique_ptr<LoadedPlanner> Load(const std::string& config = "{}") {
  PlannerLoadOptions o;
  o.config_json = config;
  o.seed = 1;
  auto planner = LoadPlanner("tensorfield", o);
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

PlanResult MustPlan(LoadedPlanner& planner, const PlannerWorld& world, const PlanRequest& r) {
  auto result = planner.Plan(world, r);
  EXPECT_TRUE(result.ok()) << result.status().message();
  if (!result.ok()) return {};
  for (const Rejection& j : result->rejections)
    ADD_FAILURE() << "robot " << j.robot << " task " << j.task << ": " << j.reason;
  return std::move(result).value();
}

PlanRequest At(double t_s, PlanEvent event = PlanEvent::kWakeup) {
  PlanRequest r;
  r.event = event;
  r.sim_time_s = t_s;
  r.call_index = uint32_t(t_s * 10);
  return r;
}

// Free (or frontier) with the robot's clearance: where the host lets a robot stand.
bool Traversable(const test::RasterWorld& world, const Eigen::Vector2f& p, float radius) {
  const PlannerFloor& f = world.Floor();
  const Eigen::Vector2i c = f.CellOf(p);
  if (!f.Contains(c.x(), c.y())) return false;
  const FloorCell cell = f.cells[f.Linear(c.x(), c.y())];
  return (cell == FloorCell::kFree || cell == FloorCell::kFrontier) &&
         f.clearance_m[f.Linear(c.x(), c.y())] >= radius - 1e-4f;
}

double Diagnostic(const PlanResult& r, const std::string& name) {
  for (const auto& [key, value] : r.diagnostics)
    if (key == name) return value;
  return std::nan("");
}

double Length(const std::vector<PathPoint>& path) {
  double s = 0.0;
  for (size_t i = 1; i < path.size(); ++i)
    s += (path[i].position_m - path[i - 1].position_m).norm();
  return s;
}

// A known 12 m x 2.6 m corridor (walls 2 cells thick, 1.2 m free between them around y = 1.3),
// unknown from x = 7 m on, one robot at (2, 1.3) heading 0.4 rad off the corridor's axis.
test::RasterWorld Corridor() {
  test::RasterWorld world(240, 52, 0.05f);
  world.Fill(0, 0, 239, 51, FloorCell::kObstacle);
  world.Fill(2, 14, 237, 37, FloorCell::kFree);  // y 0.7 .. 1.9
  world.Fill(140, 0, 239, 51, FloorCell::kUnknown);
  world.Finish();
  PlannerRobot& r = world.AddRobot(40, 26, kRadius);
  r.theta_rad = 0.4f;
  return world;
}

TEST(Tensorfield, LoadsWithDefaultsAndRefusesUnknownKeysAndBadValues) {
  ASSERT_TRUE(Load());
  ASSERT_TRUE(Load(R"({"interp": "linear", "topology_routing": false, "camera": "fixed",
                       "substeps_per_keyframe": 10, "substep_s": 0.2})"));
  for (const char* bad :
       {R"({"substeps": 5})", R"({"substep_s": 0})", R"({"speed_mps": 5})",
        R"({"interp": "cubic"})", R"({"camera": "free"})", R"({"frames_k": 1})",
        R"({"substeps_per_keyframe": 11})", R"({"gain_threshold": -1})",
        R"({"topology_routing": "yes"})", R"({"field": "vector_radial"})",
        R"({"method": "gradient"})", R"({"surface_depth_m": -0.1})", R"({"surface_depth_m": 11})",
        R"({"band_m": 0})", R"({"pitch": "down"})"}) {
    PlannerLoadOptions o;
    o.config_json = bad;
    EXPECT_FALSE(LoadPlanner("tensorfield", o).ok()) << bad;
  }
  for (const char* good : {R"({"field": "vector_normal"})", R"({"field": "vector_tangent"})",
                           R"({"method": "potential"})", R"({"method": "harmonic"})",
                           R"({"surface_depth_m": 0.5, "band_m": 1.2})", R"({"pitch": "aim"})"})
    EXPECT_TRUE(Load(good)) << good;
  // A vector field belongs to the tensor method's pipeline; the potential methods have none.
  PlannerLoadOptions o;
  o.config_json = R"({"field": "vector_tangent", "method": "potential"})";
  auto refused = LoadPlanner("tensorfield", o);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("needs method"), std::string::npos)
      << refused.status().message();
}

TEST(Tensorfield, TheFirstCallSendsAContinuousPathInFreeSpaceAndAsksForTheNextSubstep) {
  test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 1, 5.5f, 3.75f);
  world.robots()[0].radius_m = kRadius;
  auto planner = Load();
  ASSERT_TRUE(planner);
  const PlanResult r = MustPlan(*planner, world, At(10.0, PlanEvent::kStart));
  EXPECT_FALSE(r.done);
  ASSERT_EQ(r.robots.size(), 1u);
  const RobotPlan& plan = r.robots[0];
  EXPECT_EQ(plan.policy, TaskPolicy::kReplace);
  EXPECT_TRUE(plan.tasks.empty());
  EXPECT_TRUE(plan.path_continuous);
  ASSERT_GE(plan.path.size(), 2u);
  EXPECT_EQ(plan.path_speed_mps.size(), plan.path.size());
  EXPECT_LT((plan.path.front().position_m - world.robots()[0].position_m).norm(), 1e-4f);
  for (const PathPoint& p : plan.path)
    EXPECT_TRUE(Traversable(world, p.position_m, kRadius)) << p.position_m.transpose();
  for (float s : plan.path_speed_mps) {
    EXPECT_GT(s, 0.f);
    EXPECT_LE(s, 0.3f + 1e-5f);
  }
  // Three sub-steps of 0.4 s at 0.3 m/s at most.
  EXPECT_GT(Length(plan.path), 0.05);
  EXPECT_LE(Length(plan.path), 0.36 + 1e-3);
  EXPECT_NEAR(r.wakeup_t_s, 10.4, 1e-9);
  ASSERT_FALSE(plan.camera_trajectory.empty());
  for (size_t i = 1; i < plan.camera_trajectory.size(); ++i)
    EXPECT_GE(plan.camera_trajectory[i].t_s, plan.camera_trajectory[i - 1].t_s);
  bool keyframe = false;
  for (const auto& [name, value] : r.diagnostics) keyframe = keyframe || name == "field_ms";
  EXPECT_TRUE(keyframe);
}

TEST(Tensorfield, ThePathFollowsTheCorridorOverASimulatedLoop) {
  test::RasterWorld world = Corridor();
  auto planner = Load();
  ASSERT_TRUE(planner);
  const float y_axis = 1.3f;
  const Eigen::Vector2f start = world.robots()[0].position_m;
  double t = 20.0;
  int advected = 0;
  for (int call = 0; call < 16; ++call, t += 0.4) {
    const PlanResult r = MustPlan(*planner, world, At(t));
    ASSERT_FALSE(r.done) << "call " << call;
    advected += Diagnostic(r, "mode") == 0.0;  // the field's pathline, not a fallback route
    EXPECT_EQ(Diagnostic(r, "fallback_routes"), 0.0) << "call " << call;
    const RobotPlan& plan = r.robots[0];
    ASSERT_GE(plan.path.size(), 2u) << "call " << call;
    for (const PathPoint& p : plan.path) {
      EXPECT_TRUE(Traversable(world, p.position_m, kRadius)) << p.position_m.transpose();
      EXPECT_LT(std::abs(p.position_m.y() - y_axis), 0.41f) << "call " << call;
    }
    // Drive one sub-step (0.12 m) of it, as the loop would before the next call.
    PlannerRobot& robot = world.robots()[0];
    double left = 0.12;
    for (size_t i = 1; i < plan.path.size() && left > 0.0; ++i) {
      const Eigen::Vector2f d = plan.path[i].position_m - robot.position_m;
      const float step = float(std::min<double>(left, d.norm()));
      if (d.norm() < 1e-6f) continue;
      robot.position_m += d.normalized() * step;
      robot.theta_rad = std::atan2(d.y(), d.x());
      left -= step;
    }
  }
  EXPECT_GE(advected, 14);
  const Eigen::Vector2f moved = world.robots()[0].position_m - start;
  // Along +x (the side the robot faced), not across: 16 sub-steps of 0.12 m is 1.92 m.
  EXPECT_GT(moved.x(), 1.2f) << moved.transpose();
  EXPECT_LT(std::abs(moved.y()), 0.4f) << moved.transpose();
  EXPECT_LT(std::abs(world.robots()[0].theta_rad), 0.35f);  // aligned with the corridor by now
}

TEST(Tensorfield, DoneOnlyOnceNoFrontierIsLeft) {
  // Everything known: nothing to see along any skeleton edge, no frontier: done, no wakeup.
  test::RasterWorld known = test::ApartmentWorld(6.f, 4.f, 0.05f, 1, 6.f, 3.f);
  const PlanResult d = MustPlan(*Load(), known, At(5.0, PlanEvent::kStart));
  EXPECT_TRUE(d.done);
  EXPECT_TRUE(std::isnan(d.wakeup_t_s));
  // A frontier the robot reaches: never done, however little the field sees of it.
  test::RasterWorld open = test::ApartmentWorld(6.f, 4.f, 0.05f, 1, 5.0f, 3.f);
  open.robots()[0].radius_m = kRadius;
  auto planner = Load(R"({"gain_threshold": 1.0})");  // no edge counts: only the frontier holds it
  for (int call = 0; call < 8; ++call) {
    const PlanResult r = MustPlan(*planner, open, At(5.0 + 0.4 * call));
    EXPECT_FALSE(r.done) << "call " << call;
    EXPECT_FALSE(r.robots[0].path.empty()) << "call " << call;
  }
}

TEST(Tensorfield, TheFixedCameraLooksAlongThePathAndPlansAreDeterministic) {
  test::RasterWorld world = Corridor();
  const PlanResult fixed = MustPlan(*Load(R"({"camera": "fixed"})"), world, At(1.0));
  const RobotPlan& plan = fixed.robots[0];
  ASSERT_FALSE(plan.camera_trajectory.empty());
  for (const CameraSample& s : plan.camera_trajectory) {
    EXPECT_NEAR(s.pitch_rad, 0.f, 1e-5f);
    EXPECT_LT(std::abs(std::remainder(s.yaw_rad - 0.f, 6.2831853f)), 0.5f);  // along +x
  }
  const PlanResult a = MustPlan(*Load(), world, At(1.0)), b = MustPlan(*Load(), world, At(1.0));
  ASSERT_EQ(a.robots[0].path.size(), b.robots[0].path.size());
  for (size_t i = 0; i < a.robots[0].path.size(); ++i)
    EXPECT_EQ(a.robots[0].path[i].position_m, b.robots[0].path[i].position_m);
  ASSERT_EQ(a.robots[0].camera_trajectory.size(), b.robots[0].camera_trajectory.size());
  for (size_t i = 0; i < a.robots[0].camera_trajectory.size(); ++i)
    EXPECT_EQ(a.robots[0].camera_trajectory[i].yaw_rad, b.robots[0].camera_trajectory[i].yaw_rad);
}

// The surface term reads the host's surface voxels (the fake world's: every wall cell next to
// free floor, weight 2): the camera's views turn from the unknown ahead towards the walls, and
// the plan stays deterministic; the base's path does not use the term.
TEST(Tensorfield, TheSurfaceTermMovesOnlyTheCamerasViewsAndIsDeterministic) {
  test::RasterWorld world = Corridor();
  const char* config = R"({"surface_depth_m": 5.0})";
  const PlanResult a = MustPlan(*Load(config), world, At(1.0));
  const PlanResult b = MustPlan(*Load(config), world, At(1.0));
  const PlanResult off = MustPlan(*Load(), world, At(1.0));
  const RobotPlan &pa = a.robots[0], &pb = b.robots[0], &po = off.robots[0];
  ASSERT_FALSE(pa.camera_trajectory.empty());
  ASSERT_EQ(pa.camera_trajectory.size(), pb.camera_trajectory.size());
  for (size_t i = 0; i < pa.camera_trajectory.size(); ++i)
    EXPECT_EQ(pa.camera_trajectory[i].yaw_rad, pb.camera_trajectory[i].yaw_rad);
  ASSERT_EQ(pa.path.size(), po.path.size());
  for (size_t i = 0; i < pa.path.size(); ++i)
    EXPECT_EQ(pa.path[i].position_m, po.path[i].position_m);
  bool moved = pa.camera_trajectory.size() != po.camera_trajectory.size();
  for (size_t i = 0; !moved && i < pa.camera_trajectory.size(); ++i)
    moved = pa.camera_trajectory[i].yaw_rad != po.camera_trajectory[i].yaw_rad;
  EXPECT_TRUE(moved);
}

// "aim": the views tilt down towards the floor band's middle (the fake world's camera is 1.2 m
// up, over the 1.8 m band's 0.9 m), within the mount's pitch range; "level" keeps them at 0.
TEST(Tensorfield, AimedViewsTiltTowardsTheFloorBandsMiddle) {
  test::RasterWorld world = Corridor();
  const PlanResult aimed = MustPlan(*Load(R"({"pitch": "aim"})"), world, At(1.0));
  const PlanResult level = MustPlan(*Load(), world, At(1.0));
  ASSERT_FALSE(aimed.robots[0].camera_trajectory.empty());
  int down = 0;
  for (const CameraSample& s : aimed.robots[0].camera_trajectory) {
    EXPECT_LE(s.pitch_rad, 1e-6f);
    EXPECT_GE(s.pitch_rad, world.robots()[0].min_pitch_rad - 1e-6f);
    down += s.pitch_rad < -0.02f;
  }
  EXPECT_GT(down, 0);
  for (const CameraSample& s : level.robots[0].camera_trajectory)
    EXPECT_NEAR(s.pitch_rad, 0.f, 1e-6f);
}

TEST(Tensorfield, TopologyControlReportsItsWorkAndKeepsThePathInFreeSpace) {
  // Rooms joined by doors, partly unknown: key frames with corners and doorways. With
  // topology_control the moves and cancellations are counted (cumulative, never decreasing) and
  // the path stays where the robot may stand; without it the counters are not reported.
  test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 1, 5.f, 3.f);
  auto controlled = Load(R"({"topology_control": true})");
  auto plain = Load();
  ASSERT_TRUE(controlled && plain);
  double last_total = 0.0;
  for (int call = 0; call < 6; ++call) {
    const PlanResult r = MustPlan(*controlled, world, At(5.0 + 0.4 * call));
    double total = 0.0;
    for (const char* name :
         {"cancelled_pairs", "corner_wedges", "retracted_wedges", "moved_trisectors"}) {
      const double v = Diagnostic(r, name);
      ASSERT_FALSE(std::isnan(v)) << name;
      EXPECT_GE(v, 0.0) << name;
      total += v;
    }
    EXPECT_GE(total, last_total) << "call " << call;
    last_total = total;
    if (Diagnostic(r, "keyframe") == 1.0) {
      EXPECT_GE(Diagnostic(r, "control_ms"), 0.0);
      // Cancellations remove points, moves keep their count: never more after than before.
      const double before = Diagnostic(r, "control_points_before");
      EXPECT_GE(before, 0.0);
      EXPECT_GE(Diagnostic(r, "control_points_after"), 0.0);
      EXPECT_LE(Diagnostic(r, "control_points_after"), before);
      EXPECT_GE(Diagnostic(r, "census_degenerate"), 1.0);
      EXPECT_GE(Diagnostic(r, "census_vector"), 0.0);
    }
    for (const PathPoint& p : r.robots[0].path)
      EXPECT_TRUE(Traversable(world, p.position_m, 0.18f)) << p.position_m.transpose();
    const PlanResult q = MustPlan(*plain, world, At(5.0 + 0.4 * call));
    EXPECT_TRUE(std::isnan(Diagnostic(q, "corner_wedges")));
    EXPECT_TRUE(std::isnan(Diagnostic(q, "control_ms")));
    EXPECT_TRUE(std::isnan(Diagnostic(q, "control_points_before")));
  }
}

}  // namespace
}  // namespace voxplan
