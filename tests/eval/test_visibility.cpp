// ObservableSurfaceFilter on hand-made scenes where what a camera sees is known exactly: a box
// room looked at from one half, and an occluder in front of a wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "eval/visibility.h"
#include "sim/demo_room.h"
#include "sim/raycaster.h"

namespace voxplan {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Twelve triangles of an axis-aligned box; `inward` winds them to face into it (a room).
void AddBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, bool inward, Mesh& mesh) {
  const uint32_t base = uint32_t(mesh.positions.size());
  for (int k = 0; k < 8; ++k)
    mesh.positions.push_back(
        {(k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z()});
  // Outward-facing quads (corner indices), split into two triangles each.
  const std::array<std::array<uint32_t, 4>, 6> quads = {
      {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}};
  for (const auto& q : quads) {
    if (inward) {
      mesh.triangles.push_back({base + q[0], base + q[2], base + q[1]});
      mesh.triangles.push_back({base + q[0], base + q[3], base + q[2]});
    } else {
      mesh.triangles.push_back({base + q[0], base + q[1], base + q[2]});
      mesh.triangles.push_back({base + q[0], base + q[2], base + q[3]});
    }
  }
}

// The room x in [-2, 2], y in [-1, 1], z in [0, 2].
Mesh Room() {
  Mesh mesh;
  AddBox({-2.f, -1.f, 0.f}, {2.f, 1.f, 2.f}, /*inward=*/true, mesh);
  return mesh;
}

// Camera at `p_W` looking horizontally along yaw (0: +x), no roll, OpenCV axes.
Pose3d LookAlong(const Eigen::Vector3d& p_W, double yaw) {
  const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
  Pose3d T_W_C = Pose3d::Identity();
  T_W_C.linear().col(0) = forward.cross(Eigen::Vector3d::UnitZ());
  T_W_C.linear().col(1) = -Eigen::Vector3d::UnitZ();
  T_W_C.linear().col(2) = forward;
  T_W_C.translation() = p_W;
  return T_W_C;
}

// One point at a time through a PointSetFilter (each call renders every pose: tiny scenes only).
struct Seen {
  const PointSetFilter& filter;
  bool operator()(const Eigen::Vector3f& p) const { return filter({p}).at(0) == 1; }
};

TEST(ObservableSurfaceFilter, BoxRoomSeenFromItsPlusXHalf) {
  const Mesh room = Room();
  auto raycaster = MeshRaycaster::Create(room);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  // Cameras in the +x half looking +x and sideways (+-y): nothing of the -x half shows.
  std::vector<Pose3d> poses;
  for (double y : {-0.3, 0.0, 0.3})
    for (double yaw : {0.0, 0.5 * kPi, -0.5 * kPi}) poses.push_back(LookAlong({1.0, y, 1.0}, yaw));
  auto observable = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses);
  ASSERT_TRUE(observable.ok()) << observable.status().message();
  const Seen seen{*observable};

  EXPECT_TRUE(seen({2.f, 0.f, 1.f}));  // +x wall, head-on
  EXPECT_TRUE(seen({2.f, 0.4f, 1.3f}));
  EXPECT_TRUE(seen({1.f, 1.f, 1.f}));  // side walls beside the cameras
  EXPECT_TRUE(seen({1.2f, -1.f, 0.8f}));
  EXPECT_FALSE(seen({-2.f, 0.f, 1.f}));  // the far -x wall
  EXPECT_FALSE(seen({-2.f, 0.9f, 0.2f}));
  EXPECT_FALSE(seen({-1.f, 1.f, 1.f}));   // side walls in the -x half
  EXPECT_FALSE(seen({-1.5f, 0.f, 0.f}));  // floor and ceiling there
  EXPECT_FALSE(seen({-1.5f, 0.f, 2.f}));
  EXPECT_FALSE(seen({1.5f, 0.f, 1.f}));  // inside the room, on no surface: in front of the wall
  EXPECT_FALSE(seen({2.5f, 0.f, 1.f}));  // behind the +x wall
  // A grid over the whole -x half of the shell: none of it counts.
  std::vector<Eigen::Vector3f> far;
  for (float z = 0.1f; z < 2.f; z += 0.2f)
    for (float y = -0.9f; y < 1.f; y += 0.2f) far.emplace_back(-2.f, y, z);
  for (float x = -1.9f; x < -0.2f; x += 0.2f)
    for (float y = -0.9f; y < 1.f; y += 0.2f)
      far.emplace_back(x, y, 0.f), far.emplace_back(x, y, 2.f);
  const std::vector<uint8_t> far_kept = (*observable)(far);
  ASSERT_EQ(far_kept.size(), far.size());
  EXPECT_EQ(std::count(far_kept.begin(), far_kept.end(), uint8_t(1)), 0);
}

TEST(ObservableSurfaceFilter, OccluderHidesWhatIsBehindIt) {
  Mesh scene = Room();
  AddBox({0.9f, -0.2f, 0.8f}, {1.1f, 0.2f, 1.2f}, /*inward=*/false, scene);  // a floating box
  auto raycaster = MeshRaycaster::Create(scene);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const std::vector<Pose3d> poses = {LookAlong({0.0, 0.0, 1.0}, 0.0)};
  auto observable = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses);
  ASSERT_TRUE(observable.ok()) << observable.status().message();
  const Seen seen{*observable};

  EXPECT_TRUE(seen({0.9f, 0.f, 1.f}));   // the occluder's front
  EXPECT_FALSE(seen({1.1f, 0.f, 1.f}));  // its back
  EXPECT_FALSE(seen({2.f, 0.f, 1.f}));   // the wall behind it
  EXPECT_FALSE(seen({2.f, 0.1f, 1.05f}));
  EXPECT_TRUE(seen({2.f, 0.7f, 1.f}));  // the wall beside its shadow
  EXPECT_TRUE(seen({2.f, 0.f, 1.6f}));  // and above it

  // Outside the depth range nothing counts, occluded or not.
  VisibilityParams near_only;
  near_only.max_depth_m = 1.5f;
  auto near = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, near_only);
  ASSERT_TRUE(near.ok());
  EXPECT_TRUE(Seen{*near}({0.9f, 0.f, 1.f}));
  EXPECT_FALSE(Seen{*near}({2.f, 0.7f, 1.f}));
  VisibilityParams far_only;
  far_only.min_depth_m = 1.f;
  auto far = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, far_only);
  ASSERT_TRUE(far.ok());
  EXPECT_FALSE(Seen{*far}({0.9f, 0.f, 1.f}));
  EXPECT_TRUE(Seen{*far}({2.f, 0.7f, 1.f}));
}

TEST(ObservableSurfaceFilter, StrideSkipsPoses) {
  auto raycaster = MeshRaycaster::Create(Room());
  ASSERT_TRUE(raycaster.ok());
  const std::vector<Pose3d> poses = {LookAlong({0.0, 0.0, 1.0}, 0.0),
                                     LookAlong({0.0, 0.0, 1.0}, kPi)};
  VisibilityParams every_other;
  every_other.pose_stride = 2;
  auto first_only = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, every_other);
  auto both = ObservableSurfaceFilter(**raycaster, DemoCamera(), poses);
  ASSERT_TRUE(first_only.ok() && both.ok());
  EXPECT_TRUE(Seen{*first_only}({2.f, 0.f, 1.f}));
  EXPECT_FALSE(Seen{*first_only}({-2.f, 0.f, 1.f}));
  EXPECT_TRUE(Seen{*both}({-2.f, 0.f, 1.f}));
}

TEST(ObservableSurfaceFilter, RefusesBadInput) {
  auto raycaster = MeshRaycaster::Create(Room());
  ASSERT_TRUE(raycaster.ok());
  const std::vector<Pose3d> poses = {LookAlong({0.0, 0.0, 1.0}, 0.0)};
  EXPECT_FALSE(ObservableSurfaceFilter(**raycaster, PinholeCamera{}, poses).ok());
  EXPECT_FALSE(ObservableSurfaceFilter(**raycaster, DemoCamera(), {}).ok());
  VisibilityParams bad;
  bad.pose_stride = 0;
  EXPECT_FALSE(ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, bad).ok());
  bad = {};
  bad.min_depth_m = 2.f;
  bad.max_depth_m = 1.f;
  EXPECT_FALSE(ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, bad).ok());
  bad = {};
  bad.depth_tolerance_m = 0.f;
  EXPECT_FALSE(ObservableSurfaceFilter(**raycaster, DemoCamera(), poses, bad).ok());
  Pose3d nan_pose = poses[0];
  nan_pose.translation().x() = std::nan("");
  const auto refused = ObservableSurfaceFilter(**raycaster, DemoCamera(), {nan_pose});
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace voxplan
