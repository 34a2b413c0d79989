// The demo room: closed, consistently oriented boxes; a smooth trajectory that stays inside the
// room, away from the furniture, and sees every part of it that is not hidden against a wall or
// the floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "eval/visibility.h"
#include "sim/demo_room.h"
#include "sim/raycaster.h"

namespace voxplan {
namespace {

constexpr size_t kTrianglesPerBox = 12;
constexpr int kFrames = kDemoFrames;      // what `voxplan demo` runs
constexpr double kMaxStep_m = 0.1;        // between consecutive frames
constexpr double kMaxStep_rad = 0.2;      // ~11 degrees
constexpr double kWallClearance_m = 0.5;  // camera to any wall
constexpr double kFurnitureClearance_m = 0.3;
constexpr double kPitchLimitDown_rad = 0.8;  // ~46 degrees: never steeper down than this
constexpr double kPitchLimitUp_rad = 0.55;   // ~32 degrees
constexpr double kPitchReachDown_rad = 0.7;  // ~40 degrees: the floor near the path shows
constexpr double kPitchReachUp_rad = 0.45;   // ~26 degrees: the ceiling shows
constexpr double kMinValidFraction = 0.999;  // closed room: every ray hits something
// Exposed surface the trajectory must observe; samples are inset from face edges so contact
// edges (where the sub-pixel visibility test is lenient by design) do not blur the split.
constexpr float kEdgeInset_m = 0.03f;
constexpr double kMinExposedSeen = 0.99;  // of all exposed samples
constexpr double kMinExposedSeenPerFace = 0.9;
constexpr double kMaxHiddenSeen = 0.0;  // contacts: box bottoms, backs, floor under boxes

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
  double lowest_pitch = 0.0, highest_pitch = 0.0;
  for (int i = 0; i < kFrames; ++i) {
    EXPECT_TRUE(poses[i].matrix() == again[i].matrix());
    EXPECT_TRUE(ValidatePoseMatrix(poses[i].matrix()).ok());
    const Eigen::Vector3d p = poses[i].translation();
    EXPECT_LT(std::abs(p.x()), 0.5 * params.size_x_m - kWallClearance_m);
    EXPECT_LT(std::abs(p.y()), 0.5 * params.size_y_m - kWallClearance_m);
    EXPECT_GT(p.z(), kWallClearance_m);
    EXPECT_LT(p.z(), params.height_m - kWallClearance_m);
    EXPECT_NEAR(p.z(), 1.4, 0.11);
    for (const auto& box : furniture)
      EXPECT_GT(box.cast<double>().exteriorDistance(p), kFurnitureClearance_m) << "frame " << i;
    // Pitch within limits; no roll (image x axis level), so image y points down.
    const double pitch_up = std::asin(poses[i].linear()(2, 2));
    EXPECT_GT(pitch_up, -kPitchLimitDown_rad);
    EXPECT_LT(pitch_up, kPitchLimitUp_rad);
    lowest_pitch = std::min(lowest_pitch, pitch_up);
    highest_pitch = std::max(highest_pitch, pitch_up);
    EXPECT_NEAR(poses[i].linear()(2, 0), 0.0, 1e-9);
    EXPECT_LT(poses[i].linear()(2, 1), 0.0);

    const Pose3d& next = poses[(i + 1) % kFrames];
    EXPECT_LT((next.translation() - p).norm(), kMaxStep_m) << "frame " << i;
    EXPECT_LT(Eigen::AngleAxisd(poses[i].linear().transpose() * next.linear()).angle(),
              kMaxStep_rad)
        << "frame " << i;
  }
  // It looks both well down and well up: floor and ceiling both show.
  EXPECT_LT(lowest_pitch, -kPitchReachDown_rad);
  EXPECT_GT(highest_pitch, kPitchReachUp_rad);
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
  // floor, ceiling), furniture box j is part 6 + j; each piece has its own colour.
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
  EXPECT_EQ(furniture_parts.size(), DemoFurnitureBoxes().size());
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
  // All four walls, the floor and the ceiling, and every furniture piece.
  for (size_t part = 0; part < 6; ++part) EXPECT_TRUE(seen.count(part)) << "shell face " << part;
  for (size_t part : furniture_parts) EXPECT_TRUE(seen.count(part)) << "furniture " << part - 6;
}

// Every face of the ground truth, split into exposed surface and contacts (a furniture face on
// a wall or the floor, or the wall or floor under a piece): the trajectory observes nearly all
// exposed surface, and the visibility filter never counts a contact as observable.
TEST(DemoRoom, TrajectoryObservesEveryExposedFace) {
  const DemoRoomParams params;
  const Mesh mesh = BuildDemoRoom(params);
  const auto furniture = DemoFurnitureBoxes(params);
  auto raycaster = MeshRaycaster::Create(mesh);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  VisibilityParams visibility;
  visibility.pose_stride = 2;  // as the demo evaluates
  auto observable = ObservableSurfaceFilter(**raycaster, DemoCamera(),
                                            DemoTrajectory(params, kFrames), visibility);
  ASSERT_TRUE(observable.ok()) << observable.status().message();

  const float hx = 0.5f * params.size_x_m, hy = 0.5f * params.size_y_m;
  constexpr float kOn = 1e-4f;
  enum class Kind { kExposed, kHidden, kBorder };
  // Shell samples under or behind a piece are hidden, those within kEdgeInset_m of its
  // footprint's border are left out; furniture samples on the floor or a wall are hidden.
  auto kind_of = [&](const Eigen::Vector3f& p, size_t box, int normal_axis) {
    if (box > 0)
      return p.z() < kOn || std::abs(p.x()) > hx - kOn || std::abs(p.y()) > hy - kOn
                 ? Kind::kHidden
                 : Kind::kExposed;
    for (const auto& piece : furniture) {
      Eigen::AlignedBox3f inner = piece, outer = piece;
      for (int axis = 0; axis < 3; ++axis) {
        const float margin = axis == normal_axis ? kOn : kEdgeInset_m;
        inner.min()[axis] += axis == normal_axis ? -kOn : margin;
        inner.max()[axis] -= axis == normal_axis ? -kOn : margin;
        outer.min()[axis] -= margin;
        outer.max()[axis] += margin;
      }
      if (inner.contains(p)) return Kind::kHidden;
      if (outer.contains(p)) return Kind::kBorder;
    }
    return Kind::kExposed;
  };
  constexpr int kGrid = 40;
  // The grid points of every face, inset from its edges, then one call of the filter.
  struct Probe {
    size_t face;
    Kind kind;
  };
  std::vector<Eigen::Vector3f> points;
  std::vector<Probe> probes;
  for (size_t face = 0; face < mesh.num_triangles() / 2; ++face) {
    // Faces are quads of two triangles {0, 1, 2}, {0, 2, 3} over four own vertices.
    const auto& tri = mesh.triangles[2 * face];
    const Eigen::Vector3f o = mesh.positions[tri[0]];
    const Eigen::Vector3f e1 = mesh.positions[tri[1]] - o;
    const Eigen::Vector3f e2 = mesh.positions[mesh.triangles[2 * face + 1][2]] - o;
    const float s1 = kEdgeInset_m / e1.norm(), s2 = kEdgeInset_m / e2.norm();
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const float a = s1 + (1.f - 2.f * s1) * (float(i) + 0.5f) / kGrid;
        const float b = s2 + (1.f - 2.f * s2) * (float(j) + 0.5f) / kGrid;
        const Eigen::Vector3f p = o + a * e1 + b * e2;
        points.push_back(p);
        probes.push_back({face, kind_of(p, face / 6, int(face % 6) / 2)});
      }
  }
  const std::vector<uint8_t> seen = (*observable)(points);
  ASSERT_EQ(seen.size(), points.size());
  const size_t faces = mesh.num_triangles() / 2;
  std::vector<size_t> face_exposed(faces, 0), face_seen(faces, 0);
  size_t exposed = 0, exposed_seen = 0, hidden = 0, hidden_seen = 0;
  for (size_t k = 0; k < probes.size(); ++k) {
    if (probes[k].kind == Kind::kHidden) {
      ++hidden;
      hidden_seen += seen[k];
    } else if (probes[k].kind == Kind::kExposed) {
      ++face_exposed[probes[k].face];
      face_seen[probes[k].face] += seen[k];
    }
  }
  for (size_t face = 0; face < faces; ++face) {
    exposed += face_exposed[face];
    exposed_seen += face_seen[face];
    if (face_exposed[face] > 0) {
      EXPECT_GE(double(face_seen[face]) / double(face_exposed[face]), kMinExposedSeenPerFace)
          << "box " << face / 6 << " face " << face % 6;
    }
  }
  ASSERT_GT(exposed, 0u);
  ASSERT_GT(hidden, 0u);
  EXPECT_GE(double(exposed_seen) / double(exposed), kMinExposedSeen);
  EXPECT_LE(double(hidden_seen) / double(hidden), kMaxHiddenSeen);
}

}  // namespace
}  // namespace voxplan
