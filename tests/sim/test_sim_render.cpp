// Simulated datasets: RenderSimDataset -> OpenDataset round trip (poses, intrinsics, depth,
// labels), noise on, and refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "io/dataset.h"
#include "io/image_io.h"
#include "sim/dataset_writer.h"
#include "sim/floor_plan.h"
#include "sim/tour.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

// 16-bit depth at 5000 units per metre: half a unit of rounding.
constexpr float kDepthRounding_m = 0.5f / 5000.f + 1e-6f;
constexpr double kPoseTolerance = 1e-5;  // quaternions written with 9 decimals, metres with 6

void AddBox(World& world, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, uint32_t id) {
  const uint32_t base = uint32_t(world.mesh.positions.size());
  for (int i = 0; i < 8; ++i)
    world.mesh.positions.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                      (i & 4) ? hi.z() : lo.z());
  const std::array<std::array<uint32_t, 3>, 12> tris = {{{0, 2, 3},
                                                         {0, 3, 1},
                                                         {4, 5, 7},
                                                         {4, 7, 6},
                                                         {0, 1, 5},
                                                         {0, 5, 4},
                                                         {2, 6, 7},
                                                         {2, 7, 3},
                                                         {0, 4, 6},
                                                         {0, 6, 2},
                                                         {1, 3, 7},
                                                         {1, 7, 5}}};
  for (const auto& t : tris) {
    world.mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    world.triangle_instance.push_back(id);
  }
  world.instances.push_back({id, id == 1 ? "room" : "box", "test", {}});
}

// A closed 6 x 6 x 3 m room (instance 1) with a box (instance 5) in it.
World RoomWithBox() {
  World world;
  world.name = "room with box";
  AddBox(world, {-3.f, -3.f, 0.f}, {3.f, 3.f, 3.f}, 1);
  AddBox(world, {0.5f, -0.5f, 0.f}, {1.5f, 0.5f, 1.0f}, 5);
  return world;
}

TumTrajectory ThreePoses() {
  TumTrajectory t;
  t.source = "three poses";
  t.timestamps_s = {0.0, 0.1, 0.25};
  for (const auto& [eye, target] :
       {std::pair{Eigen::Vector3f(-2.f, 0.f, 1.2f), Eigen::Vector3f(1.f, 0.f, 0.5f)},
        std::pair{Eigen::Vector3f(-1.5f, -1.5f, 1.4f), Eigen::Vector3f(1.f, 0.f, 0.5f)},
        std::pair{Eigen::Vector3f(-2.f, 2.f, 1.0f), Eigen::Vector3f(1.f, 0.f, 0.5f)}})
    t.T_W_C.push_back(LookAt(eye, target).cast<double>());
  return t;
}

SimDatasetOptions SmallCamera(bool noise) {
  SimDatasetOptions o;
  o.camera = {160, 120, 130.f, 130.f, 79.5f, 59.5f};
  o.noise = noise;
  return o;
}

TEST(SimRender, RoundTripThroughOpenDataset) {
  const World world = RoomWithBox();
  auto raycaster = MeshRaycaster::Create(world);
  ASSERT_TRUE(raycaster.ok());
  test::TempDir dir("simrender");
  const TumTrajectory trajectory = ThreePoses();
  const SimDatasetOptions options = SmallCamera(/*noise=*/false);
  size_t progress = 0;
  auto summary = RenderSimDataset(**raycaster, trajectory, options, dir.path().string(),
                                  [&](size_t done) { progress = done; });
  ASSERT_TRUE(summary.ok()) << summary.status().message();
  EXPECT_EQ(summary->frames, 3u);
  EXPECT_EQ(progress, 3u);
  EXPECT_EQ(summary->valid_depth_fraction, 1.0);  // closed room: every ray hits

  auto ds = OpenDataset(dir.path().string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  const DatasetInfo& info = (*ds)->info();
  EXPECT_EQ(info.format, DatasetFormat::kTum);
  ASSERT_EQ(info.num_frames, 3u);
  EXPECT_EQ(info.camera.width, 160);
  EXPECT_EQ(info.camera.fx, 130.f);
  EXPECT_EQ(info.camera.cy, 59.5f);
  EXPECT_TRUE(info.has_color);
  EXPECT_TRUE(info.warnings.empty()) << info.warnings.front();

  RenderParams labels;
  labels.labels = true;
  labels.max_range_m = options.max_range_m;
  size_t box_pixels = 0;
  for (size_t i = 0; i < 3; ++i) {
    auto frame = (*ds)->Load(i);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    ASSERT_TRUE(frame->T_W_C.has_value());
    EXPECT_NEAR(frame->timestamp, trajectory.timestamps_s[i], 1e-9);
    EXPECT_TRUE(frame->T_W_C->matrix().isApprox(trajectory.T_W_C[i].matrix(), kPoseTolerance)) << i;
    const RenderOutput clean =
        (*raycaster)->Render(options.camera, trajectory.T_W_C[i].cast<float>(), labels);
    for (size_t p = 0; p < clean.depth.data.size(); ++p)
      ASSERT_NEAR(frame->depth.data[p], clean.depth.data[p], kDepthRounding_m) << i << " " << p;
    // Labels: 16-bit ids, read back through the depth reader at scale 1.
    const std::string label_path =
        (dir / "labels" / frame->depth_path.substr(frame->depth_path.size() - 10));
    auto ids = ReadDepthPng(label_path, 1.0);
    ASSERT_TRUE(ids.ok()) << ids.status().message();
    for (size_t p = 0; p < clean.labels.data.size(); ++p) {
      ASSERT_EQ(uint32_t(ids->data[p]), clean.labels.data[p]) << i << " " << p;
      box_pixels += clean.labels.data[p] == 5;
    }
  }
  EXPECT_GT(box_pixels, 1000u);  // the box is in view, labelled 5
}

TEST(SimRender, NoiseChangesDepthDeterministically) {
  const World world = RoomWithBox();
  auto raycaster = MeshRaycaster::Create(world);
  ASSERT_TRUE(raycaster.ok());
  test::TempDir a("simrender"), b("simrender");
  const TumTrajectory trajectory = ThreePoses();
  SimDatasetOptions options = SmallCamera(/*noise=*/true);
  options.noise_params.seed = 11;
  ASSERT_TRUE(RenderSimDataset(**raycaster, trajectory, options, a.path().string()).ok());
  auto summary = RenderSimDataset(**raycaster, trajectory, options, b.path().string());
  ASSERT_TRUE(summary.ok());
  EXPECT_LT(summary->valid_depth_fraction, 1.0);  // edge and grazing dropouts
  EXPECT_GT(summary->valid_depth_fraction, 0.8);
  auto da = ReadDepthPng((a / "depth/000001.png").string(), 5000.0);
  auto db = ReadDepthPng((b / "depth/000001.png").string(), 5000.0);
  ASSERT_TRUE(da.ok() && db.ok());
  EXPECT_EQ(da->data, db->data);
  const RenderOutput clean =
      (*raycaster)->Render(options.camera, trajectory.T_W_C[1].cast<float>(), {});
  size_t differ = 0;
  for (size_t p = 0; p < clean.depth.data.size(); ++p)
    differ += std::abs(da->data[p] - clean.depth.data[p]) > kDepthRounding_m;
  EXPECT_GT(differ, clean.depth.data.size() / 2);
}

TEST(SimRender, RefusesBadTrajectoriesAndOptions) {
  const World world = RoomWithBox();
  auto raycaster = MeshRaycaster::Create(world);
  ASSERT_TRUE(raycaster.ok());
  test::TempDir dir("simrender");
  TumTrajectory t = ThreePoses();
  t.timestamps_s[2] = 0.1;  // repeats the previous one
  auto r = RenderSimDataset(**raycaster, t, SmallCamera(false), dir.path().string());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("three poses: pose 3"), std::string::npos)
      << r.status().message();
  t = ThreePoses();
  t.T_W_C[1].translation().x() = std::nan("");
  r = RenderSimDataset(**raycaster, t, SmallCamera(false), dir.path().string());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("pose 2"), std::string::npos) << r.status().message();
  SimDatasetOptions far = SmallCamera(false);
  far.max_range_m = 20.f;  // beyond 16-bit depth at scale 5000
  EXPECT_FALSE(RenderSimDataset(**raycaster, ThreePoses(), far, dir.path().string()).ok());
  EXPECT_FALSE(
      RenderSimDataset(**raycaster, ThreePoses(), SmallCamera(false), (dir / "missing").string())
          .ok());
  EXPECT_FALSE(fs::exists(dir / "depth.txt"));
}

// Simulate end to end: a two-room world of boxes -> floor plan -> tour -> noisy dataset ->
// OpenDataset, every frame with its pose and mostly valid depth.
TEST(SimRender, TourOfTwoRoomWorldRendersReadableDataset) {
  World world;
  world.name = "two rooms";
  uint32_t id = 1;
  auto box = [&](Eigen::Vector3f lo, Eigen::Vector3f hi) { AddBox(world, lo, hi, id++); };
  box({-0.1f, -0.1f, -0.1f}, {8.1f, 3.1f, 0.f});  // floor
  box({-0.1f, -0.1f, 2.5f}, {8.1f, 3.1f, 2.6f});  // ceiling
  box({-0.1f, -0.1f, 0.f}, {8.1f, 0.f, 2.5f});    // south wall
  box({-0.1f, 3.f, 0.f}, {8.1f, 3.1f, 2.5f});     // north wall
  box({-0.1f, 0.f, 0.f}, {0.f, 3.f, 2.5f});       // west wall
  box({8.f, 0.f, 0.f}, {8.1f, 3.f, 2.5f});        // east wall
  box({3.95f, 0.f, 0.f}, {4.05f, 1.f, 2.5f});     // partition, door at y in [1, 2]
  box({3.95f, 2.f, 0.f}, {4.05f, 3.f, 2.5f});
  box({1.f, 1.f, 0.f}, {1.6f, 1.6f, 0.8f});  // a table in room a
  world.rooms = {{"a", Eigen::AlignedBox2f(Eigen::Vector2f(0, 0), Eigen::Vector2f(4, 3))},
                 {"b", Eigen::AlignedBox2f(Eigen::Vector2f(4, 0), Eigen::Vector2f(8, 3))}};
  auto plan = RasterizeFloorPlan(world);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  TourParams tour_params;
  tour_params.frame_step_m = 0.3f;
  tour_params.frame_step_deg = 30.f;
  auto tour = PlanTour(*plan, world.rooms, tour_params);
  ASSERT_TRUE(tour.ok()) << tour.status().message();
  ASSERT_TRUE(tour->unreachable_rooms.empty());

  TumTrajectory trajectory;
  trajectory.source = "tour";
  trajectory.timestamps_s = tour->timestamps_s;
  for (const Pose3f& T : tour->T_W_C) trajectory.T_W_C.push_back(T.cast<double>());
  auto raycaster = MeshRaycaster::Create(world);
  ASSERT_TRUE(raycaster.ok());
  SimDatasetOptions options;
  options.camera = {80, 60, 60.f, 60.f, 39.5f, 29.5f};
  test::TempDir dir("simtour");
  auto summary = RenderSimDataset(**raycaster, trajectory, options, dir.path().string());
  ASSERT_TRUE(summary.ok()) << summary.status().message();
  EXPECT_GT(summary->valid_depth_fraction, 0.8);

  auto ds = OpenDataset(dir.path().string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_EQ((*ds)->info().num_frames, trajectory.T_W_C.size());
  for (size_t i = 0; i < trajectory.T_W_C.size(); i += 7) {
    auto frame = (*ds)->Load(i);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    ASSERT_TRUE(frame->T_W_C.has_value());
    EXPECT_TRUE(frame->T_W_C->matrix().isApprox(trajectory.T_W_C[i].matrix(), kPoseTolerance));
    size_t valid = 0;
    for (float z : frame->depth.data) valid += z > 0.f;
    EXPECT_GT(valid, frame->depth.data.size() / 2) << i;
  }
}

}  // namespace
}  // namespace voxplan
