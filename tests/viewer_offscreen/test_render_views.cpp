// The render job below the CLI: views of an analytic sphere map (orbit and single pose, image
// sizes, hit fractions) and the all-or-nothing writing of their files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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

}  // namespace
}  // namespace voxplan
