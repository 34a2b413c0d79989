// The real planner plugins (omt, greedy, voronoi) through the host: loading by name, valid tasks
// on grid worlds (the host's validation rejects none), determinism, termination on an explored
// world, and each baseline's defining rule (GRD: distinct views; SEG: each view to its nearest
// robot; GRD "best": the best views go to the whole team).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "plugins/host/plugin_host.h"
#include "tests/plugins/fake_world.h"

namespace voxplan {
namespace {

const std::vector<std::string> kPlanners = {"omt", "greedy", "voronoi"};
// Angles and positions travel as floats through the C boundary.
constexpr float kAngleTol = 1e-3f;

std::unique_ptr<LoadedPlanner> MustLoad(const std::string& name, const std::string& config = "{}",
                                        uint64_t seed = 1) {
  PlannerLoadOptions o;
  o.config_json = config;
  o.seed = seed;
  auto planner = LoadPlanner(name, o);
  EXPECT_TRUE(planner.ok()) << name << ": " << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

PlanResult MustPlan(LoadedPlanner& planner, const PlannerWorld& world, const PlanRequest& r = {}) {
  auto result = planner.Plan(world, r);
  EXPECT_TRUE(result.ok()) << planner.name() << ": " << result.status().message();
  if (!result.ok()) return {};
  for (const Rejection& j : result->rejections) {
    ADD_FAILURE() << planner.name() << ": robot " << j.robot << " task " << j.task << ": "
                  << j.reason;
  }
  return std::move(result).value();
}

std::map<std::string, double> Diagnostics(const PlanResult& r) {
  return {r.diagnostics.begin(), r.diagnostics.end()};
}

// A world of 8 x 6 m at 5 cm: six rooms, the right third unknown, three robots.
test::RasterWorld SmallApartment() { return test::ApartmentWorld(8.f, 6.f, 0.05f, 3, 5.5f, 2.7f); }

// Every task field, byte for byte, then the paths: the whole observable plan.
std::vector<uint8_t> Bytes(const PlanResult& r) {
  std::vector<uint8_t> bytes;
  auto put = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  };
  for (const RobotPlan& plan : r.robots) {
    put(&plan.policy, sizeof plan.policy);
    for (const PlannerTask& t : plan.tasks) {
      put(t.position_m.data(), 2 * sizeof(float));
      put(&t.theta_rad, sizeof(float));
      put(&t.camera_yaw_rad, sizeof(float));
      put(&t.camera_pitch_rad, sizeof(float));
      put(&t.dwell_s, sizeof(float));
      put(&t.mode, sizeof t.mode);
      put(&t.tag, sizeof t.tag);
    }
    for (const PathPoint& p : plan.path) {
      put(p.position_m.data(), 2 * sizeof(float));
      put(&p.theta_rad, sizeof(float));
    }
    for (const CameraSample& s : plan.camera_trajectory) {
      put(&s.t_s, sizeof(float));
      put(s.position_m.data(), 3 * sizeof(float));
      put(&s.yaw_rad, sizeof(float));
    }
  }
  bytes.push_back(r.done ? 1 : 0);
  return bytes;
}

// The tag is the view's target cell: the camera (base heading + camera yaw) must face it.
void ExpectCameraFacesTarget(const PlannerWorld& world, const PlannerTask& t) {
  const PlannerFloor& floor = world.Floor();
  ASSERT_LT(t.tag, floor.cells.size());
  const Eigen::Vector2f target =
      floor.CellCenter(int(t.tag % uint32_t(floor.width)), int(t.tag / uint32_t(floor.width)));
  const Eigen::Vector2f d = target - t.position_m;
  const float want = std::atan2(d.y(), d.x());
  const float got = t.theta_rad + t.camera_yaw_rad;
  EXPECT_NEAR(std::remainder(got - want, 2.f * float(M_PI)), 0.f, kAngleTol);
}

TEST(Planners, LoadByNameWithVersions) {
  for (const std::string& name : kPlanners) {
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    EXPECT_EQ(planner->name(), name);
    EXPECT_EQ(planner->version(), "1.0.0");
  }
}

TEST(Planners, BadConfigsAreRefusedNamingTheKey) {
  for (const std::string& name : kPlanners) {
    PlannerLoadOptions o;
    o.config_json = R"({"kapa": 6})";
    auto typo = LoadPlanner(name, o);
    ASSERT_FALSE(typo.ok());
    EXPECT_NE(typo.status().message().find("'kapa' is unknown"), std::string::npos)
        << typo.status().message();
    o.config_json = R"({"kappa": "six"})";
    EXPECT_FALSE(LoadPlanner(name, o).ok());
    o.config_json = "{kappa";
    auto garbage = LoadPlanner(name, o);
    ASSERT_FALSE(garbage.ok());
    EXPECT_NE(garbage.status().message().find("not valid JSON"), std::string::npos);
  }
}

TEST(Planners, EveryRobotGetsValidTasksOnTheApartment) {
  const test::RasterWorld world = SmallApartment();
  std::set<double> view_counts;  // the baselines plan over the OMT pass's own views
  for (const std::string& name : kPlanners) {
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    SCOPED_TRACE(name);
    EXPECT_FALSE(r.done);
    ASSERT_EQ(r.robots.size(), 3u);
    int robots_with_tasks = 0;
    for (size_t i = 0; i < r.robots.size(); ++i) {
      const RobotPlan& plan = r.robots[i];
      EXPECT_EQ(plan.policy, TaskPolicy::kReplace);
      if (plan.tasks.empty()) continue;
      ++robots_with_tasks;
      ASSERT_GE(plan.path.size(), 2u);
      EXPECT_TRUE(plan.path.front().position_m.isApprox(world.Robots()[i].position_m));
      for (const PlannerTask& t : plan.tasks) ExpectCameraFacesTarget(world, t);
    }
    const auto d = Diagnostics(r);
    if (name == "greedy") {
      EXPECT_EQ(robots_with_tasks, 3);  // more important views than robots, all reachable
    } else if (name == "voronoi") {
      for (size_t i = 0; i < r.robots.size(); ++i) {  // exactly the robots owning a view
        EXPECT_EQ(r.robots[i].tasks.empty(), d.at("region_views_" + std::to_string(i)) == 0.0);
      }
    } else {
      EXPECT_GE(robots_with_tasks, 2);  // OMT's refinement may leave a robot without a cluster
    }
    EXPECT_GT(d.at("views"), 0.0);
    EXPECT_GE(d.at("plan_ms"), 0.0);
    view_counts.insert(d.at("views"));
  }
  EXPECT_EQ(view_counts.size(), 1u);
}

TEST(Planners, ValidTasksOnTheSmallFakeWorld) {
  // Coarse 0.25 m cells, a wide robot, a sealed pocket and an executing robot: nothing the
  // planners return may be rejected.
  const test::FakeWorld world;
  for (const std::string& name : kPlanners) {
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    SCOPED_TRACE(name);
    size_t tasks = 0;
    for (const RobotPlan& plan : r.robots) tasks += plan.tasks.size();
    EXPECT_GT(tasks, 0u);
  }
}

TEST(Planners, OmtCameraTrajectoryFollowsThePathInTime) {
  const test::RasterWorld world = SmallApartment();
  auto planner = MustLoad("omt");
  ASSERT_TRUE(planner);
  const PlanResult r = MustPlan(*planner, world);
  for (const RobotPlan& plan : r.robots) {
    if (plan.tasks.empty()) continue;
    ASSERT_GE(plan.camera_trajectory.size(), plan.path.size());
    EXPECT_EQ(plan.camera_trajectory.front().t_s, 0.f);
    EXPECT_GT(plan.camera_trajectory.back().t_s, 0.f);
    // Yaw at the last view is that view's camera direction.
    const PlannerTask& last = plan.tasks.back();
    EXPECT_NEAR(std::remainder(
                    plan.camera_trajectory.back().yaw_rad - (last.theta_rad + last.camera_yaw_rad),
                    2.f * float(M_PI)),
                0.f, kAngleTol);
  }
  const auto d = Diagnostics(r);
  for (const char* key : {"omt_ms", "input_ms", "output_ms", "assignment_energy", "tasks"}) {
    EXPECT_TRUE(d.count(key)) << key;
  }
}

TEST(Planners, OmtAblationsAndInternalGeodesicsPlanValidTasks) {
  const test::RasterWorld world = SmallApartment();
  for (const char* config :
       {R"({"use_task_views": false, "use_tsp": false, "refine": false, "optimize_paths": false})",
        R"({"geodesics": "internal", "kappa": 4})"}) {
    auto planner = MustLoad("omt", config);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    size_t tasks = 0;
    for (const RobotPlan& plan : r.robots) tasks += plan.tasks.size();
    EXPECT_GT(tasks, 0u) << config;
  }
}

TEST(Planners, SameSeedSameWorldSameBytes) {
  const test::RasterWorld world = SmallApartment();
  for (const std::string& name : kPlanners) {
    auto a = MustLoad(name, "{}", 5);
    auto b = MustLoad(name, "{}", 5);
    ASSERT_TRUE(a && b);
    PlanRequest request;
    request.seed = 11;
    const std::vector<uint8_t> first = Bytes(MustPlan(*a, world, request));
    EXPECT_GT(first.size(), 1u);
    EXPECT_EQ(first, Bytes(MustPlan(*b, world, request))) << name;
  }
}

TEST(Planners, DoneOnAFullyExploredWorld) {
  // No unknown cell, every surface scanned a thousand times: nothing is worth a view.
  test::RasterWorld world = test::ApartmentWorld(6.f, 4.f, 0.05f, 2, 6.f, 3.f);
  world.set_surface_weight(1000.f);
  for (const std::string& name : kPlanners) {
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    EXPECT_TRUE(r.done) << name;
    for (const RobotPlan& plan : r.robots) EXPECT_TRUE(plan.tasks.empty()) << name;
  }
}

TEST(Planners, NotDoneWhileNoRobotStandsOnKnownFreeSpace) {
  // A robot in a 0.3 m patch of known floor amid unknown space: the scene cannot be judged yet,
  // which must not read as "explored"; a view, if any, stands on the patch (turning to look).
  test::RasterWorld world(60, 60, 0.05f);
  world.Fill(0, 0, 59, 59, FloorCell::kUnknown);
  world.Fill(27, 27, 32, 32, FloorCell::kFree);
  world.Finish();
  world.AddRobot(30, 30, 0.18f);
  for (const std::string& name : kPlanners) {
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    EXPECT_FALSE(r.done) << name;
    for (const PlannerTask& t : r.robots[0].tasks) {
      EXPECT_EQ(world.CellAt(t.position_m), FloorCell::kFree) << name;
    }
  }
}

// A scanned 4 x 2 m room whose walls never gain weight, with unknown cells [x0, x1] x [y0, y1],
// and one robot at cell (10, 20) heading theta_rad.
test::RasterWorld RoomWithPocket(int x0, int y0, int x1, int y1, float theta_rad) {
  test::RasterWorld world(80, 40, 0.05f);
  world.Walls();
  world.Fill(x0, y0, x1, y1, FloorCell::kUnknown);
  world.Finish();
  world.set_surface_weight(1000.f);
  world.AddRobot(10, 20, 0.18f).theta_rad = theta_rad;
  return world;
}

TEST(Planners, DoneOnceAnIdleRobotLookedAtWhatStaysUnknown) {
  // A scanned room with an unknown pocket 2 m ahead of an idle robot: facing it, the robot has
  // looked at it from within range and it stayed unknown (the sensor cannot resolve it from
  // there), so nothing is worth a view; facing away, the pocket still is.
  for (const float theta : {0.f, 3.1416f}) {
    test::RasterWorld world = RoomWithPocket(50, 15, 55, 25, theta);
    for (const std::string& name : kPlanners) {
      auto planner = MustLoad(name);
      ASSERT_TRUE(planner);
      const PlanResult r = MustPlan(*planner, world);
      EXPECT_EQ(r.done, theta == 0.f) << name << " facing " << theta;
      EXPECT_EQ(r.robots[0].tasks.empty(), theta == 0.f) << name << " facing " << theta;
    }
  }
}

TEST(Planners, UnknownFloorTheCameraCannotSeeIsNeitherSettledNorViewedLevel) {
  // The pocket of the test above, 2.0-2.3 m ahead, under a 45° vertical field of view (an Xtion)
  // 1.2 m up: level, the camera sees no floor nearer than 2.9 m, so facing the pocket has not
  // looked at it (not settled, not done); pitched 0.5 rad down it sees floor from 0.97 m on, so
  // the same look settles it. A view sent to unknown floor tilts the camera just enough to see
  // its target, and not at all where the level camera already does.
  constexpr float kVfov = 0.785f;
  auto narrow = [](float theta, float pitch, float vfov) {
    test::RasterWorld world = RoomWithPocket(50, 15, 55, 25, theta);
    for (ScanMode& m : world.robots()[0].modes) m.vertical_fov_rad = vfov;
    world.robots()[0].camera_pitch_rad = pitch;
    return world;
  };
  for (const std::string& name : kPlanners) {
    {
      auto planner = MustLoad(name);
      ASSERT_TRUE(planner);
      EXPECT_FALSE(MustPlan(*planner, narrow(0.f, 0.f, kVfov)).done)
          << name << ": settled unseen floor";
    }
    {
      auto planner = MustLoad(name);
      ASSERT_TRUE(planner);
      EXPECT_TRUE(MustPlan(*planner, narrow(0.f, -0.5f, kVfov)).done) << name;
    }
    for (const float vfov : {kVfov, 1.2f}) {
      test::RasterWorld world = narrow(3.1416f, 0.f, vfov);
      auto planner = MustLoad(name);
      ASSERT_TRUE(planner);
      const PlanResult r = MustPlan(*planner, world);
      ASSERT_FALSE(r.robots[0].tasks.empty()) << name;
      const PlannerFloor& floor = world.Floor();
      const float h = world.robots()[0].camera_height_m;
      for (const PlannerTask& t : r.robots[0].tasks) {
        ASSERT_LT(t.tag, floor.cells.size());
        const Eigen::Vector2f target = floor.CellCenter(int(t.tag % uint32_t(floor.width)),
                                                        int(t.tag / uint32_t(floor.width)));
        if (world.CellAt(target) != FloorCell::kUnknown) continue;  // a wall to rescan: level
        const float d = (target - t.position_m).norm();
        const float below = std::atan2(h, d);  // the target's floor below the horizon
        EXPECT_LE(t.camera_pitch_rad, 0.f) << name;
        EXPECT_LE(below, 0.5f * vfov - t.camera_pitch_rad + kAngleTol) << name << " d " << d;
        // Level whenever a level camera sees the target's near edge.
        if (std::atan2(h, d - 0.5f * floor.cell_size_m) <= 0.5f * vfov) {
          EXPECT_EQ(t.camera_pitch_rad, 0.f) << name << " d " << d;
        }
      }
    }
  }
}

TEST(Planners, AFailedTaskSettlesNothingUntilTheRobotTakesAView) {
  // The pocket of the test above, 2 m ahead of a robot whose drive towards it was refused: it
  // stands where it stopped, facing the pocket, idle, and has not looked from any view. Neither
  // the failure call nor a later idle call may settle the pocket (it would end the run with the
  // pocket unseen); once the robot stands at a view it was sent to after the failure, it may.
  for (const std::string& name : kPlanners) {
    // Facing away: the start settles nothing of the pocket.
    test::RasterWorld world = RoomWithPocket(50, 15, 55, 25, 3.1416f);
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    const PlanResult start = MustPlan(*planner, world);
    ASSERT_FALSE(start.done) << name;
    ASSERT_FALSE(start.robots[0].tasks.empty()) << name;
    world.robots()[0].theta_rad = 0.f;  // turned towards its task, then bumped
    PlanRequest failed;
    failed.event = PlanEvent::kTaskFailed;
    failed.event_robot = 0;
    failed.call_index = 1;
    failed.failed_task = start.robots[0].tasks[0];
    const PlanResult after_failure = MustPlan(*planner, world, failed);
    EXPECT_FALSE(after_failure.done) << name;
    PlanRequest idle;
    idle.event = PlanEvent::kRobotIdle;
    idle.event_robot = 0;
    idle.call_index = 2;
    const PlanResult still = MustPlan(*planner, world, idle);
    EXPECT_FALSE(still.done) << name << ": settled the pocket from where the drive failed";
    ASSERT_FALSE(still.robots[0].tasks.empty()) << name;
    // It takes its view: standing there, facing the target, the pocket is looked at in vain.
    const PlannerTask& view = still.robots[0].tasks.back();
    world.robots()[0].position_m = view.position_m;
    world.robots()[0].theta_rad = view.theta_rad;
    world.robots()[0].camera_yaw_rad = view.camera_yaw_rad;
    world.robots()[0].camera_pitch_rad = view.camera_pitch_rad;
    idle.call_index = 3;
    EXPECT_TRUE(MustPlan(*planner, world, idle).done) << name;
  }
}

TEST(Planners, ImportanceThresholdScalesWithWhatTheCameraSees) {
  // 1.5 is the paper's bar for its sensor's views (58°, ψ flat from 0.5 to 3 m). Views reach no
  // further and no wider than the robots' camera, and the bar scales with what such a view can
  // see (the ψ-weighted area of its fan), so a camera at least as good as the paper's keeps it.
  const double deg = M_PI / 180.0;
  const auto capacity = [](double fov_rad, double range_m) {  // ∫ψ(d) d dd, d_min = 0.5 m
    return fov_rad * (0.25 / 3.0 + 0.5 * (range_m * range_m - 0.25));
  };
  constexpr double kFloatTol = 1e-6;  // angles and ranges cross the plugin boundary as floats
  const std::vector<std::tuple<double, float, double>> cameras = {
      {90.0, 5.f, 1.5},  // the explorer's default
      {58.0, 3.f, 1.5},  // the paper's Xtion
      {29.0, 3.f, 0.75},
      {58.0, 1.5f, 1.5 * capacity(58 * deg, 1.5) / capacity(58 * deg, 3.0)}};
  for (const auto& [fov_deg, range_m, want] : cameras) {
    test::RasterWorld world = SmallApartment();
    for (PlannerRobot& r : world.robots()) {
      r.modes[0].horizontal_fov_rad = float(fov_deg * deg);
      r.modes[0].max_range_m = range_m;
    }
    auto planner = MustLoad("omt");
    ASSERT_TRUE(planner);
    const double got = Diagnostics(MustPlan(*planner, world)).at("importance_threshold");
    EXPECT_NEAR(got, want, kFloatTol * want) << fov_deg << " deg, " << range_m << " m";
    if (fov_deg >= 58.0 && range_m >= 3.f) {
      EXPECT_EQ(got, 1.5);  // exactly the paper's
    }
  }
  // A pocket of 2 x 2 unknown cells in a scanned room: a view of it is worth about 1 (4 cells
  // of a quarter reference cell each). Below the bar for the default camera, so the planners
  // are done; above it for a camera half as wide (bar 0.75), which still sends a robot there.
  for (const std::string& name : kPlanners) {
    for (const double fov_deg : {90.0, 29.0}) {
      // Facing away: its first look settles nothing of the pocket.
      test::RasterWorld world = RoomWithPocket(50, 20, 51, 21, 3.1416f);
      world.robots()[0].modes[0].horizontal_fov_rad = float(fov_deg * deg);
      auto planner = MustLoad(name);
      ASSERT_TRUE(planner);
      const PlanResult r = MustPlan(*planner, world);
      EXPECT_EQ(r.done, fov_deg == 90.0) << name << " " << fov_deg << " deg";
      EXPECT_EQ(r.robots[0].tasks.empty(), fov_deg == 90.0) << name << " " << fov_deg << " deg";
    }
  }
}

TEST(Planners, SettleViewsThatKeepComingBackAndFinish) {
  // A room whose walls never gain weight (this world's surfaces are fixed, as a surface the
  // sensor cannot improve from anywhere reachable would be): each view stays important, so
  // without the repeat rule the robot is sent to the same views forever. The robot takes each
  // task (stands at the view, looks along it) and reports idle.
  for (const std::string& name : kPlanners) {
    test::RasterWorld world(60, 40, 0.05f);
    world.Walls();
    world.Fill(28, 18, 32, 22, FloorCell::kObstacle);
    world.Finish();
    world.set_surface_weight(0.5f);  // uncertainty 0.67: above the queue's 0.2, below unknown's 1
    world.AddRobot(10, 20, 0.18f);
    auto planner = MustLoad(name);
    ASSERT_TRUE(planner);
    constexpr int kMaxCalls = 120;
    std::map<uint32_t, int> given;  // views handed out per target tag
    bool done = false;
    for (int call = 0; call < kMaxCalls && !done; ++call) {
      PlanRequest request;
      request.event = call == 0 ? PlanEvent::kStart : PlanEvent::kRobotIdle;
      request.event_robot = call == 0 ? -1 : 0;
      request.call_index = uint32_t(call);
      const PlanResult r = MustPlan(*planner, world, request);
      done = r.done;
      if (done || r.robots[0].tasks.empty()) break;
      PlannerRobot& robot = world.robots()[0];
      for (const PlannerTask& t : r.robots[0].tasks) ++given[t.tag];
      const PlannerTask& last = r.robots[0].tasks.back();
      robot.position_m = last.position_m;
      robot.theta_rad = last.theta_rad;
      robot.camera_yaw_rad = last.camera_yaw_rad;
    }
    EXPECT_TRUE(done) << name << ": still planning after " << kMaxCalls << " calls";
    for (const auto& [tag, n] : given) EXPECT_LE(n, 6) << name << ": target " << tag;
  }
}

TEST(Planners, GreedyGivesDistinctRobotsDistinctViews) {
  // Four robots, two per room: the pairs start at the same nearest view and must split.
  const test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 4, 5.5f, 4.f);
  for (const char* config :
       {R"({"policy": "best_view"})", R"({"policy": "best"})", R"({"policy": "nearest"})"}) {
    auto planner = MustLoad("greedy", config);
    ASSERT_TRUE(planner);
    const PlanResult r = MustPlan(*planner, world);
    std::set<uint32_t> tags;
    std::set<std::pair<float, float>> positions;
    for (const RobotPlan& plan : r.robots) {
      ASSERT_EQ(plan.tasks.size(), 1u) << config;  // one task per robot per call
      EXPECT_TRUE(tags.insert(plan.tasks[0].tag).second) << config;
      EXPECT_TRUE(
          positions.insert({plan.tasks[0].position_m.x(), plan.tasks[0].position_m.y()}).second)
          << config;
    }
  }
}

// A 6 x 2 m scanned room: a small unknown pocket P at the bottom left, right behind robot 0 (it
// faces away, so it has not looked at it), and a large unknown block U at the right end; robot 1
// waits in the top left corner, farther from U than robot 0. With kappa 1 the pass extracts two
// views, P first (its cells have the lowest indices) and then one of U, the more important.
test::RasterWorld PocketAndBlockWorld(bool with_robot_1 = true) {
  test::RasterWorld world(120, 40, 0.05f);
  world.Walls();
  world.Fill(4, 1, 11, 6, FloorCell::kUnknown);      // P
  world.Fill(100, 2, 118, 38, FloorCell::kUnknown);  // U
  world.Finish();
  world.set_surface_weight(1000.f);  // only unknown space is worth a view
  world.AddRobot(20, 12, 0.18f).theta_rad = 0.f;
  if (with_robot_1) world.AddRobot(8, 30, 0.18f).theta_rad = 1.5708f;
  return world;
}

TEST(Planners, GreedyBestSendsTheTeamToTheBestViewsNotTheNearest) {
  const test::RasterWorld world = PocketAndBlockWorld();
  const int width = world.Floor().width;
  auto in_pocket = [&](const PlannerTask& t) { return int(t.tag % uint32_t(width)) <= 12; };
  auto in_block = [&](const PlannerTask& t) { return int(t.tag % uint32_t(width)) >= 99; };
  std::map<std::string, PlanResult> results;
  for (const char* policy : {"best_view", "best", "nearest"}) {
    auto planner = MustLoad("greedy", std::string(R"({"kappa": 1, "policy": ")") + policy + "\"}");
    ASSERT_TRUE(planner);
    results[policy] = MustPlan(*planner, world);
    const PlanResult& r = results[policy];
    ASSERT_EQ(Diagnostics(r).at("views_important"), 2.0) << policy;
    for (const RobotPlan& plan : r.robots) ASSERT_EQ(plan.tasks.size(), 1u) << policy;
  }
  // best and best_view: U, the better view, goes to the nearer of the two robots (both hold
  // none yet), robot 0; P to the robot with fewer views, robot 1, although robot 0 stands next
  // to it.
  for (const char* policy : {"best_view", "best"}) {
    EXPECT_TRUE(in_block(results[policy].robots[0].tasks[0])) << policy;
    EXPECT_TRUE(in_pocket(results[policy].robots[1].tasks[0])) << policy;
  }
  // nearest: robot 0 plans first and takes P, robot 1 what is left.
  EXPECT_TRUE(in_pocket(results["nearest"].robots[0].tasks[0]));
  EXPECT_TRUE(in_block(results["nearest"].robots[1].tasks[0]));
}

TEST(Planners, GreedyBestViewTakesTheBestViewWhereBestTakesTheClosestOfItsShare) {
  // Robot 0 alone, kappa 2: both views, P (next to it) and U (the better one), are its own.
  const test::RasterWorld world = PocketAndBlockWorld(/*with_robot_1=*/false);
  const int width = world.Floor().width;
  std::map<std::string, PlanResult> results;
  for (const char* policy : {"best_view", "best"}) {
    auto planner = MustLoad("greedy", std::string(R"({"kappa": 2, "policy": ")") + policy + "\"}");
    ASSERT_TRUE(planner);
    results[policy] = MustPlan(*planner, world);
    ASSERT_EQ(Diagnostics(results[policy]).at("views_important"), 2.0) << policy;
    ASSERT_EQ(results[policy].robots[0].tasks.size(), 1u) << policy;
  }
  EXPECT_GE(int(results["best_view"].robots[0].tasks[0].tag % uint32_t(width)), 99);  // U
  EXPECT_LE(int(results["best"].robots[0].tasks[0].tag % uint32_t(width)), 12);       // P
  // Without a policy, best_view is what runs.
  auto plain = MustLoad("greedy", R"({"kappa": 2})");
  ASSERT_TRUE(plain);
  EXPECT_EQ(Bytes(MustPlan(*plain, world)), Bytes(results["best_view"]));
}

TEST(Planners, GreedyPoliciesAreDeterministicAndCheckedAtLoad) {
  const test::RasterWorld world = SmallApartment();
  for (const char* config :
       {R"({"policy": "best_view"})", R"({"policy": "best"})", R"({"policy": "nearest"})"}) {
    auto a = MustLoad("greedy", config, 3);
    auto b = MustLoad("greedy", config, 3);
    ASSERT_TRUE(a && b);
    const std::vector<uint8_t> first = Bytes(MustPlan(*a, world));
    EXPECT_GT(first.size(), 1u);
    EXPECT_EQ(first, Bytes(MustPlan(*b, world))) << config;
  }
  PlannerLoadOptions o;
  o.config_json = R"({"policy": "closest"})";
  auto bad = LoadPlanner("greedy", o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("policy"), std::string::npos) << bad.status().message();
}

TEST(Planners, GreedyOnIdlePlansOnlyTheIdleRobotAroundOthersQueues) {
  for (const char* config :
       {R"({"policy": "best_view"})", R"({"policy": "best"})", R"({"policy": "nearest"})"}) {
    test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 2, 5.5f, 4.f);
    auto planner = MustLoad("greedy", config);
    ASSERT_TRUE(planner);
    // Robot 1 is busy with the view greedy would give it; robot 0 turns idle next to it.
    const PlanResult start = MustPlan(*planner, world);
    ASSERT_EQ(start.robots[1].tasks.size(), 1u) << config;
    world.robots()[1].executing = true;
    world.robots()[1].queue = start.robots[1].tasks;
    PlanRequest idle;
    idle.event = PlanEvent::kRobotIdle;
    idle.event_robot = 0;
    const PlanResult r = MustPlan(*planner, world, idle);
    EXPECT_TRUE(r.robots[1].tasks.empty()) << config;
    EXPECT_EQ(r.robots[1].policy, TaskPolicy::kAppend) << config;  // its queue is left alone
    ASSERT_EQ(r.robots[0].tasks.size(), 1u) << config;
    EXPECT_NE(r.robots[0].tasks[0].tag, start.robots[1].tasks[0].tag) << config;
  }
}

TEST(Planners, BaselinesDoNotRetryAFailedViewAtOnce) {
  const std::vector<std::pair<std::string, std::string>> planners = {
      {"greedy", R"({"policy": "best_view"})"},
      {"greedy", R"({"policy": "best"})"},
      {"greedy", R"({"policy": "nearest"})"},
      {"voronoi", "{}"}};
  for (const auto& [name, config] : planners) {
    test::RasterWorld world = SmallApartment();
    auto planner = MustLoad(name, config);
    ASSERT_TRUE(planner);
    const PlanResult start = MustPlan(*planner, world);
    ASSERT_EQ(start.robots[1].tasks.size(), 1u) << name << config;
    PlanRequest failed;
    failed.event = PlanEvent::kTaskFailed;
    failed.event_robot = 1;
    failed.failed_task = start.robots[1].tasks[0];
    const PlanResult r = MustPlan(*planner, world, failed);
    EXPECT_EQ(r.robots[1].tasks.size(), 1u) << name << config;  // another view of its own
    for (const PlannerTask& t : r.robots[1].tasks) {
      EXPECT_NE(t.tag, failed.failed_task.tag) << name << config;
      EXPECT_GT((t.position_m - failed.failed_task.position_m).norm(), 0.5f) << name << config;
    }
  }
}

TEST(Planners, VoronoiSendsEachRobotToViewsNearestToIt) {
  // Four robots; the two in the rooms next to the unknown part split its views.
  const test::RasterWorld world = test::ApartmentWorld(10.f, 6.f, 0.05f, 4, 7.f, 3.3f);
  auto planner = MustLoad("voronoi", R"({"tasks_per_call": 3})");
  ASSERT_TRUE(planner);
  const PlanResult r = MustPlan(*planner, world);
  const std::vector<PlannerRobot> robots = world.Robots();
  std::vector<std::vector<float>> fields;
  for (const PlannerRobot& robot : robots) {
    fields.push_back(world.GeodesicField(robot.position_m, robot.radius_m).value());
  }
  const PlannerFloor& floor = world.Floor();
  int tasks = 0;
  for (size_t i = 0; i < r.robots.size(); ++i) {
    EXPECT_LE(r.robots[i].tasks.size(), 3u);
    for (const PlannerTask& t : r.robots[i].tasks) {
      ++tasks;
      const Eigen::Vector2i c = floor.CellOf(t.position_m);
      const size_t cell = floor.Linear(c.x(), c.y());
      for (size_t j = 0; j < robots.size(); ++j) {
        EXPECT_LE(fields[i][cell], fields[j][cell]) << "robot " << i << " vs " << j;
      }
    }
  }
  EXPECT_GE(tasks, 6);  // two robots own views, and their chains of 3 were followed
}

}  // namespace
}  // namespace voxplan
