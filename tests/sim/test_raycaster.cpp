// MeshRaycaster against analytic depth (box, plane), colour interpolation and determinism; the
// viewer's cutaway (back faces, a cut height) and the dollhouse that chooses it.
#include <gtest/gtest.h>

#include <cmath>

#include "core/parallel.h"
#include "sim/mesh_scene.h"
#include "sim/raycaster.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

using test::TestCamera;

// Float ray-triangle intersection against the exact analytic depth, a few metres away.
constexpr float kDepthTolerance_m = 1e-4f;
constexpr int kColorTolerance = 1;  // rounding of the interpolated colour

// Closed axis-aligned box, 8 shared vertices, outward counter-clockwise triangles.
Mesh BoxMesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  Mesh mesh;
  for (int i = 0; i < 8; ++i)
    mesh.positions.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                (i & 4) ? hi.z() : lo.z());
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},   // -z, +z
                    {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // -y, +y
                    {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};  // -x, +x
  return mesh;
}

// Square quad in the plane z = z0, x and y in [-half, half], two triangles facing +z.
Mesh QuadMesh(float half, float z0) {
  Mesh mesh;
  mesh.positions = {{-half, -half, z0}, {half, -half, z0}, {half, half, z0}, {-half, half, z0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// A pixel whose 3x3 neighbourhood mixes hits and misses in the reference: the mesh and the
// analytic shape may legitimately disagree there by one pixel.
bool IsSilhouette(const DepthImage& reference, int u, int v) {
  const bool hit = reference.at(u, v) > 0.f;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int uu = u + du, vv = v + dv;
      if (uu < 0 || vv < 0 || uu >= reference.width || vv >= reference.height) continue;
      if ((reference.at(uu, vv) > 0.f) != hit) return true;
    }
  return false;
}

// Compares away from silhouettes; returns the number of pixels compared with a hit.
int ExpectDepthMatches(const DepthImage& rendered, const DepthImage& reference) {
  EXPECT_EQ(rendered.width, reference.width);
  EXPECT_EQ(rendered.height, reference.height);
  int compared_hits = 0;
  for (int v = 0; v < reference.height; ++v)
    for (int u = 0; u < reference.width; ++u) {
      if (IsSilhouette(reference, u, v)) continue;
      const float expected = reference.at(u, v), got = rendered.at(u, v);
      if (expected == 0.f) {
        EXPECT_EQ(got, 0.f) << "pixel " << u << "," << v;
      } else {
        EXPECT_NEAR(got, expected, kDepthTolerance_m) << "pixel " << u << "," << v;
        ++compared_hits;
      }
    }
  return compared_hits;
}

TEST(MeshRaycaster, BoxDepthMatchesAnalytic) {
  const test::Box box{{-0.5f, -0.4f, 0.f}, {0.5f, 0.6f, 1.f}};
  auto raycaster = MeshRaycaster::Create(BoxMesh(box.lo, box.hi));
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const PinholeCamera camera = TestCamera(160, 120);
  for (const Eigen::Vector3f& eye :
       {Eigen::Vector3f(2.5f, 1.5f, 1.8f), Eigen::Vector3f(-2.f, -2.5f, 0.7f),
        Eigen::Vector3f(0.3f, 0.2f, 3.f)}) {
    const Pose3f T_W_C = LookAt(eye, Eigen::Vector3f(0.f, 0.1f, 0.5f));
    const RenderOutput out = (*raycaster)->Render(camera, T_W_C);
    const int hits = ExpectDepthMatches(out.depth, test::RenderDepth(box, camera, T_W_C));
    EXPECT_GT(hits, 1000);
  }
}

TEST(MeshRaycaster, PlaneDepthMatchesAnalytic) {
  auto raycaster = MeshRaycaster::Create(QuadMesh(20.f, 0.f));
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const test::Plane plane{Eigen::Vector3f::UnitZ(), 0.f};
  PinholeCamera camera = TestCamera(160, 120);
  const Pose3f T_W_C = LookAt({0.4f, -0.3f, 2.f}, {1.f, 1.5f, 0.f});
  const RenderOutput out = (*raycaster)->Render(camera, T_W_C);
  EXPECT_EQ(ExpectDepthMatches(out.depth, test::RenderDepth(plane, camera, T_W_C)),
            camera.width * camera.height);

  // A flipped image y axis (ICL-NUIM's fy < 0) must still give positive z depth.
  camera.fy = -camera.fy;
  const RenderOutput flipped = (*raycaster)->Render(camera, T_W_C);
  EXPECT_EQ(ExpectDepthMatches(flipped.depth, test::RenderDepth(plane, camera, T_W_C)),
            camera.width * camera.height);
}

TEST(MeshRaycaster, MaxRangeDropsFarHits) {
  auto raycaster = MeshRaycaster::Create(QuadMesh(20.f, 0.f));
  ASSERT_TRUE(raycaster.ok());
  const PinholeCamera camera = TestCamera(160, 120);
  const Pose3f T_W_C = LookAt({0.f, 0.f, 2.f}, {4.f, 0.f, 0.f});
  const DepthImage full = (*raycaster)->Render(camera, T_W_C).depth;
  RenderParams params;
  params.max_range_m = 4.f;
  const DepthImage capped = (*raycaster)->Render(camera, T_W_C, params).depth;
  int dropped = 0;
  for (size_t i = 0; i < full.data.size(); ++i) {
    if (full.data[i] <= params.max_range_m) {
      EXPECT_EQ(capped.data[i], full.data[i]);
    } else {
      EXPECT_EQ(capped.data[i], 0.f);
      ++dropped;
    }
  }
  EXPECT_GT(dropped, 100);
}

TEST(MeshRaycaster, InterpolatesVertexColours) {
  // Red along x = -1, blue along x = +1: the colour is linear in x, which barycentric
  // interpolation reproduces exactly on both triangles.
  Mesh quad = QuadMesh(1.f, 0.f);
  for (const auto& p : quad.positions)
    quad.colors.push_back(p.x() < 0.f ? std::array<uint8_t, 3>{255, 0, 0}
                                      : std::array<uint8_t, 3>{0, 0, 255});
  auto raycaster = MeshRaycaster::Create(quad);
  ASSERT_TRUE(raycaster.ok());
  const PinholeCamera camera = TestCamera(160, 120);
  const Pose3f T_W_C = LookAt({0.f, 0.f, 2.f}, {0.f, 0.f, 0.f}, Eigen::Vector3f::UnitY());
  const RenderOutput out = (*raycaster)->Render(camera, T_W_C);
  int hits = 0, misses = 0;
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const float z = out.depth.at(u, v);
      const uint32_t c = out.color.at(u, v);
      if (z == 0.f) {
        EXPECT_EQ(c, PackRgb(0, 0, 0));  // black on miss
        ++misses;
        continue;
      }
      ++hits;
      const Eigen::Vector3f p_W = T_W_C * camera.Unproject(float(u), float(v), z);
      const float s = 0.5f * (p_W.x() + 1.f);  // 0 at the red edge, 1 at the blue edge
      EXPECT_NEAR(Red(c), 255.f * (1.f - s), kColorTolerance + 0.5f) << u << "," << v;
      EXPECT_EQ(Green(c), 0);
      EXPECT_NEAR(Blue(c), 255.f * s, kColorTolerance + 0.5f) << u << "," << v;
    }
  EXPECT_GT(hits, 5000);
  EXPECT_GT(misses, 1000);
}

TEST(MeshRaycaster, GreyWithoutColours) {
  auto raycaster = MeshRaycaster::Create(QuadMesh(5.f, 0.f));
  ASSERT_TRUE(raycaster.ok());
  const RenderOutput out = (*raycaster)
                               ->Render(TestCamera(32, 24), LookAt({0.f, 0.f, 1.f}, {0.f, 0.f, 0.f},
                                                                   Eigen::Vector3f::UnitY()));
  for (uint32_t c : out.color.data) EXPECT_EQ(c, PackRgb(180, 180, 180));
}

TEST(MeshRaycaster, DeterministicAcrossThreadCounts) {
  Mesh box = BoxMesh({-0.5f, -0.5f, 0.f}, {0.5f, 0.5f, 1.f});
  for (size_t i = 0; i < box.positions.size(); ++i)
    box.colors.push_back({uint8_t(30 * i), uint8_t(255 - 20 * i), uint8_t(90 + 10 * i)});
  auto raycaster = MeshRaycaster::Create(box);
  ASSERT_TRUE(raycaster.ok());
  const PinholeCamera camera = TestCamera(203, 117);  // sizes not multiples of the tile
  const Pose3f T_W_C = LookAt({2.f, 1.f, 1.5f}, {0.f, 0.f, 0.5f});
  RenderOutput one_thread;
  {
    ThreadLimit limit(1);
    one_thread = (*raycaster)->Render(camera, T_W_C);
  }
  const RenderOutput all_threads = (*raycaster)->Render(camera, T_W_C);
  EXPECT_EQ(one_thread.depth.data, all_threads.depth.data);
  EXPECT_EQ(one_thread.color.data, all_threads.color.data);
}

TEST(MeshRaycaster, RefusesBadMeshes) {
  Mesh bad_index = QuadMesh(1.f, 0.f);
  bad_index.triangles.push_back({0, 1, 7});
  auto r1 = MeshRaycaster::Create(bad_index);
  ASSERT_FALSE(r1.ok());
  EXPECT_EQ(r1.status().code(), StatusCode::kInvalidArgument);

  Mesh bad_colors = QuadMesh(1.f, 0.f);
  bad_colors.colors.resize(2);
  auto r2 = MeshRaycaster::Create(bad_colors);
  ASSERT_FALSE(r2.ok());
  EXPECT_EQ(r2.status().code(), StatusCode::kInvalidArgument);
}

TEST(MeshRaycaster, EmptyMeshRendersNothing) {
  auto raycaster = MeshRaycaster::Create(Mesh{});
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const RenderOutput out = (*raycaster)->Render(TestCamera(16, 12), Pose3f::Identity());
  for (float z : out.depth.data) EXPECT_EQ(z, 0.f);
}

// Two boxes as a World: instance 3 (left) and 7 (right, farther), both of kept triangle order.
World TwoBoxWorld() {
  World world;
  world.name = "two boxes";
  const Mesh a = BoxMesh({-1.2f, -0.5f, 0.f}, {-0.2f, 0.5f, 1.f});
  const Mesh b = BoxMesh({0.4f, 0.5f, 0.f}, {1.4f, 1.5f, 1.5f});
  world.mesh = a;
  for (const auto& t : b.triangles) world.mesh.triangles.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  world.mesh.positions.insert(world.mesh.positions.end(), b.positions.begin(), b.positions.end());
  world.triangle_instance.assign(12, 3);
  world.triangle_instance.resize(24, 7);
  world.instances = {{3, "box", "a", {}}, {7, "box", "b", {}}};
  return world;
}

TEST(MeshRaycaster, LabelsAreInstanceIdsOfTheNearestBox) {
  const World world = TwoBoxWorld();
  auto raycaster = MeshRaycaster::Create(world);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  const test::Box box_a{{-1.2f, -0.5f, 0.f}, {-0.2f, 0.5f, 1.f}};
  const test::Box box_b{{0.4f, 0.5f, 0.f}, {1.4f, 1.5f, 1.5f}};
  const PinholeCamera camera = TestCamera(160, 120);
  RenderParams params;
  params.labels = true;
  params.normals = true;
  for (const Eigen::Vector3f& eye :
       {Eigen::Vector3f(0.f, -4.f, 1.5f), Eigen::Vector3f(3.f, -3.f, 2.f)}) {
    const Pose3f T_W_C = LookAt(eye, Eigen::Vector3f(0.1f, 0.5f, 0.5f));
    const RenderOutput out = (*raycaster)->Render(camera, T_W_C, params);
    ASSERT_EQ(out.labels.width, camera.width);
    const DepthImage da = test::RenderDepth(box_a, camera, T_W_C);
    const DepthImage db = test::RenderDepth(box_b, camera, T_W_C);
    int seen_a = 0, seen_b = 0;
    for (int v = 0; v < camera.height; ++v)
      for (int u = 0; u < camera.width; ++u) {
        if (IsSilhouette(da, u, v) || IsSilhouette(db, u, v)) continue;
        const float za = da.at(u, v), zb = db.at(u, v);
        uint32_t expected = kNoInstance;
        if (za > 0.f && (zb == 0.f || za < zb)) expected = 3;
        if (zb > 0.f && (za == 0.f || zb < za)) expected = 7;
        EXPECT_EQ(out.labels.at(u, v), expected) << u << "," << v;
        seen_a += expected == 3;
        seen_b += expected == 7;
        // Normals: unit, facing the camera, along a world axis (box faces).
        const Eigen::Vector3f n_C = out.normals_C.at(u, v);
        if (expected == kNoInstance) {
          EXPECT_EQ(n_C, Eigen::Vector3f::Zero());
          continue;
        }
        EXPECT_NEAR(n_C.norm(), 1.f, 1e-5f);
        EXPECT_LT(n_C.dot(camera.Unproject(float(u), float(v), 1.f)), 0.f);
        const Eigen::Vector3f n_W = T_W_C.linear() * n_C;
        EXPECT_NEAR(n_W.cwiseAbs().maxCoeff(), 1.f, 1e-5f);
      }
    EXPECT_GT(seen_a, 200);
    EXPECT_GT(seen_b, 200);
  }
  // Without `labels`, no label image; a Mesh-made raycaster labels nothing.
  EXPECT_TRUE((*raycaster)->Render(camera, LookAt({0, -4, 1}, {0, 0, 0.5f})).labels.empty());
  auto bare = MeshRaycaster::Create(world.mesh);
  ASSERT_TRUE(bare.ok());
  const RenderOutput unlabeled = (*bare)->Render(camera, LookAt({0, -4, 1}, {0, 0, 0.5f}), params);
  for (uint32_t id : unlabeled.labels.data) EXPECT_EQ(id, kNoInstance);
}

TEST(MeshRaycaster, RefusesWorldWithoutOneIdPerTriangle) {
  World world = TwoBoxWorld();
  world.triangle_instance.pop_back();
  auto r = MeshRaycaster::Create(world);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("two boxes"), std::string::npos) << r.status().message();
}

// A room as a fused mesh has it: a floor quad at z = 0 facing up and a ceiling quad at z = 2.5
// facing down (both towards the room), 4 m square.
Mesh FusedRoom() {
  Mesh mesh;
  mesh.positions = {{-2, -2, 0},    {2, -2, 0},    {2, 2, 0},    {-2, 2, 0},
                    {-2, -2, 2.5f}, {2, -2, 2.5f}, {2, 2, 2.5f}, {-2, 2, 2.5f}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}};
  return mesh;
}

TEST(MeshRaycaster, CutawayCullsBackFacesAndCutsAboveAHeight) {
  const PinholeCamera camera = TestCamera(32, 24);
  const Pose3f T_W_C = LookAt({0.1f, 0.2f, 6.f}, {0.f, 0.f, 0.f});  // from above, looking down
  const float centre_depth = [&] {
    auto plain = MeshRaycaster::Create(FusedRoom());
    return (*plain)->Render(camera, T_W_C).depth.at(16, 12);
  }();
  EXPECT_NEAR(centre_depth, 3.5f, 0.05f);  // the ceiling's back, 6 - 2.5 m away
  MeshCutaway cull;
  cull.cull_back_faces = true;
  auto culled = MeshRaycaster::Create(FusedRoom(), cull);
  ASSERT_TRUE(culled.ok()) << culled.status().message();
  EXPECT_NEAR((*culled)->Render(camera, T_W_C).depth.at(16, 12), 6.0f, 0.05f);  // the floor
  // The ceiling turned to face up (a closed world's roof): culling keeps it, the cut removes it.
  Mesh roofed = FusedRoom();
  roofed.triangles[2] = {4, 5, 6};
  roofed.triangles[3] = {4, 6, 7};
  auto still_roofed = MeshRaycaster::Create(roofed, cull);
  EXPECT_NEAR((*still_roofed)->Render(camera, T_W_C).depth.at(16, 12), 3.5f, 0.05f);
  MeshCutaway cut = cull;
  cut.cut_above = true;
  cut.max_height_m = 1.5f;
  auto opened = MeshRaycaster::Create(roofed, cut);
  EXPECT_NEAR((*opened)->Render(camera, T_W_C).depth.at(16, 12), 6.0f, 0.05f);
  // The sensors' raycaster (no cutaway) is unchanged: every image as before.
  auto sensor = MeshRaycaster::Create(roofed);
  EXPECT_EQ((*sensor)->Render(camera, T_W_C).depth.data,
            (*MeshRaycaster::Create(roofed, MeshCutaway{}))->Render(camera, T_W_C).depth.data);
}

TEST(MeshScene, DollhouseCutsClosedRoomsAndOnlyCullsFusedOnes) {
  DollhouseParams on;
  on.enabled = true;
  EXPECT_FALSE(DollhouseCutaway(FusedRoom(), DollhouseParams{}).any());
  // Surfaces seen from inside (normals towards the room): culling is enough.
  const MeshCutaway fused = DollhouseCutaway(FusedRoom(), on);
  EXPECT_TRUE(fused.cull_back_faces);
  EXPECT_FALSE(fused.cut_above);
  // A closed box (a world's walls and roof face outwards): cut at 60 % of its height.
  const MeshCutaway closed = DollhouseCutaway(BoxMesh({-2, -2, 0}, {2, 2, 2.5f}), on);
  EXPECT_TRUE(closed.cull_back_faces);
  EXPECT_TRUE(closed.cut_above);
  EXPECT_NEAR(closed.max_height_m, 1.5f, 1e-5f);
}

}  // namespace
}  // namespace voxplan
