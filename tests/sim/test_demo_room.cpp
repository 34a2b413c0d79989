// The demo room: closed, consistently oriented boxes; a smooth trajectory that stays inside the
// room, away from the furniture, and sees every part of it.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "sim/demo_room.h"
#include "sim/raycaster.h"

namespace voxplan {
namespace {

constexpr size_t kTrianglesPerBox = 12;
constexpr int kFrames = 120;
constexpr double kMaxStep_m = 0.1;        // between consecutive frames of a 120-frame loop
constexpr double kMaxStep_rad = 0.2;      // ~11 degrees
constexpr double kWallClearance_m = 0.5;  // camera to any wall
constexpr double kFurnitureClearance_m = 0.3;
constexpr double kMinPitch_rad = 0.1;        // ~6 degrees down
constexpr double kMaxPitch_rad = 0.7;        // ~40 degrees down
constexpr double kMinValidFraction = 0.999;  // closed room: every ray hits something

using Key = std::tuple<float, float, float>;
Key KeyOf(const Eigen::Vector3f& p) { return {p.x(), p.y(), p.z()}; }

TEST(DemoRoom, EveryBoxIsClosedAndConsistentlyOriented) {
  const Mesh mesh = BuildDemoRoom();
  const auto furniture = DemoFurnitureBoxes();
  ASSERT_GE(furniture.size(), 4u);
  ASSERT_EQ(mesh.num_triangles(), kTrianglesPerBox * (furniture.size() + 1));
  EXPECT_EQ(mesh.colors.size(), mesh.num_vertices());
  EXPECT_EQ(mesh.normals.size(), mesh.num_vertices());

  for (size_t box = 0; box <= furniture.size(); ++box) {
    // Directed edges by position (faces have their own vertices): in a closed, consistently
    // wound surface each appears once, and its reverse once.
    std::map<std::pair<Key, Key>, int> directed;
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    for (size_t t = box * kTrianglesPerBox; t < (box + 1) * kTrianglesPerBox; ++t)
      for (int k = 0; k < 3; ++k) {
        const auto& a = mesh.positions[mesh.triangles[t][k]];
        const auto& b = mesh.positions[mesh.triangles[t][(k + 1) % 3]];
        ++directed[{KeyOf(a), KeyOf(b)}];
        centre += a / float(3 * kTrianglesPerBox);
      }
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1) << "box " << box;
      const auto reverse = directed.find({edge.second, edge.first});
      EXPECT_TRUE(reverse != directed.end() && reverse->second == 1) << "box " << box;
    }
    // Room shell faces inwards, furniture outwards; stored normals agree with the winding.
    for (size_t t = box * kTrianglesPerBox; t < (box + 1) * kTrianglesPerBox; ++t) {
      const auto& tri = mesh.triangles[t];
      const Eigen::Vector3f a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                            c = mesh.positions[tri[2]];
      const Eigen::Vector3f n = (b - a).cross(c - a).normalized();
      const float outward = n.dot((a + b + c) / 3.f - centre);
      if (box == 0)
        EXPECT_LT(outward, 0.f) << "room triangle " << t;
      else
        EXPECT_GT(outward, 0.f) << "furniture triangle " << t;
      for (uint32_t i : tri) EXPECT_GT(mesh.normals[i].dot(n), 0.999f);
      // Flat colour per face.
      EXPECT_EQ(mesh.colors[tri[0]], mesh.colors[tri[1]]);
      EXPECT_EQ(mesh.colors[tri[0]], mesh.colors[tri[2]]);
    }
  }
  // Floor, ceiling and the four walls each have their own colour.
  std::set<std::array<uint8_t, 3>> shell_colors;
  for (size_t t = 0; t < kTrianglesPerBox; ++t)
    shell_colors.insert(mesh.colors[mesh.triangles[t][0]]);
  EXPECT_EQ(shell_colors.size(), 6u);
}

TEST(DemoRoom, TrajectoryIsDeterministicSmoothAndInside) {
  const DemoRoomParams params;
  const auto poses = DemoTrajectory(params, kFrames);
  ASSERT_EQ(poses.size(), size_t(kFrames));
  const auto again = DemoTrajectory(params, kFrames);
  const auto furniture = DemoFurnitureBoxes(params);
  for (int i = 0; i < kFrames; ++i) {
    EXPECT_TRUE(poses[i].matrix() == again[i].matrix());
    EXPECT_TRUE(ValidatePoseMatrix(poses[i].matrix()).ok());
    const Eigen::Vector3d p = poses[i].translation();
    EXPECT_LT(std::abs(p.x()), 0.5 * params.size_x_m - kWallClearance_m);
    EXPECT_LT(std::abs(p.y()), 0.5 * params.size_y_m - kWallClearance_m);
    EXPECT_GT(p.z(), kWallClearance_m);
    EXPECT_LT(p.z(), params.height_m - kWallClearance_m);
    EXPECT_NEAR(p.z(), 1.4, 0.05);
    for (const auto& box : furniture)
      EXPECT_GT(box.cast<double>().exteriorDistance(p), kFurnitureClearance_m) << "frame " << i;
    // Pitched down, never up; no roll (image x axis level), so image y points down.
    const double pitch_down = std::asin(-poses[i].linear()(2, 2));
    EXPECT_GT(pitch_down, kMinPitch_rad);
    EXPECT_LT(pitch_down, kMaxPitch_rad);
    EXPECT_NEAR(poses[i].linear()(2, 0), 0.0, 1e-9);
    EXPECT_LT(poses[i].linear()(2, 1), 0.0);

    const Pose3d& next = poses[(i + 1) % kFrames];
    EXPECT_LT((next.translation() - p).norm(), kMaxStep_m) << "frame " << i;
    EXPECT_LT(Eigen::AngleAxisd(poses[i].linear().transpose() * next.linear()).angle(),
              kMaxStep_rad)
        << "frame " << i;
  }
  EXPECT_TRUE(DemoTrajectory(params, 0).empty());
}

TEST(DemoRoom, RendersSeeEverythingWithValidDepth) {
  const Mesh mesh = BuildDemoRoom();
  auto raycaster = MeshRaycaster::Create(mesh);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const PinholeCamera camera = DemoCamera();
  EXPECT_EQ(camera.width, 640);
  EXPECT_EQ(camera.height, 480);
  EXPECT_FLOAT_EQ(camera.fx, 525.f);
  EXPECT_FLOAT_EQ(camera.cy, 239.5f);

  // Which part each flat face colour belongs to: shell face k is part k (-x, +x, -y, +y,
  // floor, ceiling), furniture box j is part 6 + j. The table legs share one colour, so they
  // count as the first leg.
  std::map<uint32_t, size_t> part_of_color;
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const auto& c = mesh.colors[mesh.triangles[t][0]];
    const size_t box = t / kTrianglesPerBox;
    part_of_color.emplace(PackRgb(c[0], c[1], c[2]),
                          box == 0 ? (t % kTrianglesPerBox) / 2 : 5 + box);
  }
  std::set<size_t> furniture_parts;
  for (const auto& [color, part] : part_of_color)
    if (part >= 6) furniture_parts.insert(part);
  EXPECT_GE(furniture_parts.size(), 5u);
  std::set<size_t> seen;
  const auto poses = DemoTrajectory({}, kFrames);
  for (int i = 0; i < kFrames; i += 4) {
    const RenderOutput out = (*raycaster)->Render(camera, poses[i].cast<float>());
    size_t valid = 0;
    for (size_t p = 0; p < out.depth.data.size(); ++p) {
      if (out.depth.data[p] > 0.f) {
        ++valid;
        EXPECT_GT(out.depth.data[p], 0.2f);
      }
      const auto it = part_of_color.find(out.color.data[p]);
      if (it != part_of_color.end()) seen.insert(it->second);
    }
    EXPECT_GE(double(valid) / double(out.depth.data.size()), kMinValidFraction) << "frame " << i;
  }
  // All four walls and the floor, and every furniture piece (legs included).
  for (size_t part = 0; part < 5; ++part) EXPECT_TRUE(seen.count(part)) << "shell face " << part;
  for (size_t part : furniture_parts) EXPECT_TRUE(seen.count(part)) << "furniture " << part - 6;
}

}  // namespace
}  // namespace voxplan
