// The render job below the CLI: views of an analytic sphere map (orbit and single pose, image
// sizes, hit fractions), orbits framed on a room map's surface whatever stray blocks it holds,
// upright pictures for a y-flipped camera, and the all-or-nothing writing of their files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/parallel.h"
#include "tests/support/test_support.h"
#include "viewer_offscreen/map_scene.h"
#include "viewer_offscreen/render_views.h"
#include "viewer_offscreen/view_files.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 64, kHeight = 48;

const test::Sphere kSphere{Eigen::Vector3f(0.5f, 0.5f, 0.5f), 0.3f};

MapScene SphereScene() {
  return MapScene(
      test::FillExactSdf([](const Eigen::Vector3f& p) { return kSphere.Sdf(p); }, {0.02f, 0.08f},
                         Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones()),
      MapSceneParams{});
}

RenderViewsParams SmallViews() {
  RenderViewsParams params;
  params.width = kWidth;
  params.height = kHeight;
  return params;
}

TEST(RenderViewsTest, OrbitGivesOneImageOfTheRequestedSizePerView) {
  const MapScene scene = SphereScene();
  RenderViewsParams params = SmallViews();
  params.orbit_views = 5;
  Result<RenderedViews> views = RenderViews(scene, params);
  ASSERT_TRUE(views.ok()) << views.status().message();
  EXPECT_EQ(views->T_W_C.size(), 5u);
  ASSERT_EQ(views->images.size(), 5u);
  for (const ColorImage& image : views->images) {
    EXPECT_EQ(image.width, kWidth);
    EXPECT_EQ(image.height, kHeight);
  }
  // Framed on the blocks around the sphere: it is in every view, and does not fill them.
  EXPECT_GT(views->hit_fraction, 0.0);
  EXPECT_LT(views->hit_fraction, 1.0);
  EXPECT_TRUE(views->bounds_W.contains(kSphere.c));
  EXPECT_NEAR((views->framing.centre_W - kSphere.c).norm(), 0.0f, 0.2f);
}

TEST(RenderViewsTest, PoseGivesOneViewAndLookingAwayHitsNothing) {
  const MapScene scene = SphereScene();
  RenderViewsParams params = SmallViews();
  const Eigen::Vector3f eye_W(0.5f, -1.5f, 0.5f);
  params.T_W_C = LookAt(eye_W, kSphere.c);
  Result<RenderedViews> towards = RenderViews(scene, params);
  ASSERT_TRUE(towards.ok()) << towards.status().message();
  ASSERT_EQ(towards->T_W_C.size(), 1u);
  EXPECT_TRUE(towards->T_W_C[0].isApprox(*params.T_W_C));
  EXPECT_GT(towards->hit_fraction, 0.0);

  params.T_W_C = LookAt(eye_W, Eigen::Vector3f(0.5f, -3.0f, 0.5f));
  Result<RenderedViews> away = RenderViews(scene, params);
  ASSERT_TRUE(away.ok()) << away.status().message();
  EXPECT_EQ(away->hit_fraction, 0.0);
}

// Stands in for io's WriteColorPng: a few bytes per file, failing from image `fail_at` on.
PngWriter FakeWriter(size_t fail_at) {
  return [fail_at, count = size_t(0)](const std::string& path, const ColorImage&) mutable {
    if (count++ >= fail_at) return IoError("disk full");
    std::ofstream(path) << "png";
    return Status::Ok();
  };
}

TEST(ViewFilesTest, WritesNumberedFilesIntoANewFolder) {
  const test::TempDir tmp("view_files");
  const std::vector<ColorImage> images(3, ColorImage(2, 2, 0u));
  const std::string dir = (tmp / "a" / "b").string();
  Result<std::vector<std::string>> written = WriteViewFiles(dir, images, FakeWriter(99));
  ASSERT_TRUE(written.ok()) << written.status().message();
  ASSERT_EQ(written->size(), 3u);
  EXPECT_EQ((*written)[2], (fs::path(dir) / "render_002.png").string());
  for (const std::string& path : *written) EXPECT_TRUE(fs::is_regular_file(path)) << path;
}

TEST(ViewFilesTest, FailureRemovesTheFilesAndTheFoldersItMade) {
  const test::TempDir tmp("view_files");
  const std::vector<ColorImage> images(3, ColorImage(2, 2, 0u));
  Result<std::vector<std::string>> written =
      WriteViewFiles((tmp / "a" / "b").string(), images, FakeWriter(2));
  ASSERT_FALSE(written.ok());
  EXPECT_NE(written.status().message().find("render_002.png: disk full"), std::string::npos)
      << written.status().message();
  EXPECT_FALSE(fs::exists(tmp / "a"));
  EXPECT_TRUE(fs::is_directory(tmp.path()));

  // In a folder that was there before, only the files go.
  written = WriteViewFiles(tmp.path().string(), images, FakeWriter(1));
  ASSERT_FALSE(written.ok());
  EXPECT_TRUE(fs::is_directory(tmp.path()));
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

TEST(RenderViewsTest, ChoosingTheSideOrbitsBelowASurfaceSeenOnlyFromBelow) {
  // A slab's underside: the SDF is positive below z = 0.5 and negative above, as a ceiling fused
  // from the room under it.
  const MapScene ceiling(
      test::FillExactSdf([](const Eigen::Vector3f& p) { return 0.5f - p.z(); }, {0.02f, 0.08f},
                         Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones()),
      MapSceneParams{});
  RenderViewsParams params = SmallViews();
  params.orbit_views = 3;
  Result<RenderedViews> above = RenderViews(ceiling, params);
  ASSERT_TRUE(above.ok()) << above.status().message();
  EXPECT_FALSE(above->from_below);
  EXPECT_GT(above->framing.height_m, 0.0f);
  params.choose_side = true;
  Result<RenderedViews> chosen = RenderViews(ceiling, params);
  ASSERT_TRUE(chosen.ok()) << chosen.status().message();
  EXPECT_TRUE(chosen->from_below);
  EXPECT_LT(chosen->framing.height_m, 0.0f);
  EXPECT_GT(chosen->hit_fraction, 2.0 * above->hit_fraction);
  // A sphere looks the same from both sides: above, as without the choice.
  const MapScene sphere = SphereScene();
  Result<RenderedViews> round = RenderViews(sphere, params);
  ASSERT_TRUE(round.ok());
  EXPECT_FALSE(round->from_below);
}

// --- Framing an orbit on a map's surface -------------------------------------------------------

// A 4 x 3 x 2.5 m room fused from inside (the distance is positive in the room: its walls, floor
// and ceiling face into it), 5 cm voxels; with `strays`, blocks far out that a real map collects
// too: three patches of noise surface (20 cm squares, 0.3 % of the room's surface together) and a
// trail of free-space blocks (observed, no surface), up to 14 m away.
constexpr float kRoomVoxel = 0.05f;
const test::Box kRoom{Eigen::Vector3f::Zero(), Eigen::Vector3f(4.f, 3.f, 2.5f)};
// The share of pixels a framed orbit of the room shows it in (measured at 80 x 60: 0.40 with the
// strays, 0.44 without; framed on the block union with the strays, as before, 0.01).
constexpr double kRoomFillsViews = 0.3;

TsdfVolume RoomMap(bool strays) {
  const VolumeParams params{kRoomVoxel, 4 * kRoomVoxel};
  TsdfVolume volume = test::FillExactSdf([](const Eigen::Vector3f& p) { return -kRoom.Sdf(p); },
                                         params, kRoom.lo - Eigen::Vector3f::Constant(0.3f),
                                         kRoom.hi + Eigen::Vector3f::Constant(0.3f));
  if (!strays) return volume;
  const float block_m = volume.block_size_m();
  const auto fill = [&](BlockIndex b, bool surface) {
    TsdfBlock& block = volume.FindOrAllocate(b);
    const float mid_z = BlockOrigin(b, block_m).z() + 0.5f * block_m;
    for (int i = 0; i < kBlockVoxels; ++i) {
      const Eigen::Vector3f c = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), kRoomVoxel);
      const VoxelIndex v = VoxelOfLinear(i);
      const bool patch = surface && v.x < 4 && v.y < 4;  // a 20 cm square of noise
      block.tsdf[i] = EncodeTsdf(patch ? (c.z() - mid_z) / params.trunc_m : 1.0f);
      block.weight[i] = EncodeWeight(1.0f);
    }
  };
  for (const BlockIndex b : {BlockIndex{30, 4, 2}, BlockIndex{-20, 25, 3}, BlockIndex{5, -22, 15}})
    fill(b, true);
  for (int x = 11; x <= 35; ++x) fill({x, 4, 3}, false);
  return volume;
}

// A scene that gives no surface samples, as a mesh: framed on its bounds.
class BoxFramedScene : public SurfaceScene {
 public:
  explicit BoxFramedScene(const SurfaceScene& scene) : scene_(scene) {}
  Eigen::AlignedBox3f Bounds() const override { return scene_.Bounds(); }
  SurfaceImages Render(const PinholeCamera& camera, const Pose3f& T_W_C) const override {
    return scene_.Render(camera, T_W_C);
  }

 private:
  const SurfaceScene& scene_;
};

TEST(RenderViewsTest, AMapsOrbitFramesItsSurfaceNotItsStrayBlocks) {
  const MapScene clean(RoomMap(false), MapSceneParams{});
  const MapScene stray(RoomMap(true), MapSceneParams{});
  EXPECT_GT(stray.Bounds().max().x(), 14.f);  // the blocks reach out
  const std::vector<Eigen::Vector3f> samples = stray.SurfaceSamples();
  ASSERT_FALSE(samples.empty());
  size_t far_out = 0;
  for (const Eigen::Vector3f& p : samples) far_out += std::abs(kRoom.Sdf(p)) > 2 * kRoomVoxel;
  EXPECT_GT(far_out, 0u);
  EXPECT_LT(double(far_out), 0.01 * double(samples.size()));

  RenderViewsParams params = SmallViews();
  params.width = 80;
  params.height = 60;
  params.orbit_views = 8;
  params.choose_side = true;  // as `voxplan render` orbits
  Result<RenderedViews> framed = RenderViews(stray, params);
  Result<RenderedViews> reference = RenderViews(clean, params);
  ASSERT_TRUE(framed.ok() && reference.ok());
  EXPECT_TRUE(framed->surface_framed);
  EXPECT_GT(framed->hit_fraction, kRoomFillsViews);
  EXPECT_GT(reference->hit_fraction, kRoomFillsViews);
  // The strays move the framing little (they take part of the 1 % the framing may leave out,
  // so a little more of the room stays in: 4 % farther).
  EXPECT_LT((framed->framing.centre_W - 0.5f * (kRoom.lo + kRoom.hi)).norm(), 0.1f);
  EXPECT_LT((framed->framing.centre_W - reference->framing.centre_W).norm(), 0.05f);
  EXPECT_NEAR(framed->framing.distance_m, reference->framing.distance_m,
              0.08f * reference->framing.distance_m);
  // Every view holds the room: its outermost bits touch the image border at a few pixels at most
  // (5 of the 276 measured).
  for (const Pose3f& T_W_C : framed->T_W_C) {
    const SurfaceImages s = stray.Render(framed->camera, T_W_C);
    int border = 0, border_hits = 0;
    for (int v = 0; v < s.depth.height; ++v)
      for (int u = 0; u < s.depth.width; ++u)
        if (u == 0 || v == 0 || u == s.depth.width - 1 || v == s.depth.height - 1)
          ++border, border_hits += s.depth.at(u, v) > 0.f;
    EXPECT_LE(border_hits, border / 20);
  }

  // Given numbers win: the orbit the block union framed (FrameBox), which shows the room small.
  const OrbitFraming boxed = FrameBox(stray.Bounds(), CameraFromFov(80, 60, params.fov_deg));
  params.orbit_radius_m = boxed.radius_m;
  params.orbit_height_m = boxed.height_m;
  Result<RenderedViews> given = RenderViews(stray, params);
  ASSERT_TRUE(given.ok());
  EXPECT_EQ(given->framing.radius_m, boxed.radius_m);
  EXPECT_EQ(given->framing.height_m, boxed.height_m);
  EXPECT_LT(given->hit_fraction, 0.1 * framed->hit_fraction);

  // A scene without samples (a mesh) frames its box as it always did.
  params.orbit_radius_m.reset();
  params.orbit_height_m.reset();
  const BoxFramedScene box_framed(stray);
  Result<RenderedViews> mesh_like = RenderViews(box_framed, params);
  ASSERT_TRUE(mesh_like.ok());
  EXPECT_FALSE(mesh_like->surface_framed);
  EXPECT_EQ(mesh_like->framing.radius_m, boxed.radius_m);
  EXPECT_EQ(std::abs(mesh_like->framing.height_m), boxed.height_m);
  EXPECT_EQ(mesh_like->framing.centre_W, boxed.centre_W);
  // A pose renders as given, with nothing framed.
  params = SmallViews();
  params.T_W_C = LookAt(Eigen::Vector3f(2.f, -3.f, 4.f), Eigen::Vector3f(2.f, 1.5f, 0.f));
  Result<RenderedViews> posed = RenderViews(stray, params);
  ASSERT_TRUE(posed.ok());
  EXPECT_FALSE(posed->surface_framed);
  EXPECT_TRUE(posed->T_W_C[0].isApprox(*params.T_W_C));
}

TEST(RenderViewsTest, SurfaceCrossingsAreTheObservedZeroCrossingsThinnedEvenly) {
  const TsdfVolume room = RoomMap(false);
  const std::vector<Eigen::Vector3f> all = SurfaceCrossings(room, 0.5f, 0);
  ASSERT_FALSE(all.empty());
  // Each lies within a voxel of a wall, floor or ceiling.
  for (const Eigen::Vector3f& p : all)
    ASSERT_LT(std::abs(kRoom.Sdf(p)), kRoomVoxel) << p.transpose();
  // Thinned: at most the cap, every k-th, the same for any thread count.
  const std::vector<Eigen::Vector3f> some = SurfaceCrossings(room, 0.5f, 1000);
  EXPECT_LE(some.size(), 1000u);
  EXPECT_GT(some.size(), 500u);
  const size_t k = (all.size() + 999) / 1000;
  for (size_t i = 0; i < some.size(); ++i) ASSERT_EQ(some[i], all[i * k]) << i;
  {
    const ThreadLimit one(1);
    EXPECT_EQ(SurfaceCrossings(room, 0.5f, 1000), some);
  }
  // Voxels below the weight the rays see are not surface.
  EXPECT_TRUE(SurfaceCrossings(room, 2.0f).empty());
}

// --- A y-flipped camera (fy < 0, ICL-NUIM's) ---------------------------------------------------

// Hit pixels in the top and in the bottom half of an image (depth mode: misses are black).
std::pair<int, int> HitsTopBottom(const ColorImage& image) {
  int top = 0, bottom = 0;
  for (int v = 0; v < image.height; ++v)
    for (int u = 0; u < image.width; ++u)
      if (image.at(u, v) != PackRgb(0, 0, 0)) (v < image.height / 2 ? top : bottom) += 1;
  return {top, bottom};
}

bool SameUpToRowFlip(const ColorImage& a, const ColorImage& b) {
  if (a.width != b.width || a.height != b.height) return false;
  for (int v = 0; v < a.height; ++v)
    for (int u = 0; u < a.width; ++u)
      if (a.at(u, v) != b.at(u, a.height - 1 - v)) return false;
  return true;
}

// The sphere at (0.5, 0.5, 0.5) seen from 1.5 m along -x, the optical axis 0.25 m below its
// centre, so that an upright picture (world up +z) shows it in its top half.
constexpr float kBelow = 0.25f;
PinholeCamera Flipped(PinholeCamera camera) {
  camera.fy = -camera.fy;
  return camera;
}

TEST(RenderViewsTest, AYFlippedCameraAtItsOwnPosesIsUprightAsItsFrames) {
  const MapScene scene = SphereScene();
  RenderViewsParams params = SmallViews();
  params.mode = ShadeMode::kDepth;
  // ICL-NUIM's convention: the camera's +y points up (world +z), x = y cross z.
  Pose3f icl = Pose3f::Identity();
  icl.linear().col(1) = Eigen::Vector3f::UnitZ();
  icl.linear().col(2) = Eigen::Vector3f::UnitX();
  icl.linear().col(0) = icl.linear().col(1).cross(icl.linear().col(2));
  icl.translation() = kSphere.c + Eigen::Vector3f(-1.5f, 0.f, -kBelow);
  params.T_W_C = icl;
  const PinholeCamera y_down = CameraFromFov(kWidth, kHeight, 60.f);  // cy at the image centre
  params.camera = Flipped(y_down);
  Result<RenderedViews> flipped = RenderViews(scene, params);
  ASSERT_TRUE(flipped.ok()) << flipped.status().message();
  EXPECT_FALSE(flipped->rows_flipped);  // its top rows look up already
  EXPECT_LT(flipped->camera.fy, 0.f);
  const auto [top, bottom] = HitsTopBottom(flipped->images[0]);
  EXPECT_GT(top, 10 * std::max(bottom, 1)) << top << " " << bottom;  // upright: sphere on top

  // The same pose with a y-down camera: the same picture upside down, row for row.
  params.camera = y_down;
  Result<RenderedViews> y_down_view = RenderViews(scene, params);
  ASSERT_TRUE(y_down_view.ok());
  EXPECT_FALSE(y_down_view->rows_flipped);
  EXPECT_TRUE(SameUpToRowFlip(flipped->images[0], y_down_view->images[0]));
  EXPECT_EQ(y_down_view->hit_fraction, flipped->hit_fraction);
}

TEST(RenderViewsTest, AYFlippedCameraAtUprightPosesRendersItsRowsFlipped) {
  const MapScene scene = SphereScene();
  RenderViewsParams params = SmallViews();
  params.mode = ShadeMode::kNormals;  // world normals: the same colours either way up
  const PinholeCamera y_down = CameraFromFov(kWidth, kHeight, 60.f);
  // A level pose built for a y-down image (LookAt), and an orbit.
  params.T_W_C = LookAt(kSphere.c + Eigen::Vector3f(-1.5f, 0.f, -kBelow),
                        kSphere.c + Eigen::Vector3f(0.f, 0.f, -kBelow));
  for (bool orbit : {false, true}) {
    SCOPED_TRACE(orbit ? "orbit" : "pose");
    if (orbit) {
      params.T_W_C.reset();
      params.orbit_views = 3;
    }
    params.camera = y_down;
    Result<RenderedViews> upright = RenderViews(scene, params);
    params.camera = Flipped(y_down);
    params.camera->cy = 20.f;  // off centre: mirrored to height - 1 - 20 for the flipped rows
    Result<RenderedViews> flipped = RenderViews(scene, params);
    ASSERT_TRUE(upright.ok() && flipped.ok());
    EXPECT_FALSE(upright->rows_flipped);
    EXPECT_TRUE(flipped->rows_flipped);
    EXPECT_EQ(flipped->camera.fy, y_down.fy);
    EXPECT_EQ(flipped->camera.cy, float(kHeight - 1) - 20.f);
    // With the principal point where the flipped camera's rows put it, the same pictures.
    params.camera = y_down;
    params.camera->cy = float(kHeight - 1) - 20.f;
    Result<RenderedViews> same = RenderViews(scene, params);
    ASSERT_TRUE(same.ok());
    ASSERT_EQ(same->images.size(), flipped->images.size());
    for (size_t k = 0; k < same->images.size(); ++k)
      EXPECT_EQ(same->images[k].data, flipped->images[k].data) << k;
  }
  // The flip follows the up axis given: with -z up the level pose is upside down for a y-down
  // camera, and its y-flipped twin keeps its rows.
  params.orbit_views = 1;
  params.T_W_C = LookAt(Eigen::Vector3f(-1.f, 0.5f, 0.5f), kSphere.c);
  params.up_W = -Eigen::Vector3f::UnitZ();
  params.camera = Flipped(y_down);
  Result<RenderedViews> down_up = RenderViews(scene, params);
  ASSERT_TRUE(down_up.ok());
  EXPECT_FALSE(down_up->rows_flipped);
}

TEST(RenderViewsTest, UprightCameraFlipsOnlyAYFlippedCameraWhoseTopLooksDown) {
  const PinholeCamera y_down{64, 48, 50.f, 50.f, 31.5f, 20.f};
  const Pose3f level = LookAt(Eigen::Vector3f(-2.f, 0.f, 0.f), Eigen::Vector3f::Zero());
  bool flipped = true;
  const PinholeCamera same = UprightCamera(y_down, {level}, Eigen::Vector3f::UnitZ(), &flipped);
  EXPECT_FALSE(flipped);
  EXPECT_EQ(same.fy, y_down.fy);
  PinholeCamera y_up = y_down;
  y_up.fy = -50.f;
  const PinholeCamera turned = UprightCamera(y_up, {level}, Eigen::Vector3f::UnitZ(), &flipped);
  EXPECT_TRUE(flipped);
  EXPECT_EQ(turned.fy, 50.f);
  EXPECT_EQ(turned.cy, 27.f);
  EXPECT_EQ(turned.fx, y_up.fx);
  EXPECT_EQ(turned.cx, y_up.cx);
  // Its top looks up when the world's up is -z; no views, no reason to flip.
  UprightCamera(y_up, {level}, -Eigen::Vector3f::UnitZ(), &flipped);
  EXPECT_FALSE(flipped);
  UprightCamera(y_up, {}, Eigen::Vector3f::UnitZ(), &flipped);
  EXPECT_FALSE(flipped);
}

}  // namespace
}  // namespace voxplan
