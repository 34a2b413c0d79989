// The planner plugin boundary: loading by name and path, refusal of incompatible or broken
// modules with a message (never a crash), exceptions turned into statuses, validation of what a
// plugin returns, the time budget, and determinism for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>

#include "plugins/host/plugin_host.h"
#include "plugins/planner_cpp.h"
#include "tests/plugins/fake_world.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

const std::filesystem::path kDir = VOXPLAN_TEST_PLANNER_DIR;

PlannerLoadOptions Options(const std::string& config = "{}", uint64_t seed = 0) {
  PlannerLoadOptions o;
  o.config_json = config;
  o.seed = seed;
  o.search_path = {kDir};
  return o;
}

std::unique_ptr<LoadedPlanner> MustLoad(const std::string& name, const std::string& config = "{}",
                                        uint64_t seed = 0) {
  auto planner = LoadPlanner(name, Options(config, seed));
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

std::map<std::string, double> Diagnostics(const PlanResult& r) {
  return {r.diagnostics.begin(), r.diagnostics.end()};
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(PluginHost, LoadsByNameAndPlansToReachableFrontiers) {
  auto planner = MustLoad("minimal");
  ASSERT_TRUE(planner);
  EXPECT_EQ(planner->name(), "minimal");
  EXPECT_EQ(planner->version(), "1.0.0");
  const test::FakeWorld world;
  auto result = planner->Plan(world, {});
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_TRUE(result->rejections.empty());
  ASSERT_EQ(result->robots.size(), 2u);
  for (size_t r = 0; r < 2; ++r) {
    const RobotPlan& plan = result->robots[r];
    EXPECT_EQ(plan.policy, TaskPolicy::kReplace);
    ASSERT_EQ(plan.tasks.size(), 1u);
    EXPECT_EQ(world.CellAt(plan.tasks[0].position_m), FloorCell::kFrontier);
    ASSERT_GE(plan.path.size(), 2u);
    EXPECT_TRUE(plan.path.front().position_m.isApprox(world.Robots()[r].position_m));
    EXPECT_TRUE(plan.path.back().position_m.isApprox(plan.tasks[0].position_m));
  }
  const auto d = Diagnostics(*result);
  EXPECT_GT(d.at("frontier_cells"), 0.0);
  EXPECT_GE(d.at("plan_ms"), 0.0);
  EXPECT_FALSE(result->done);
  EXPECT_EQ(result->drawings.size(), 4u);  // a path and a label per robot
  EXPECT_FALSE(result->over_budget);
}

TEST(PluginHost, LoadsByPath) {
  auto planner = LoadPlanner((kDir / "libvoxplan_planner_minimal.so").string());
  ASSERT_TRUE(planner.ok()) << planner.status().message();
  EXPECT_EQ((*planner)->name(), "minimal");
}

TEST(PluginHost, LoadsAPlainCPlanner) {
  auto planner = MustLoad("c_minimal");
  ASSERT_TRUE(planner);
  const test::FakeWorld world;
  auto result = planner->Plan(world, {});
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_TRUE(result->done);
  EXPECT_EQ(Diagnostics(*result).at("robots"), 2.0);
}

TEST(PluginHost, RefusesAnotherAbiVersionNamingBoth) {
  auto planner = LoadPlanner("abi2", Options());
  ASSERT_FALSE(planner.ok());
  EXPECT_EQ(planner.status().code(), StatusCode::kUnsupported);
  EXPECT_TRUE(Contains(planner.status().message(), "built for planner ABI 2"))
      << planner.status().message();
  EXPECT_TRUE(Contains(planner.status().message(), "this voxplan speaks ABI 1"));
}

TEST(PluginHost, RefusesAWrongTableSize) {
  auto planner = LoadPlanner("badsize", Options());
  ASSERT_FALSE(planner.ok());
  EXPECT_EQ(planner.status().code(), StatusCode::kUnsupported);
  const std::string expected = std::to_string(sizeof(vp_planner_api));
  EXPECT_TRUE(Contains(planner.status().message(), "expects " + expected))
      << planner.status().message();
}

TEST(PluginHost, RefusesAModuleWithoutEntrySymbol) {
  auto planner = LoadPlanner("noentry", Options());
  ASSERT_FALSE(planner.ok());
  EXPECT_TRUE(Contains(planner.status().message(), "no vp_planner_entry symbol"))
      << planner.status().message();
}

TEST(PluginHost, RefusesMissingAndNonLibraryFiles) {
  auto missing = LoadPlanner("/nonexistent/libvoxplan_planner_x.so");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);

  test::TempDir dir("planner_host");
  const std::filesystem::path fake = dir / "libvoxplan_planner_text.so";
  std::ofstream(fake) << "not an ELF file\n";
  auto text = LoadPlanner(fake.string());
  ASSERT_FALSE(text.ok());
  EXPECT_EQ(text.status().code(), StatusCode::kInvalidArgument);  // checked before dlopen
  EXPECT_TRUE(Contains(text.status().message(), "not a shared object for this machine"));
}

TEST(PluginHost, UnknownNameListsTheAvailablePlanners) {
  auto planner = LoadPlanner("nosuch", Options());
  ASSERT_FALSE(planner.ok());
  EXPECT_EQ(planner.status().code(), StatusCode::kNotFound);
  const std::string& m = planner.status().message();
  EXPECT_TRUE(Contains(m, "unknown planner 'nosuch'")) << m;
  EXPECT_TRUE(Contains(m, "garbage, goto, minimal, noentry, probe, throwing")) << m;
  const std::vector<std::string> names = AvailablePlanners({kDir});
  EXPECT_EQ(names.front(), "abi1_0");  // sorted
  // A name never becomes a path outside the search path.
  EXPECT_FALSE(LoadPlanner("..", Options()).ok());
}

TEST(PluginHost, SearchPathComesFromTheEnvironmentFirst) {
  ASSERT_EQ(setenv("VOXPLAN_PLANNER_PATH", (kDir.string() + ":/nowhere").c_str(), 1), 0);
  const std::vector<std::filesystem::path> path = DefaultPlannerSearchPath();
  ASSERT_GE(path.size(), 2u);
  EXPECT_EQ(path[0], kDir);
  EXPECT_EQ(path[1], "/nowhere");
  auto planner = LoadPlanner("minimal");
  unsetenv("VOXPLAN_PLANNER_PATH");
  EXPECT_TRUE(planner.ok()) << planner.status().message();
}

TEST(PluginHost, CreateFailureIsReportedWithThePluginsMessage) {
  auto refused = LoadPlanner("minimal", Options(R"({"fail": true})"));
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(Contains(refused.status().message(), "option fail is set"))
      << refused.status().message();
  auto thrown = LoadPlanner("throwing", Options("create"));
  ASSERT_FALSE(thrown.ok());
  EXPECT_TRUE(Contains(thrown.status().message(), "refusing to be created"));
}

TEST(PluginHost, ExceptionsInPlanBecomeStatuses) {
  const test::FakeWorld world;
  auto planner = MustLoad("throwing");
  ASSERT_TRUE(planner);
  for (int i = 0; i < 2; ++i) {  // the instance stays usable after a failure
    auto result = planner->Plan(world, {});
    ASSERT_FALSE(result.ok());
    EXPECT_TRUE(Contains(result.status().message(), "boom in plan")) << result.status().message();
    EXPECT_TRUE(Contains(result.status().message(), "status 6"));
  }
  auto non_std = MustLoad("throwing", "int");
  ASSERT_TRUE(non_std);
  auto result = non_std->Plan(world, {});
  ASSERT_FALSE(result.ok());
  EXPECT_TRUE(Contains(result.status().message(), "unknown exception"));
  // A bad query argument comes back as a host status, which the C++ layer rethrows.
  auto bad_query = MustLoad("throwing", "bad_robot");
  ASSERT_TRUE(bad_query);
  result = bad_query->Plan(world, {});
  ASSERT_FALSE(result.ok());
  EXPECT_TRUE(Contains(result.status().message(), "get_robot failed with status 1"))
      << result.status().message();
}

TEST(PluginHost, GarbageIsRejectedAndLoggedAndTheRestKept) {
  const test::FakeWorld world;
  auto planner = MustLoad("garbage");
  ASSERT_TRUE(planner);
  auto result = planner->Plan(world, {});
  ASSERT_TRUE(result.ok()) << result.status().message();
  const RobotPlan& plan = result->robots[0];
  ASSERT_EQ(plan.tasks.size(), 1u);
  EXPECT_EQ(plan.tasks[0].tag, 1u);
  EXPECT_TRUE(plan.path.empty());  // it held an infinity

  std::map<int, std::string> task_reasons;
  int other = 0;
  for (const Rejection& r : result->rejections) {
    if (r.task >= 0) {
      EXPECT_EQ(r.robot, 0);
      task_reasons[r.task] = r.reason;
    } else {
      ++other;
      if (r.robot == 1) {
        EXPECT_TRUE(Contains(r.reason, "speeds")) << r.reason;
      }
    }
  }
  ASSERT_EQ(task_reasons.size(), 8u);
  EXPECT_TRUE(Contains(task_reasons[0], "non-finite"));
  EXPECT_TRUE(Contains(task_reasons[2], "inside an obstacle"));
  EXPECT_TRUE(Contains(task_reasons[3], "unknown space"));
  EXPECT_TRUE(Contains(task_reasons[4], "too close to an obstacle"));
  EXPECT_TRUE(Contains(task_reasons[5], "unreachable"));
  EXPECT_TRUE(Contains(task_reasons[6], "outside the map bounds"));
  EXPECT_TRUE(Contains(task_reasons[7], "mode 7 unknown"));
  EXPECT_TRUE(Contains(task_reasons[8], "dwell"));
  EXPECT_EQ(other, 4);  // the path, robot 1's speeds, the NaN diagnostic, the NaN drawing
  EXPECT_TRUE(result->robots[1].path.empty());
  EXPECT_FALSE(result->robots[1].path_continuous);
  const auto d = Diagnostics(*result);
  EXPECT_EQ(d.count("energy"), 0u);
  EXPECT_EQ(d.at("iterations"), 3.0);
  EXPECT_TRUE(result->drawings.empty());
  int warnings = 0;
  for (const PlanLogEntry& e : result->log) warnings += e.level == VP_LOG_WARNING;
  EXPECT_EQ(warnings, int(result->rejections.size()));
}

TEST(PluginHost, QueriesReachThePluginUnchanged) {
  test::FakeWorld world;
  auto planner = MustLoad("probe", "{}", 5);
  ASSERT_TRUE(planner);
  PlanRequest request;
  request.event = PlanEvent::kTaskFailed;
  request.event_robot = 1;
  request.call_index = 3;
  request.seed = 77;
  request.time_budget_s = 2.0;
  request.failed_task.tag = 12;
  auto result = planner->Plan(world, request);
  ASSERT_TRUE(result.ok()) << result.status().message();
  const auto d = Diagnostics(*result);
  EXPECT_EQ(d.at("create_seed"), 5.0);
  EXPECT_EQ(d.at("event"), VP_EVENT_TASK_FAILED);
  EXPECT_EQ(d.at("event_robot"), 1.0);
  EXPECT_EQ(d.at("call_index"), 3.0);
  EXPECT_EQ(d.at("call_seed"), 77.0);
  EXPECT_EQ(d.at("budget_s"), 2.0);
  EXPECT_EQ(d.at("failed_tag"), 12.0);
  EXPECT_EQ(d.at("revision"), 42.0);
  EXPECT_FLOAT_EQ(float(d.at("voxel_size_m")), 0.05f);
  EXPECT_FLOAT_EQ(float(d.at("bounds_max_x")), 5.f);
  EXPECT_EQ(d.at("state_0"), VP_VOXEL_OCCUPIED);
  EXPECT_EQ(d.at("state_1"), VP_VOXEL_FREE);
  EXPECT_EQ(d.at("state_2"), VP_VOXEL_UNOBSERVED);
  EXPECT_NEAR(d.at("ray_distance"), 0.85, 0.02);
  EXPECT_EQ(d.at("ray_result"), VP_RAY_SURFACE);
  EXPECT_EQ(d.at("frontier_voxels"), double(world.FrontierVoxels().size()));
  EXPECT_EQ(d.at("surface_voxels"), double(world.SurfaceVoxels().size()));
  EXPECT_NEAR(d.at("surface_normal_norm"), 1.0, 1e-6);
  EXPECT_EQ(d.at("floor_width"), test::FakeWorld::kWidth);
  EXPECT_EQ(d.at("floor_cell_0"), VP_FLOOR_OBSTACLE);
  EXPECT_EQ(d.at("instances"), 1.0);
  EXPECT_EQ(d.at("instance_label_is_chair"), 1.0);
  EXPECT_EQ(d.at("robots"), 2.0);
  EXPECT_EQ(d.at("robot1_id"), 11.0);
  EXPECT_EQ(d.at("robot1_status"), VP_ROBOT_EXECUTING);
  EXPECT_EQ(d.at("robot1_modes"), 2.0);
  EXPECT_EQ(d.at("robot1_queue_tag"), 99.0);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_speed")), 0.2f);
  // Geodesic distances are symmetric, zero on the diagonal, and at least the straight line.
  EXPECT_EQ(d.at("d00"), 0.0);
  EXPECT_TRUE(std::isfinite(d.at("d01")));
  EXPECT_NEAR(d.at("d01"), d.at("d10"), 1e-4);
  const float straight = (world.Robots()[0].position_m - world.Robots()[1].position_m).norm();
  EXPECT_GE(d.at("d01"), straight);
  ASSERT_FALSE(result->log.empty());
  EXPECT_EQ(result->log[0].message, "probe done");
}

// The fake world with the sealed pocket's wall voxels as the chair's (instance 3), its robot 1
// some way into a run, and an arm-mounted reconstructor.
class ChairWorld : public test::FakeWorld {
 public:
  ChairWorld() {
    PlannerRobot& r1 = robots()[1];
    r1.distance_m = 2.5f;
    r1.busy_s = 10.f;
    r1.idle_s = 4.f;
    ScanMode& arm = r1.modes[1];
    arm.mount = CameraMount::kArm;
    arm.camera_height_min_m = 0.4f;
    arm.camera_height_max_m = 1.5f;
    arm.reach_max_m = 0.8f;
    arm.capture_hz = 2.f;
    arm.switch_s = 2.f;
  }
  static bool OnChair(const SurfaceVoxel& v) {
    return v.position.x() > 0.5f && v.position.x() < 1.75f && v.position.y() > 1.5f &&
           v.position.y() < 2.75f;
  }
  std::vector<SurfaceVoxel> SurfaceVoxels() const override {
    std::vector<SurfaceVoxel> v = FakeWorld::SurfaceVoxels();
    for (SurfaceVoxel& s : v) s.instance = OnChair(s) ? 3 : -1;
    return v;
  }
};

TEST(PluginHost, Abi11FieldsAndExtensionsReachThePlugin) {
  ChairWorld world;
  auto planner = MustLoad("probe");
  ASSERT_TRUE(planner);
  auto result = planner->Plan(world, PlanRequest{});
  ASSERT_TRUE(result.ok()) << result.status().message();
  const auto d = Diagnostics(*result);
  EXPECT_FLOAT_EQ(float(d.at("robot1_distance_m")), 2.5f);
  EXPECT_FLOAT_EQ(float(d.at("robot1_busy_s")), 10.f);
  EXPECT_FLOAT_EQ(float(d.at("robot1_idle_s")), 4.f);
  EXPECT_EQ(d.at("reconstructor_mount"), VP_MOUNT_ARM);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_height_max_m")), 1.5f);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_reach_max_m")), 0.8f);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_capture_hz")), 2.f);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_switch_s")), 2.f);
  EXPECT_EQ(d.at("ext_objects_1"), 1.0);
  EXPECT_EQ(d.at("ext_objects_2"), 0.0);
  EXPECT_EQ(d.at("ext_unknown"), 0.0);
  EXPECT_EQ(d.at("ext_null_name"), 0.0);
  // vp.objects: exactly the chair's voxels, in the world's order.
  std::vector<SurfaceVoxel> chair;
  for (const SurfaceVoxel& v : world.SurfaceVoxels()) {
    if (ChairWorld::OnChair(v)) chair.push_back(v);
  }
  ASSERT_GT(chair.size(), 4u);
  EXPECT_EQ(d.at("chair_voxels"), double(chair.size()));
  EXPECT_EQ(d.at("chair_voxels_all_its_own"), 1.0);
  EXPECT_FLOAT_EQ(float(d.at("chair_first_x")), chair[0].position.x());
  EXPECT_EQ(d.at("absent_voxels"), 0.0);
}

TEST(PluginHost, APluginBuiltAgainstAbi10LoadsAndPlans) {
  test::FakeWorld world;
  auto planner = MustLoad("abi1_0");
  ASSERT_TRUE(planner);
  auto result = planner->Plan(world, PlanRequest{});
  ASSERT_TRUE(result.ok()) << result.status().message();
  const auto d = Diagnostics(*result);
  // It sees a larger host table than its own and gets the 1.0 prefix of the grown structs:
  // vp_robot grew by 3 floats, vp_mode_params by 12 four-byte fields.
  EXPECT_EQ(d.at("host_table_size"), double(sizeof(vp_host_api)));
  EXPECT_EQ(d.at("robot_size_asked"), double(sizeof(vp_robot) - 3 * sizeof(float)));
  EXPECT_EQ(d.at("robot_size_written"), d.at("robot_size_asked"));
  EXPECT_EQ(d.at("mode_size_asked"), double(sizeof(vp_mode_params) - 12 * sizeof(float)));
  EXPECT_EQ(d.at("mode_size_written"), d.at("mode_size_asked"));
  const PlannerRobot r0 = world.Robots()[0];  // Robots() returns a copy
  EXPECT_FLOAT_EQ(float(d.at("robot0_x")), r0.position_m.x());
  EXPECT_FLOAT_EQ(float(d.at("robot0_pitch_rate")), r0.camera_pitch_rate_radps);
  EXPECT_FLOAT_EQ(float(d.at("reconstructor_cy")), r0.modes[1].cy);
  // Its task passed validation and reached the plan.
  ASSERT_EQ(result->robots.size(), 2u);
  ASSERT_EQ(result->robots[0].tasks.size(), 1u);
  EXPECT_EQ(result->robots[0].tasks[0].tag, 7u);
  EXPECT_FLOAT_EQ(result->robots[0].tasks[0].position_m.x(), r0.position_m.x());
}

TEST(PluginCppLayer, AMissingOrShortExtensionIsAClearError) {
  // A host table whose get_extension has nothing, then one whose vp.objects table is too short
  // for the struct the plugin was built with.
  vp_host_api host = PlannerHostApi();
  host.get_call_info = [](const vp_world*, vp_call_info*) -> vp_status { return VP_OK; };
  host.get_extension = [](const char*, uint32_t) -> const vp_extension_header* { return nullptr; };
  const vp_world* no_world = nullptr;
  const vp::WorldView view(&host, no_world);
  EXPECT_EQ(view.Extension<vp_objects_ext>(VP_EXT_OBJECTS, 1), nullptr);
  try {
    (void)view.InstanceSurface(3);
    ADD_FAILURE() << "no vp.objects: InstanceSurface must throw";
  } catch (const vp::Error& e) {
    EXPECT_EQ(e.status(), VP_ERROR_NOT_AVAILABLE);
    EXPECT_TRUE(Contains(e.what(), "vp.objects version 1")) << e.what();
  }
  host.get_extension = [](const char*, uint32_t) -> const vp_extension_header* {
    static const vp_extension_header kShort = {sizeof(vp_extension_header), 1};
    return &kShort;
  };
  const vp::WorldView short_view(&host, no_world);
  EXPECT_EQ(short_view.Extension<vp_objects_ext>(VP_EXT_OBJECTS, 1), nullptr);
  // The real host's table is whole.
  const vp_extension_header* real = PlannerHostApi().get_extension(VP_EXT_OBJECTS, 1);
  ASSERT_NE(real, nullptr);
  EXPECT_EQ(real->struct_size, sizeof(vp_objects_ext));
  EXPECT_EQ(real->version, 1u);
  // Every extension this header names is there, whole, at version 1 (and not at 2).
  const std::pair<const char*, uint32_t> tables[] = {{VP_EXT_OBJECTS, sizeof(vp_objects_ext)},
                                                     {VP_EXT_TASK, sizeof(vp_task_ext_table)},
                                                     {VP_EXT_MOTION, sizeof(vp_motion_ext)},
                                                     {VP_EXT_SCHEDULE, sizeof(vp_schedule_ext)}};
  for (const auto& [name, size] : tables) {
    const vp_extension_header* t = PlannerHostApi().get_extension(name, 1);
    ASSERT_NE(t, nullptr) << name;
    EXPECT_EQ(t->struct_size, size) << name;
    EXPECT_EQ(t->version, 1u) << name;
    EXPECT_EQ(PlannerHostApi().get_extension(name, 2), nullptr) << name;
  }
}

TEST(PluginHost, DeterministicForASeed) {
  const test::FakeWorld world;
  const std::string config = R"({"candidates": 6})";
  auto plan = [&](uint64_t create_seed, uint64_t call_seed) {
    auto planner = MustLoad("minimal", config, create_seed);
    PlanRequest request;
    request.seed = call_seed;
    auto result = planner->Plan(world, request);
    EXPECT_TRUE(result.ok());
    std::vector<uint32_t> tags;
    for (const RobotPlan& p : result->robots) {
      for (const PlannerTask& t : p.tasks) tags.push_back(t.tag);
    }
    return tags;
  };
  const std::vector<uint32_t> reference = plan(3, 11);
  ASSERT_EQ(reference.size(), 2u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(plan(3, 11), reference);
  // The seed matters: among a few other seeds some pick other frontier cells.
  bool any_differs = false;
  for (uint64_t seed = 0; seed < 8; ++seed)
    any_differs = any_differs || plan(seed, 11) != reference;
  EXPECT_TRUE(any_differs);
}

TEST(PluginHost, OverBudgetCallsAreFlagged) {
  const test::FakeWorld world;
  auto planner = MustLoad("minimal", R"({"sleep_ms": 30})");
  ASSERT_TRUE(planner);
  PlanRequest request;
  request.time_budget_s = 0.005;
  auto slow = planner->Plan(world, request);
  ASSERT_TRUE(slow.ok());
  EXPECT_TRUE(slow->over_budget);
  EXPECT_GE(slow->elapsed_ms, 30.0);
  ASSERT_FALSE(slow->log.empty());
  EXPECT_TRUE(Contains(slow->log.back().message, "over its budget"));
  EXPECT_EQ(slow->robots[0].tasks.size(), 1u);  // the plan itself is kept
  request.time_budget_s = 0.0;                  // no budget: never over it
  auto unbounded = planner->Plan(world, request);
  ASSERT_TRUE(unbounded.ok());
  EXPECT_FALSE(unbounded->over_budget);
}

// The plugin side of the handshake (planner_cpp.h), called directly.
class Nothing : public vp::Planner {
 public:
  explicit Nothing(const vp::Config&) {}
  void Plan(const vp::WorldView&, vp::PlanOutput&) override {}
};

TEST(PluginCppLayer, EntryRefusesAnotherHostAbiOrAShortHostTable) {
  vp_planner_api api{};
  api.struct_size = sizeof(api);
  EXPECT_EQ(vp::detail::Entry<Nothing>(2, &PlannerHostApi(), &api, "n", "1"),
            VP_ERROR_ABI_MISMATCH);
  EXPECT_EQ(api.abi_version, VP_PLANNER_ABI_VERSION);  // written even on refusal
  vp_host_api short_host = PlannerHostApi();
  short_host.struct_size = sizeof(vp_host_api) - sizeof(void*);
  EXPECT_EQ(vp::detail::Entry<Nothing>(1, &short_host, &api, "n", "1"), VP_ERROR_STRUCT_SIZE);
  // That is a 1.0 host: a plugin that also supports those tests for get_extension first.
  EXPECT_FALSE(VP_HOST_HAS(&short_host, get_extension));
  EXPECT_TRUE(VP_HOST_HAS(&PlannerHostApi(), get_extension));
  // An older host with a shorter planner table gets only the prefix it asked for.
  vp_planner_api prefix{};
  prefix.struct_size = offsetof(vp_planner_api, create);
  EXPECT_EQ(vp::detail::Entry<Nothing>(1, &PlannerHostApi(), &prefix, "n", "1"), VP_OK);
  EXPECT_EQ(prefix.struct_size, offsetof(vp_planner_api, create));
  EXPECT_EQ(prefix.create, nullptr);
  EXPECT_STREQ(prefix.name, "n");
}

}  // namespace
}  // namespace voxplan
