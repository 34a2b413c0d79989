// The simulator's CLI run as a user would: `sim render` of a generated apartment into a dataset
// `fuse` reads and `eval mesh --observable-from` scores; `sim tour` visiting every room of the
// world's room table; `eval objects` and `eval run` on hand-made inputs with known answers; and
// bad input (NaN poses, missing scenes, absurd scales) refused with nothing written.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "io/mesh_io.h"
#include "io/tum_trajectory.h"
#include "sim/scene_loader.h"
#include "sim/world_io.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::RunCli;
using test::RunResult;

constexpr double kExact = 1e-9;           // sums of a few exact steps, printed in full
constexpr double kCopyDistance_m = 1e-5;  // a mesh against an exact copy of itself
constexpr float kCameraHeight_m = 1.2f;

// A small generated apartment (size S, ~0.1 s) in dir/apt; returns its mesh path.
std::string GenerateApartment(const fs::path& dir) {
  const RunResult r = RunCli({"sim", "scene", "--generate", "apartment", "--size", "S", "--seed",
                              "1", "--out", (dir / "apt").string(), "--no-glb"});
  EXPECT_EQ(r.exit_code, 0) << Describe(r);
  return (dir / "apt" / "world.ply").string();
}

// Camera-to-world pose at (x, y, camera height) looking horizontally along world heading
// `yaw_rad`, in OpenCV axes (x right, y down, z forward).
Pose3d LookAlong(double x, double y, double yaw_rad) {
  const Eigen::Vector3d forward(std::cos(yaw_rad), std::sin(yaw_rad), 0.0);
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  Eigen::Matrix3d R;
  R.col(0) = down.cross(forward);  // right = y_C x z_C
  R.col(1) = down;
  R.col(2) = forward;
  Pose3d T = Pose3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(x, y, kCameraHeight_m);
  return T;
}

void WriteTrajectory(const fs::path& path, const std::vector<Pose3d>& poses) {
  std::vector<double> t;
  for (size_t i = 0; i < poses.size(); ++i) t.push_back(double(i) / 30.0);
  ASSERT_TRUE(WriteTumTrajectory(path.string(), t, poses).ok());
}

void WriteText(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

TEST(SimCli, RenderedApartmentIsFusedAndScoredOnItsObservableSurface) {
  const test::TempDir dir("sim_cli_render");
  const std::string scene = GenerateApartment(dir.path());
  Result<World> world = LoadWorld(scene);
  ASSERT_TRUE(world.ok()) << world.status().message();
  ASSERT_FALSE(world->rooms.empty());
  // Three poses at the centre of the first room, turning on the spot.
  const Eigen::Vector2f c = world->rooms[0].footprint_W.center();
  const fs::path trajectory = dir / "traj.txt", dataset = dir / "ds";
  WriteTrajectory(trajectory, {LookAlong(c.x(), c.y(), 0.0), LookAlong(c.x(), c.y(), 0.3),
                               LookAlong(c.x(), c.y(), 0.6)});

  const RunResult render =
      RunCli({"sim", "render", "--scene", scene, "--trajectory", trajectory.string(), "--out",
              dataset.string(), "--size", "80x60", "--fx", "66", "--noise", "off"});
  ASSERT_EQ(render.exit_code, 0) << Describe(render);
  EXPECT_EQ(render.last_json["frames"].get<int>(), 3);
  EXPECT_GT(render.last_json["valid_depth_fraction"].get<double>(), 0.9);  // closed rooms
  for (const char* name :
       {"depth.txt", "rgb.txt", "labels.txt", "groundtruth.txt", "camera.txt", "instances.tsv"})
    EXPECT_TRUE(fs::is_regular_file(dataset / name)) << name;

  const fs::path mesh = dir / "fused.ply";
  const RunResult fuse = RunCli({"fuse", dataset.string(), "--voxel-size", "0.05", "--trunc",
                                 "0.15", "--max-depth", "6", "--mesh", mesh.string()});
  ASSERT_EQ(fuse.exit_code, 0) << Describe(fuse);
  EXPECT_EQ(fuse.last_json["format"], "tum");
  EXPECT_EQ(fuse.last_json["frames"].get<int>(), 3);
  EXPECT_EQ(fuse.last_json["camera"]["fx"].get<double>(), 66.0);  // camera.txt was read
  EXPECT_GT(fuse.last_json["mesh_triangles"].get<int>(), 100);

  // Three views of one room: most of what they see is rebuilt (10 cm, twice the voxel), but
  // they see a small part of the apartment.
  const RunResult eval =
      RunCli({"eval", "mesh", mesh.string(), scene, "--samples-per-m2", "200", "--threshold", "0.1",
              "--observable-from", dataset.string(), "--max-depth", "6"});
  ASSERT_EQ(eval.exit_code, 0) << Describe(eval);
  const nlohmann::json& j = eval.last_json;
  EXPECT_EQ(j["observable_poses"].get<int>(), 3);
  EXPECT_EQ(j["camera"]["width"].get<int>(), 80);
  EXPECT_GT(j["completeness"].get<double>(), 0.8);
  EXPECT_LT(j["observable_fraction"].get<double>(), 0.15);
  EXPECT_LT(j["completeness_full"].get<double>(), j["completeness"].get<double>());
  EXPECT_NEAR(j["observable_area_m2"].get<double>(),
              j["observable_fraction"].get<double>() * j["ground_truth_area_m2"].get<double>(),
              1e-6);
  // The same poses as a trajectory file with the rendered camera give the same answer.
  const RunResult from_file =
      RunCli({"eval", "mesh", mesh.string(), scene, "--samples-per-m2", "200", "--threshold", "0.1",
              "--observable-from", trajectory.string(), "--size", "80x60", "--intrinsics",
              "66,66,39.5,29.5", "--max-depth", "6"});
  ASSERT_EQ(from_file.exit_code, 0) << Describe(from_file);
  EXPECT_EQ(from_file.last_json["completeness"], j["completeness"]);
  EXPECT_EQ(from_file.last_json["observable_fraction"], j["observable_fraction"]);
}

TEST(SimCli, TourVisitsEveryRoomOfTheWorldAndLooksUpAndDown) {
  const test::TempDir dir("sim_cli_tour");
  const std::string scene = GenerateApartment(dir.path());
  Result<World> world = LoadWorld(scene);
  ASSERT_TRUE(world.ok()) << world.status().message();
  const fs::path out = dir / "tour.txt";
  const RunResult r = RunCli({"sim", "tour", "--scene", scene, "--out", out.string(),
                              "--frame-step-deg", "30", "--frame-step", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  EXPECT_EQ(r.last_json["rooms"].get<size_t>(), world->rooms.size());
  EXPECT_TRUE(r.last_json["unreachable_rooms"].empty());
  Result<TumTrajectory> tour = ReadTumTrajectory(out.string());
  ASSERT_TRUE(tour.ok()) << tour.status().message();
  EXPECT_EQ(tour->T_W_C.size(), r.last_json["frames"].get<size_t>());
  for (const Room& room : world->rooms) {
    bool visited = false;
    for (const Pose3d& T : tour->T_W_C)
      visited |= room.footprint_W.contains(T.translation().head<2>().cast<float>());
    EXPECT_TRUE(visited) << room.name;
  }
  // The spins tilt the camera by the default ±45°: its optical axis climbs and sinks that far.
  double max_up_deg = 0.0, max_down_deg = 0.0;
  for (const Pose3d& T : tour->T_W_C) {
    const double elevation_deg = std::asin(T.linear()(2, 2)) * 180.0 / std::numbers::pi;
    max_up_deg = std::max(max_up_deg, elevation_deg);
    max_down_deg = std::max(max_down_deg, -elevation_deg);
  }
  EXPECT_NEAR(max_up_deg, 45.0, 1e-3);
  EXPECT_NEAR(max_down_deg, 45.0, 1e-3);
}

// Axis-aligned box [lo, hi] as 12 triangles appended to `world`, labelled `id`.
void AddBox(World* world, uint32_t id, const std::string& class_name, const Eigen::Vector3f& lo,
            const Eigen::Vector3f& hi) {
  Mesh& mesh = world->mesh;
  const uint32_t base = uint32_t(mesh.positions.size());
  for (int i = 0; i < 8; ++i)
    mesh.positions.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                                i & 4 ? hi.z() : lo.z());
  const std::array<std::array<uint32_t, 4>, 6> quads = {
      {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}};
  for (const auto& q : quads) {
    mesh.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    mesh.triangles.push_back({base + q[0], base + q[2], base + q[3]});
    world->triangle_instance.insert(world->triangle_instance.end(), 2, id);
  }
  Instance instance;
  instance.id = id;
  instance.class_name = class_name;
  instance.model = class_name + "_box";
  instance.bounds_W = Eigen::AlignedBox3f(lo, hi);
  world->instances.push_back(instance);
}

TEST(SimCli, EvalObjectsScoresAnExactCopyOfOneOfTwoObjects) {
  const test::TempDir dir("sim_cli_objects");
  // A floor slab (structure, not an object), a chair-sized and a table-sized box 2 m apart.
  World world;
  world.name = "two_boxes";
  AddBox(&world, 1, "floor", {-1.f, -1.f, -0.1f}, {4.f, 2.f, 0.f});
  AddBox(&world, 2, "chair", {0.f, 0.f, 0.f}, {0.5f, 0.5f, 0.9f});
  AddBox(&world, 3, "table", {2.5f, 0.f, 0.f}, {3.5f, 1.f, 0.75f});
  WorldWriteOptions write;
  write.write_glb = false;
  write.write_floor_plan = false;
  fs::create_directory(dir / "world");
  ASSERT_TRUE(WriteWorld(world, (dir / "world").string(), write).ok());
  // The reconstruction: the chair alone, exactly.
  World chair;
  AddBox(&chair, 2, "chair", {0.f, 0.f, 0.f}, {0.5f, 0.5f, 0.9f});
  const fs::path recon = dir / "chair.ply";
  ASSERT_TRUE(WriteMesh(chair.mesh, recon.string()).ok());

  const RunResult r = RunCli({"eval", "objects", recon.string(), "--scene",
                              (dir / "world" / "world.ply").string(), "--samples-per-m2", "2000"});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const nlohmann::json& j = r.last_json;
  EXPECT_EQ(j["objects_evaluated"].get<int>(), 2);  // the floor is excluded
  EXPECT_EQ(j["objects_reconstructed"].get<int>(), 1);
  ASSERT_EQ(j["objects"].size(), 2u);
  EXPECT_EQ(j["objects"][0]["class"], "chair");
  EXPECT_DOUBLE_EQ(j["objects"][0]["completeness"].get<double>(), 1.0);
  EXPECT_LT(j["objects"][0]["accuracy_mean_m"].get<double>(), kCopyDistance_m);
  EXPECT_EQ(j["objects"][1]["class"], "table");
  EXPECT_DOUBLE_EQ(j["objects"][1]["completeness"].get<double>(), 0.0);
  EXPECT_TRUE(j["objects"][1]["accuracy_mean_m"].is_null());
  EXPECT_DOUBLE_EQ(j["o_comp"].get<double>(), 0.5);
  EXPECT_LT(j["o_rms_m"].get<double>(), kCopyDistance_m);
}

TEST(SimCli, EvalRunGivesExactDistancesBalanceAndIdleTime) {
  const test::TempDir dir("sim_cli_run");
  // r0 drives 10 m along x in 10 s; r1 drives 4 m along y in 4 s, then waits 6 s.
  std::string log = "# two robots\nt,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode\n";
  for (int t = 0; t <= 10; ++t) {
    log += std::to_string(t) + ",r0," + std::to_string(t) + ",0,0,0,0,busy,explorer\n";
    log += std::to_string(t) + ",r1,0," + std::to_string(std::min(t, 4) + 1) + ",0,0,0," +
           (t >= 4 ? "idle" : "busy") + ",reconstructor\n";
  }
  const fs::path path = dir / "run.csv", csv = dir / "series.csv";
  WriteText(path, log);
  const RunResult r =
      RunCli({"eval", "run", path.string(), "--floor-area", "7", "--csv", csv.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const nlohmann::json& j = r.last_json;
  EXPECT_NEAR(j["distance_per_robot_m"]["r0"].get<double>(), 10.0, kExact);
  EXPECT_NEAR(j["distance_per_robot_m"]["r1"].get<double>(), 4.0, kExact);
  EXPECT_NEAR(j["distance_total_m"].get<double>(), 14.0, kExact);
  EXPECT_NEAR(j["distance_per_area"].get<double>(), 2.0, kExact);
  EXPECT_NEAR(j["load_balance_cov"].get<double>(), 3.0 / 7.0, kExact);  // std 3, mean 7
  EXPECT_NEAR(j["time_s"].get<double>(), 10.0, kExact);
  EXPECT_NEAR(j["idle_time_s"]["r1"].get<double>(), 6.0, kExact);
  EXPECT_NEAR(j["time_load_balance"].get<double>(), 0.3, kExact);  // 6 s of 2 x 10 s
  EXPECT_TRUE(fs::is_regular_file(csv));
}

TEST(SimCli, BadInputIsRefusedAndNothingIsWritten) {
  const test::TempDir dir("sim_cli_bad");
  const std::string scene = GenerateApartment(dir.path());
  const fs::path good = dir / "good.txt", nan = dir / "nan.txt";
  WriteTrajectory(good, {LookAlong(2.0, 2.0, 0.0)});
  WriteText(nan, "0 1 1 1.2 0 0 0 1\n0.1 1 nan 1.2 0 0 0 1\n");
  const std::string out = (dir / "out").string();
  const std::string tour = (dir / "tour.txt").string();
  struct Case {
    std::vector<std::string> args;
    std::string message;  // part of the expected error
  };
  const std::vector<Case> cases = {
      {{"sim", "render", "--scene", scene, "--trajectory", nan.string(), "--out", out}, "nan.txt"},
      {{"sim", "render", "--scene", (dir / "none.ply").string(), "--trajectory", good.string(),
        "--out", out},
       "none.ply"},
      {{"sim", "render", "--scene", scene, "--scale", "1000", "--trajectory", good.string(),
        "--out", out},
       "world.ply"},
      {{"sim", "tour", "--scene", (dir / "none.ply").string(), "--out", tour}, "none.ply"},
      {{"sim", "tour", "--scene", scene, "--scale", "1000", "--out", tour}, "world.ply"},
      {{"sim", "tour", "--scene", scene, "--spin-pitches", "0,80", "--out", tour}, "pitch"},
      {{"eval", "mesh", scene, scene, "--observable-from", nan.string()}, "nan.txt"},
  };
  for (const Case& c : cases) {
    const RunResult r = RunCli(c.args);
    EXPECT_NE(r.exit_code, 0) << Describe(r);
    EXPECT_NE(r.err.find("error:"), std::string::npos) << Describe(r);
    EXPECT_NE(r.err.find(c.message), std::string::npos) << Describe(r);
    EXPECT_TRUE(r.out.empty() || r.last_json.is_null()) << Describe(r);
    EXPECT_FALSE(fs::exists(out)) << Describe(r);
    EXPECT_FALSE(fs::exists(tour)) << Describe(r);
  }
}

}  // namespace
}  // namespace voxplan
