// The taskflow planner plugin (Guo 2022) through the host, on grid worlds: valid tasks only, the
// task flow's append to every robot (and NoFlow's wait for all), exploration views with the
// head's tilt sweep, reconstruction views of a half-seen object on the arm within its workspace,
// fixed and forced modes, termination, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "plugins/host/plugin_host.h"
#include "tests/plugins/fake_world.h"

namespace voxplan {
namespace {

std::unique_ptr<LoadedPlanner> Load(const std::string& config = "{}") {
  PlannerLoadOptions o;
  o.config_json = config;
  o.seed = 1;
  auto planner = LoadPlanner("taskflow", o);
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

PlanResult MustPlan(LoadedPlanner& planner, const PlannerWorld& world, const PlanRequest& r = {}) {
  auto result = planner.Plan(world, r);
  EXPECT_TRUE(result.ok()) << result.status().message();
  if (!result.ok()) return {};
  for (const Rejection& j : result->rejections)
    ADD_FAILURE() << "robot " << j.robot << " task " << j.task << ": " << j.reason;
  return std::move(result).value();
}

size_t Tasks(const PlanResult& r) {
  size_t n = 0;
  for (const RobotPlan& p : r.robots) n += p.tasks.size();
  return n;
}

// The reconstructor on an arm (sim/robot.h's workspace), as explore's --profile guo2022 shows it.
void ArmReconstructors(test::RasterWorld& world) {
  for (PlannerRobot& r : world.robots()) {
    ScanMode& m = r.modes[1];
    m.mount = CameraMount::kArm;
    m.camera_height_min_m = 0.4f;
    m.camera_height_max_m = 1.5f;
    m.reach_min_m = 0.3f;
    m.reach_max_m = 0.8f;
    m.reach_half_angle_rad = 1.5707963f;
    m.min_pitch_rad = -1.5707963f;
    m.max_pitch_rad = 1.5707963f;
    m.min_range_m = 0.2f;
    m.max_range_m = 2.5f;
    m.horizontal_fov_rad = 1.0122910f;
  }
}

// A known apartment of four rooms (robots at (2, 1.5) and (6, 1.5)), plus a box (instance 7) of
// 0.6 x 0.6 x 0.8 m in the first room, of which only the faces towards -x and -y were seen; its
// footprint is obstacle on the floor raster (occupied at every height).
class BoxWorld : public test::RasterWorld {
 public:
  BoxWorld() : RasterWorld(test::ApartmentWorld(8.f, 6.f, 0.05f, 2, 8.f, 3.75f)) {
    Fill(20, 10, 32, 22, FloorCell::kObstacle);  // x 1.0 .. 1.65, y 0.5 .. 1.15
    Finish();
    ArmReconstructors(*this);
  }
  std::vector<ObjectInstance> Instances() const override {
    ObjectInstance box;
    box.id = 7;
    box.label = "box";
    box.bbox_min = lo_;
    box.bbox_max = hi_;
    ObjectInstance wall;
    wall.id = 8;
    wall.label = "wall";
    return {box, wall};
  }
  std::vector<SurfaceVoxel> SurfaceVoxels() const override {
    std::vector<SurfaceVoxel> out = RasterWorld::SurfaceVoxels();
    for (float z = lo_.z(); z <= hi_.z(); z += 0.05f)
      for (float t = 0.f; t <= 0.6f; t += 0.05f) {
        SurfaceVoxel a;  // the -x face
        a.position = {lo_.x(), lo_.y() + t, z};
        a.normal = -Eigen::Vector3f::UnitX();
        a.weight = 5.f;
        a.instance = 7;
        out.push_back(a);
        SurfaceVoxel b = a;  // the -y face
        b.position = {lo_.x() + t, lo_.y(), z};
        b.normal = -Eigen::Vector3f::UnitY();
        out.push_back(b);
      }
    return out;
  }

 private:
  Eigen::Vector3f lo_{1.0f, 0.5f, 0.05f}, hi_{1.6f, 1.1f, 0.8f};
};

TEST(Taskflow, LoadsAndRefusesBadConfigsNamingTheKey) {
  ASSERT_TRUE(Load());
  for (const char* bad : {R"({"flow": "sometimes"})", R"({"lambda": 1})",
                          R"({"fixed_explorers": -1})", R"({"policy": "best"})"}) {
    PlannerLoadOptions o;
    o.config_json = bad;
    EXPECT_FALSE(LoadPlanner("taskflow", o).ok()) << bad;
  }
}

TEST(Taskflow, TheStartAppendsValidExplorationViewsWithTheHeadsTiltSweep) {
  test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 3, 5.5f, 2.7f);
  auto planner = Load();
  ASSERT_TRUE(planner);
  PlanRequest start;
  start.event = PlanEvent::kStart;
  const PlanResult r = MustPlan(*planner, world, start);
  EXPECT_FALSE(r.done);
  ASSERT_GT(Tasks(r), 0u);
  for (const RobotPlan& plan : r.robots) {
    EXPECT_EQ(plan.policy, TaskPolicy::kAppend);  // the task flow appends, never replaces
    for (const PlannerTask& t : plan.tasks) {
      EXPECT_EQ(t.mode, 0);  // no objects: exploration only
      EXPECT_TRUE(t.camera.Sweeps());
      EXPECT_LT(t.camera.sweep_pitch_min_rad, 0.f);
      EXPECT_GT(t.camera.sweep_pitch_max_rad, 0.f);
      EXPECT_FALSE(t.camera.ArmSet());
    }
  }
}

TEST(Taskflow, AsyncPlansWhenOneRobotRunsDryAndSyncWaitsForAll) {
  test::RasterWorld world = test::ApartmentWorld(8.f, 6.f, 0.05f, 2, 5.5f, 2.7f);
  PlannerTask queued;
  queued.position_m = world.robots()[1].position_m;
  world.robots()[1].queue = {queued};
  world.robots()[1].executing = true;
  PlanRequest idle;
  idle.event = PlanEvent::kRobotIdle;
  idle.event_robot = 0;
  auto async = Load();
  const PlanResult a = MustPlan(*async, world, idle);
  EXPECT_GT(Tasks(a), 0u);  // robot 0 ran dry: a round for the team, appended
  auto sync = Load(R"({"flow": "sync"})");
  const PlanResult s = MustPlan(*sync, world, idle);
  EXPECT_EQ(Tasks(s), 0u);  // robot 1 still works: NoFlow waits
  // A watchdog interval call with every robot busy plans nothing either.
  world.robots()[0].queue = {queued};
  world.robots()[0].executing = true;
  PlanRequest interval;
  interval.event = PlanEvent::kInterval;
  EXPECT_EQ(Tasks(MustPlan(*Load(), world, interval)), 0u);
}

TEST(Taskflow, AHalfSeenObjectGetsArmViewsOfItsUnseenSideInsideTheWorkspace) {
  BoxWorld world;
  auto planner = Load(R"({"views_per_robot": 1})");
  ASSERT_TRUE(planner);
  const PlanResult r = MustPlan(*planner, world);
  size_t recon = 0;
  for (const RobotPlan& plan : r.robots)
    for (const PlannerTask& t : plan.tasks) {
      if (t.camera.object_id < 0) continue;
      ++recon;
      EXPECT_EQ(t.camera.object_id, 7);  // never the wall
      EXPECT_EQ(t.mode, 1);
      ASSERT_TRUE(t.camera.ArmSet());
      EXPECT_GE(t.camera.height_m, 0.4f - 1e-4f);
      EXPECT_LE(t.camera.height_m, 1.5f + 1e-4f);
      const float reach = t.camera.offset_m.norm();
      EXPECT_GE(reach, 0.3f - 1e-4f);
      EXPECT_LE(reach, 0.8f + 1e-4f);
      EXPECT_TRUE(t.camera.look_at);
      // The camera stands on the unseen (+x or +y) side of the box.
      const float c = std::cos(t.theta_rad), s = std::sin(t.theta_rad);
      const Eigen::Vector2f cam =
          t.position_m + Eigen::Vector2f(c * t.camera.offset_m.x() - s * t.camera.offset_m.y(),
                                         s * t.camera.offset_m.x() + c * t.camera.offset_m.y());
      EXPECT_TRUE(cam.x() > 1.6f || cam.y() > 1.1f) << cam.transpose();
    }
  EXPECT_GT(recon, 0u);
  // The next round: the object is queued for (its tasks are in a robot's queue), so no new views.
  for (size_t i = 0; i < r.robots.size(); ++i) world.robots()[i].queue = r.robots[i].tasks;
  const PlanResult again = MustPlan(*planner, world);
  for (const RobotPlan& plan : again.robots)
    for (const PlannerTask& t : plan.tasks) EXPECT_NE(t.camera.object_id, 7);
}

TEST(Taskflow, ForcedAndFixedModesAndNoCompletionAreHonoured) {
  BoxWorld world;
  for (const auto& [config, want_mode] : std::vector<std::pair<std::string, int>>{
           {R"({"force_mode": "explorer"})", 0}, {R"({"force_mode": "reconstructor"})", 1}}) {
    const PlanResult r = MustPlan(*Load(config), world);
    ASSERT_GT(Tasks(r), 0u) << config;
    for (const RobotPlan& plan : r.robots)
      for (const PlannerTask& t : plan.tasks) {
        EXPECT_EQ(t.mode, want_mode) << config;
        if (want_mode == 0) {
          EXPECT_FALSE(t.camera.ArmSet()) << config;  // a head has no arm
        }
      }
  }
  const PlanResult none = MustPlan(*Load(R"({"completion": "none"})"), world);
  for (const RobotPlan& plan : none.robots)
    for (const PlannerTask& t : plan.tasks) EXPECT_LT(t.camera.object_id, 0);
  // Two robots, one fixed explorer: robot 0 explores, robot 1 reconstructs.
  const PlanResult fixed = MustPlan(*Load(R"({"modes": "fixed", "fixed_explorers": 1})"), world);
  for (const PlannerTask& t : fixed.robots[0].tasks) EXPECT_EQ(t.mode, 0);
  for (const PlannerTask& t : fixed.robots[1].tasks) EXPECT_EQ(t.mode, 1);
}

TEST(Taskflow, DoneOnAFullyExploredWorldWithNothingIncompleteAndDeterministic) {
  test::RasterWorld world = test::ApartmentWorld(6.f, 4.f, 0.05f, 2, 6.f, 3.f);
  const PlanResult r = MustPlan(*Load(), world);
  EXPECT_TRUE(r.done);
  EXPECT_EQ(Tasks(r), 0u);
  BoxWorld box;
  const PlanResult a = MustPlan(*Load(), box), b = MustPlan(*Load(), box);
  ASSERT_EQ(a.robots.size(), b.robots.size());
  for (size_t i = 0; i < a.robots.size(); ++i) {
    ASSERT_EQ(a.robots[i].tasks.size(), b.robots[i].tasks.size());
    for (size_t k = 0; k < a.robots[i].tasks.size(); ++k) {
      EXPECT_EQ(a.robots[i].tasks[k].position_m, b.robots[i].tasks[k].position_m);
      EXPECT_EQ(a.robots[i].tasks[k].camera.height_m, b.robots[i].tasks[k].camera.height_m);
    }
  }
}

}  // namespace
}  // namespace voxplan
