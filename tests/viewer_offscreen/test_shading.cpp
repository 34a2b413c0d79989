// The offscreen viewer against an analytic sphere: silhouette size, normals facing the camera,
// shading falling off toward the rim, background outside; the depth colour map and orbits.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "tests/support/test_support.h"
#include "viewer_offscreen/orbit.h"
#include "viewer_offscreen/shading.h"

namespace voxplan {
namespace {

// Odd sizes put the principal point on a pixel centre.
constexpr int kWidth = 201, kHeight = 151;
constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kSilhouetteTolPx = 1.5f;
constexpr float kNormalTolDeg = 4.0f;

float Luma(uint32_t c) { return 0.2126f * Red(c) + 0.7152f * Green(c) + 0.0722f * Blue(c); }

struct SphereScene {
  test::Sphere sphere{Eigen::Vector3f(1.0f, 2.0f, 0.5f), 0.5f};
  PinholeCamera camera = CameraFromFov(kWidth, kHeight, 60.0f);
  Eigen::Vector3f eye_W{1.0f + 1.2f, 2.0f - 1.0f, 0.5f + 0.8f};
  Pose3f T_W_C = LookAt(eye_W, sphere.c);
  SurfaceImages surface;  // analytic depth, vertices and normals

  SphereScene() {
    surface.depth = test::RenderDepth(sphere, camera, T_W_C);
    surface.vertex_W = VerticesFromDepth(surface.depth, camera, T_W_C);
    surface.normal_W =
        Image<Eigen::Vector3f>(kWidth, kHeight, Eigen::Vector3f::Constant(std::nanf("")));
    for (size_t i = 0; i < surface.depth.data.size(); ++i) {
      if (surface.depth.data[i] > 0.0f)
        surface.normal_W.data[i] = (surface.vertex_W.data[i] - sphere.c).normalized();
    }
  }
  int cu() const { return int(camera.cx); }
  int cv() const { return int(camera.cy); }
  float DistancePx(int u, int v) const {
    return std::hypot(float(u) - camera.cx, float(v) - camera.cy);
  }
  // The silhouette's radius in pixels: the sphere's angular radius asin(r / D), seen by a
  // pinhole with focal length fx, along the row through the principal point.
  float SilhouetteRadiusPx() const {
    const float D = (eye_W - sphere.c).norm();
    return camera.fx * sphere.r / std::sqrt(D * D - sphere.r * sphere.r);
  }
};

TEST(ShadingTest, ShadedSphereSilhouetteCentreAndFalloff) {
  const SphereScene s;
  const ShadeParams params;
  Result<ColorImage> image = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kShaded, params);
  ASSERT_TRUE(image.ok()) << image.status().message();
  const ColorImage& rgb = *image;
  ASSERT_EQ(rgb.width, kWidth);
  ASSERT_EQ(rgb.height, kHeight);

  // Silhouette along the centre row.
  int hits = 0;
  for (int u = 0; u < kWidth; ++u) hits += rgb.at(u, s.cv()) != params.background ? 1 : 0;
  EXPECT_NEAR(0.5f * float(hits), s.SilhouetteRadiusPx(), kSilhouetteTolPx);
  // Everything well outside is background, everything well inside is surface.
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const float d = s.DistancePx(u, v);
      if (d > s.SilhouetteRadiusPx() + 2.0f) {
        ASSERT_EQ(rgb.at(u, v), params.background) << u << "," << v;
      }
      if (d < s.SilhouetteRadiusPx() - 2.0f) {
        ASSERT_NE(rgb.at(u, v), params.background) << u << "," << v;
      }
    }
  }
  // The headlight meets the centre head-on: brightest there (neutral grey * (ambient +
  // diffuse) + full specular), dimming monotonically toward the rim.
  const float centre = Luma(rgb.at(s.cu(), s.cv()));
  const float expected =
      Red(params.neutral) * (params.ambient + params.diffuse) + 255.0f * params.specular;
  EXPECT_NEAR(centre, std::min(expected, 255.0f), 1.5f);
  float previous = centre;
  const int rim = int(s.SilhouetteRadiusPx()) - 1;
  for (int du = 1; du <= rim; ++du) {
    const float l = Luma(rgb.at(s.cu() + du, s.cv()));
    EXPECT_LE(l, previous + 1.0f) << "at +" << du << " px";
    previous = l;
  }
  EXPECT_LT(Luma(rgb.at(s.cu() + rim, s.cv())), 0.6f * centre);
}

TEST(ShadingTest, NormalsModeCentreFacesTheCamera) {
  const SphereScene s;
  Result<ColorImage> image = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kNormals);
  ASSERT_TRUE(image.ok());
  const uint32_t c = image->at(s.cu(), s.cv());
  const Eigen::Vector3f n_W =
      Eigen::Vector3f(Red(c), Green(c), Blue(c)) / 255.0f * 2.0f - Eigen::Vector3f::Ones();
  const Eigen::Vector3f to_eye = (s.eye_W - s.sphere.c).normalized();
  EXPECT_GT(n_W.normalized().dot(to_eye), 0.999f) << n_W.transpose();
  EXPECT_EQ(image->at(0, 0), ShadeParams{}.background);
}

TEST(ShadingTest, NormalsFromDepthMatchTheSphere) {
  const SphereScene s;
  const Image<Eigen::Vector3f> normal_W = NormalsFromVertices(s.surface.vertex_W, s.eye_W);
  int checked = 0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      // Near the rim the surface turns away and neighbour differences get long.
      if (s.DistancePx(u, v) > 0.8f * s.SilhouetteRadiusPx()) continue;
      const Eigen::Vector3f& n = normal_W.at(u, v);
      ASSERT_TRUE(n.allFinite()) << u << "," << v;
      const float cos_angle = n.dot(s.surface.normal_W.at(u, v));
      EXPECT_GT(cos_angle, std::cos(kNormalTolDeg * kPi / 180.0f)) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_FALSE(normal_W.at(0, 0).allFinite());  // background stays unknown
}

TEST(ShadingTest, DepthOnlyInputShadesLikeTheAnalyticNormals) {
  // The mesh path: only depth (and colour) known; vertices and normals computed.
  const SphereScene s;
  SurfaceImages depth_only;
  depth_only.depth = s.surface.depth;
  Result<ColorImage> computed = Shade(depth_only, s.camera, s.T_W_C, ShadeMode::kShaded);
  Result<ColorImage> analytic = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kShaded);
  ASSERT_TRUE(computed.ok() && analytic.ok());
  double sum = 0.0;
  int n = 0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      if (s.DistancePx(u, v) > 0.8f * s.SilhouetteRadiusPx()) continue;
      sum += std::abs(Luma(computed->at(u, v)) - Luma(analytic->at(u, v)));
      ++n;
    }
  }
  EXPECT_LT(sum / n, 4.0);  // grey levels
}

TEST(ShadingTest, ColourModeUsesSurfaceColourElseNeutral) {
  SphereScene s;
  const ShadeParams params;
  Result<ColorImage> grey = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kColour, params);
  ASSERT_TRUE(grey.ok());
  EXPECT_EQ(grey->at(s.cu(), s.cv()), params.neutral);
  EXPECT_EQ(grey->at(0, 0), params.background);

  s.surface.color = ColorImage(kWidth, kHeight, PackRgb(10, 200, 30));
  Result<ColorImage> green = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kColour, params);
  ASSERT_TRUE(green.ok());
  EXPECT_EQ(green->at(s.cu(), s.cv()), PackRgb(10, 200, 30));
  EXPECT_EQ(green->at(0, 0), params.background);
  // Shaded modulates the colour: green stays dominant.
  Result<ColorImage> lit = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kShaded, params);
  ASSERT_TRUE(lit.ok());
  const uint32_t c = lit->at(s.cu() + 20, s.cv() + 10);
  EXPECT_GT(Green(c), Red(c) + 50);
  EXPECT_GT(Green(c), Blue(c) + 50);
}

TEST(ShadingTest, RefusesMismatchedSizes) {
  SphereScene s;
  s.surface.color = ColorImage(10, 10);
  EXPECT_FALSE(Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kShaded).ok());
  SurfaceImages empty;
  EXPECT_FALSE(Shade(empty, s.camera, s.T_W_C, ShadeMode::kDepth).ok());
  PinholeCamera other = s.camera;
  other.width = 100;
  EXPECT_FALSE(Shade(SphereScene().surface, other, s.T_W_C, ShadeMode::kDepth).ok());
}

TEST(ShadingTest, ViridisIsMonotonicAndDistinct) {
  EXPECT_EQ(ViridisColor(0.0f), PackRgb(0x44, 0x01, 0x54));
  EXPECT_EQ(ViridisColor(1.0f), PackRgb(0xFD, 0xE7, 0x25));
  EXPECT_EQ(ViridisColor(-3.0f), ViridisColor(0.0f));  // clamped
  EXPECT_EQ(ViridisColor(7.0f), ViridisColor(1.0f));
  std::set<uint32_t> distinct;
  float previous = -1.0f;
  constexpr int kSteps = 64;
  for (int i = 0; i <= kSteps; ++i) {
    const uint32_t c = ViridisColor(float(i) / kSteps);
    EXPECT_GT(Luma(c), previous) << "step " << i;  // lightness rises: readable in grey too
    previous = Luma(c);
    distinct.insert(c);
  }
  EXPECT_EQ(distinct.size(), size_t(kSteps + 1));
}

TEST(ShadingTest, DepthModeNearIsBrightMissesAreBlack) {
  const SphereScene s;
  Result<ColorImage> image = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kDepth);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image->at(0, 0), PackRgb(0, 0, 0));
  // The centre is the nearest point of the sphere, the rim the farthest.
  const int rim = int(s.SilhouetteRadiusPx()) - 1;
  EXPECT_GT(Luma(image->at(s.cu(), s.cv())), Luma(image->at(s.cu() + rim, s.cv())) + 100.0f);
  // A fixed range: depth at the far end maps to the dark end of the map.
  ShadeParams fixed;
  fixed.depth_near_m = 0.1f;
  fixed.depth_far_m = 100.0f;
  Result<ColorImage> far = Shade(s.surface, s.camera, s.T_W_C, ShadeMode::kDepth, fixed);
  ASSERT_TRUE(far.ok());
  EXPECT_GT(Luma(far->at(s.cu(), s.cv())), 200.0f);  // 1.5 m of 100 m: near the bright end
}

TEST(ShadingTest, ParsesModes) {
  EXPECT_EQ(*ParseShadeMode("shaded"), ShadeMode::kShaded);
  EXPECT_EQ(*ParseShadeMode("normals"), ShadeMode::kNormals);
  EXPECT_EQ(*ParseShadeMode("colour"), ShadeMode::kColour);
  EXPECT_EQ(*ParseShadeMode("color"), ShadeMode::kColour);
  EXPECT_EQ(*ParseShadeMode("depth"), ShadeMode::kDepth);
  EXPECT_FALSE(ParseShadeMode("wireframe").ok());
  for (ShadeMode m :
       {ShadeMode::kShaded, ShadeMode::kNormals, ShadeMode::kColour, ShadeMode::kDepth})
    EXPECT_EQ(*ParseShadeMode(ShadeModeName(m)), m);
}

TEST(OrbitTest, PosesLookAtTheCentreFromTheCircle) {
  const Eigen::Vector3f centre(1.0f, -2.0f, 0.5f);
  const float radius = 3.0f, height = 1.5f;
  const PinholeCamera camera = CameraFromFov(kWidth, kHeight, 60.0f);
  const std::vector<Pose3f> poses = OrbitPoses(centre, radius, height, 8);
  ASSERT_EQ(poses.size(), 8u);
  for (size_t k = 0; k < poses.size(); ++k) {
    const Pose3f& T_W_C = poses[k];
    const Eigen::Matrix3f R = T_W_C.linear();
    EXPECT_TRUE((R.transpose() * R).isIdentity(1e-5f));
    EXPECT_NEAR(R.determinant(), 1.0f, 1e-5f);
    const Eigen::Vector3f eye = T_W_C.translation();
    EXPECT_NEAR(eye.z() - centre.z(), height, 1e-5f);
    EXPECT_NEAR((eye - centre).head<2>().norm(), radius, 1e-5f);
    const float angle = std::atan2(eye.y() - centre.y(), eye.x() - centre.x());
    EXPECT_NEAR(std::remainder(angle - float(k) * kPi / 4.0f, 2.0f * kPi), 0.0f, 1e-5f);
    // The centre sits on the optical axis, in front, at the principal point.
    const Eigen::Vector3f centre_C = T_W_C.inverse() * centre;
    EXPECT_GT(centre_C.z(), 0.0f);
    const Eigen::Vector2f px = camera.Project(centre_C);
    EXPECT_NEAR(px.x(), camera.cx, 1e-3f);
    EXPECT_NEAR(px.y(), camera.cy, 1e-3f);
    // Upright: image x horizontal, image y (down) pointing down in the world.
    EXPECT_NEAR(R.col(0).z(), 0.0f, 1e-6f);
    EXPECT_LT(R.col(1).z(), 0.0f);
  }
}

TEST(OrbitTest, YUpOrbitCirclesTheYAxisUpright) {
  const Eigen::Vector3f centre(0.5f, 1.0f, -2.0f);
  for (const Pose3f& T_W_C : OrbitPoses(centre, 2.0f, 1.0f, 5, Eigen::Vector3f::UnitY())) {
    const Eigen::Vector3f offset = T_W_C.translation() - centre;
    EXPECT_NEAR(offset.y(), 1.0f, 1e-5f);
    EXPECT_NEAR(std::hypot(offset.x(), offset.z()), 2.0f, 1e-5f);
    EXPECT_NEAR(T_W_C.linear().col(0).y(), 0.0f, 1e-6f);  // image x horizontal
    EXPECT_LT(T_W_C.linear().col(1).y(), 0.0f);           // image down is world down
    EXPECT_NEAR(T_W_C.linear().determinant(), 1.0f, 1e-5f);
    EXPECT_TRUE((T_W_C.inverse() * centre).head<2>().isZero(1e-5f));
  }
}

TEST(OrbitTest, LookAtStraightDownStaysValid) {
  const Pose3f T_W_C = LookAt(Eigen::Vector3f(0, 0, 5), Eigen::Vector3f::Zero());
  EXPECT_TRUE(T_W_C.linear().allFinite());
  EXPECT_NEAR(T_W_C.linear().determinant(), 1.0f, 1e-5f);
  EXPECT_TRUE((T_W_C.linear().col(2) - Eigen::Vector3f(0, 0, -1)).isZero(1e-6f));
}

TEST(OrbitTest, FrameBoxKeepsTheBoxInView) {
  const Eigen::AlignedBox3f box(Eigen::Vector3f(-1.0f, 0.0f, 0.0f),
                                Eigen::Vector3f(3.0f, 2.0f, 2.5f));
  const PinholeCamera camera = CameraFromFov(320, 240, 60.0f);
  const OrbitFraming f = FrameBox(box, camera);
  EXPECT_TRUE(f.centre_W.isApprox(box.center()));
  EXPECT_NEAR(std::hypot(f.radius_m, f.height_m), f.distance_m, 1e-4f);
  for (const Pose3f& T_W_C : OrbitPoses(f.centre_W, f.radius_m, f.height_m, 12)) {
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3f p_C =
          T_W_C.inverse() * box.corner(static_cast<Eigen::AlignedBox3f::CornerType>(corner));
      ASSERT_GT(p_C.z(), 0.0f);
      const Eigen::Vector2f px = camera.Project(p_C);
      // Pixels span [-0.5, size - 0.5] around their integer centres.
      EXPECT_TRUE(px.x() >= -0.5f && px.x() <= 319.5f && px.y() >= -0.5f && px.y() <= 239.5f)
          << px.transpose();
    }
  }
}

}  // namespace
}  // namespace voxplan
