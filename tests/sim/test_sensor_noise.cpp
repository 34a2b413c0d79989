// The Kinect-like noise model: axial σ against the model on rendered planes, disparity
// quantisation steps, lateral jitter statistics, grazing and edge dropout, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/parallel.h"
#include "sim/raycaster.h"
#include "sim/sensor_noise.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

// With ~19k samples the sample σ is within ~1% of the true one; 5% leaves room for the
// float rounding of depth and the clamp of Box-Muller's tail.
constexpr double kSigmaRelTolerance = 0.05;
constexpr float kQuantTolerance_px = 1e-3f;  // disparity of a quantised depth: a whole step

KinectNoiseParams Only(bool axial, bool lateral, bool quantize) {
  KinectNoiseParams p;
  p.seed = 7;
  p.grazing_dropout = false;
  p.edge_dropout = false;
  p.axial = axial;
  p.lateral = lateral;
  p.quantize = quantize;
  return p;
}

// A large quad in the plane z = z0 seen head-on from the origin (camera looking along +z).
RenderOutput RenderFrontalPlane(float z0, const PinholeCamera& camera, bool normals = true) {
  Mesh mesh;
  const float h = 4.f * z0;
  mesh.positions = {{-h, -h, z0}, {h, -h, z0}, {h, h, z0}, {-h, h, z0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  auto raycaster = MeshRaycaster::Create(mesh);
  EXPECT_TRUE(raycaster.ok());
  RenderParams params;
  params.normals = normals;
  return (*raycaster)->Render(camera, Pose3f::Identity(), params);
}

struct Moments {
  double mean = 0.0, stddev = 0.0;
  size_t n = 0;
};
Moments ErrorMoments(const DepthImage& noisy, const DepthImage& clean) {
  Moments m;
  double sum = 0.0, sum2 = 0.0;
  for (size_t i = 0; i < clean.data.size(); ++i) {
    if (!(clean.data[i] > 0.f) || !(noisy.data[i] > 0.f)) continue;
    const double e = double(noisy.data[i]) - double(clean.data[i]);
    sum += e;
    sum2 += e * e;
    ++m.n;
  }
  m.mean = sum / double(m.n);
  m.stddev = std::sqrt(sum2 / double(m.n) - m.mean * m.mean);
  return m;
}

TEST(SensorNoise, AxialSigmaMatchesModelOnPlanes) {
  const PinholeCamera camera = test::TestCamera(160, 120);
  for (float z : {0.8f, 1.5f, 3.0f, 4.5f}) {
    const RenderOutput clean = RenderFrontalPlane(z, camera);
    const KinectNoiseParams params = Only(true, false, false);
    auto noisy = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 0);
    ASSERT_TRUE(noisy.ok()) << noisy.status().message();
    const Moments m = ErrorMoments(*noisy, clean.depth);
    const double sigma = AxialSigma(params, z);
    EXPECT_EQ(m.n, clean.depth.data.size());
    EXPECT_NEAR(m.stddev, sigma, kSigmaRelTolerance * sigma) << "z " << z;
    EXPECT_LT(std::abs(m.mean), 4.0 * sigma / std::sqrt(double(m.n))) << "z " << z;
  }
  // The model's own numbers (Nguyen 2012): 1.2 mm at 0.4 m, 1.2 + 1.9 * 2.6^2 mm at 3 m.
  EXPECT_NEAR(AxialSigma({}, 0.4f), 0.0012f, 1e-7f);
  EXPECT_NEAR(AxialSigma({}, 3.0f), 0.0012f + 0.0019f * 2.6f * 2.6f, 1e-6f);
}

TEST(SensorNoise, AxialErrorsHaveGaussianTails) {
  // The share of standardised errors beyond k σ against 2 (1 - Φ(k)), over enough frames that
  // the ziggurat's tail (beyond 3.44 σ) and its wedges are sampled; 5 binomial σ either side.
  constexpr double kBinomialSigmas = 5.0;
  const PinholeCamera camera = test::TestCamera(160, 120);
  const float z = 1.5f;
  const RenderOutput clean = RenderFrontalPlane(z, camera);
  const KinectNoiseParams params = Only(true, false, false);
  const double sigma = AxialSigma(params, z);
  const std::vector<double> ks = {1.0, 2.0, 3.0, 3.5};
  std::vector<size_t> beyond(ks.size(), 0);
  size_t n = 0;
  for (uint64_t frame = 0; frame < 12; ++frame) {
    auto noisy = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, frame);
    ASSERT_TRUE(noisy.ok());
    for (size_t i = 0; i < clean.depth.data.size(); ++i) {
      const double e = std::abs(double(noisy->data[i]) - double(clean.depth.data[i])) / sigma;
      for (size_t j = 0; j < ks.size(); ++j) beyond[j] += e > ks[j] ? 1 : 0;
      ++n;
    }
  }
  for (size_t j = 0; j < ks.size(); ++j) {
    const double p = std::erfc(ks[j] / std::numbers::sqrt2);
    const double tolerance = kBinomialSigmas * std::sqrt(p * (1.0 - p) / double(n));
    EXPECT_NEAR(double(beyond[j]) / double(n), p, tolerance) << "beyond " << ks[j] << " sigma";
  }
}

TEST(SensorNoise, QuantisedDepthsSitOnDisparitySteps) {
  const PinholeCamera camera = test::TestCamera(160, 120);
  const KinectNoiseParams params = Only(false, false, true);
  const float fb = std::abs(camera.fx) * params.baseline_m;
  for (float z : {1.0f, 2.37f, 4.1f}) {
    const RenderOutput clean = RenderFrontalPlane(z, camera);
    auto noisy = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 0);
    ASSERT_TRUE(noisy.ok());
    // Depth step between neighbouring disparities at z: z^2 step / (f b).
    const float half_step_m = 0.5f * z * z * params.disparity_step_px / fb;
    for (size_t i = 0; i < clean.depth.data.size(); i += 37) {
      const float q = noisy->data[i];
      ASSERT_GT(q, 0.f);
      const float steps = fb / q / params.disparity_step_px;
      EXPECT_NEAR(steps, std::round(steps), kQuantTolerance_px / params.disparity_step_px);
      EXPECT_LE(std::abs(q - clean.depth.data[i]), half_step_m * 1.01f);
    }
  }
  // Beyond the farthest disparity step there is no return.
  EXPECT_EQ(QuantizeDepth(params, camera.fx, 10.f * fb / params.disparity_step_px), 0.f);
}

TEST(SensorNoise, AxialAndQuantisationCombine) {
  // Axial noise, then quantisation: the error's RMS against E[(Q(z + σ x) - z)^2], x ~ N(0, 1),
  // integrated numerically. A Kinect-like focal length keeps the steps near σ.
  const PinholeCamera camera{160, 120, 525.f, 525.f, 79.5f, 59.5f};
  const KinectNoiseParams params = Only(true, false, true);
  for (float z : {1.5f, 3.0f}) {
    const RenderOutput clean = RenderFrontalPlane(z, camera);
    auto noisy = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 3);
    ASSERT_TRUE(noisy.ok());
    const double sigma = AxialSigma(params, z);
    double expected2 = 0.0, weight = 0.0;
    for (double x = -6.0; x <= 6.0; x += 1e-3) {
      const double w = std::exp(-0.5 * x * x);
      const double e = QuantizeDepth(params, camera.fx, float(z + sigma * x)) - z;
      expected2 += w * e * e;
      weight += w;
    }
    const double expected = std::sqrt(expected2 / weight);
    const Moments m = ErrorMoments(*noisy, clean.depth);
    const double rms = std::sqrt(m.stddev * m.stddev + m.mean * m.mean);
    EXPECT_NEAR(rms, expected, kSigmaRelTolerance * expected) << "z " << z;
    EXPECT_GT(rms, sigma);  // quantisation only adds
  }
}

TEST(SensorNoise, LateralShiftsAreRoundedGaussians) {
  // Depth linear in u: the error of each pixel is 1 cm times its integer column shift.
  const PinholeCamera camera = test::TestCamera(160, 120);
  DepthImage ramp(camera.width, camera.height);
  for (int v = 0; v < ramp.height; ++v)
    for (int u = 0; u < ramp.width; ++u) ramp.at(u, v) = 1.f + 0.01f * float(u);
  const KinectNoiseParams params = Only(false, true, false);
  auto noisy = ApplyKinectNoise(ramp, {}, camera, params, 0);
  ASSERT_TRUE(noisy.ok());
  double sum2 = 0.0;
  size_t n = 0;
  for (int v = 0; v < ramp.height; ++v)
    for (int u = 3; u + 3 < ramp.width; ++u) {  // away from the clamped borders
      const double shift = (noisy->at(u, v) - ramp.at(u, v)) / 0.01;
      ASSERT_NEAR(shift, std::round(shift), 1e-2);
      sum2 += shift * shift;
      ++n;
    }
  // E[round(N(0, s))^2] = sum_k k^2 P(round = k).
  const double s = params.lateral_sigma_px;
  double expected = 0.0;
  for (int k = 1; k <= 5; ++k) {
    const double p = 0.5 * (std::erfc((k - 0.5) / (s * std::numbers::sqrt2)) -
                            std::erfc((k + 0.5) / (s * std::numbers::sqrt2)));
    expected += 2.0 * k * k * p;
  }
  EXPECT_NEAR(sum2 / double(n), expected, 2 * kSigmaRelTolerance * expected);
}

TEST(SensorNoise, GrazingAnglesDropOut) {
  // A floor plane seen from 1 m above, camera pitched down 45°: the incidence angle grows from
  // the bottom rows to the top ones and crosses the threshold inside the image.
  const PinholeCamera camera = test::TestCamera(160, 120);
  Mesh floor;
  floor.positions = {{-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}};
  floor.triangles = {{0, 1, 2}, {0, 2, 3}};
  auto raycaster = MeshRaycaster::Create(floor);
  ASSERT_TRUE(raycaster.ok());
  const Pose3f T_W_C = LookAt({0.f, 0.f, 1.f}, {0.f, 1.f, 0.f});  // 45° down
  RenderParams rp;
  rp.normals = true;
  const RenderOutput clean = (*raycaster)->Render(camera, T_W_C, rp);
  KinectNoiseParams params = Only(false, false, false);
  params.grazing_dropout = true;
  params.max_incidence_deg = 60.f;
  for (bool from_depth : {false, true}) {
    Image<Eigen::Vector3f> no_normals;
    auto noisy =
        ApplyKinectNoise(clean.depth, from_depth ? no_normals : clean.normals_C, camera, params, 0);
    ASSERT_TRUE(noisy.ok());
    int dropped = 0, kept = 0;
    const Eigen::Vector3f up_C = T_W_C.linear().transpose() * Eigen::Vector3f::UnitZ();
    for (int v = 2; v + 2 < camera.height; ++v)
      for (int u = 2; u + 2 < camera.width; ++u) {
        if (!(clean.depth.at(u, v) > 0.f)) continue;
        const Eigen::Vector3f ray = camera.Unproject(float(u), float(v), 1.f).normalized();
        const float angle_deg =
            std::acos(std::abs(ray.dot(up_C))) * 180.f / std::numbers::pi_v<float>;
        if (std::abs(angle_deg - params.max_incidence_deg) < 1.f) continue;  // rounding margin
        const bool expect_drop = angle_deg > params.max_incidence_deg;
        EXPECT_EQ(noisy->at(u, v) == 0.f, expect_drop) << u << "," << v << " " << angle_deg;
        (expect_drop ? dropped : kept)++;
      }
    EXPECT_GT(dropped, 500) << "from_depth " << from_depth;
    EXPECT_GT(kept, 500) << "from_depth " << from_depth;
  }
}

TEST(SensorNoise, FarSideOfDepthEdgesDropsOut) {
  // A wall at 3 m and a near box covering the left half at 1 m.
  const PinholeCamera camera = test::TestCamera(160, 120);
  DepthImage depth(camera.width, camera.height, 3.f);
  for (int v = 0; v < depth.height; ++v)
    for (int u = 0; u < depth.width / 2; ++u) depth.at(u, v) = 1.f;
  KinectNoiseParams params = Only(false, false, false);
  params.edge_dropout = true;
  params.edge_dropout_probability = 0.6f;
  auto noisy = ApplyKinectNoise(depth, {}, camera, params, 0);
  ASSERT_TRUE(noisy.ok());
  const int edge = depth.width / 2;  // first far column
  int far_dropped = 0;
  for (int v = 0; v < depth.height; ++v) {
    EXPECT_EQ(noisy->at(edge - 1, v), 1.f) << v;  // near side kept
    EXPECT_EQ(noisy->at(edge + 1, v), 3.f) << v;  // beyond the radius kept
    far_dropped += noisy->at(edge, v) == 0.f;
  }
  // Binomial(120, 0.6): mean 72, σ 5.4; 4σ either side.
  EXPECT_NEAR(far_dropped, 72, 22);
}

TEST(SensorNoise, DeterministicPerSeedFrameAndThreads) {
  const PinholeCamera camera = test::TestCamera(160, 120);
  const RenderOutput clean = RenderFrontalPlane(2.f, camera);
  const KinectNoiseParams params;  // everything on
  DepthImage one, two;
  {
    ThreadLimit limit(1);
    one = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 5).value();
  }
  {
    ThreadLimit limit(2);
    two = ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 5).value();
  }
  EXPECT_EQ(one.data, two.data);
  const DepthImage other =
      ApplyKinectNoise(clean.depth, clean.normals_C, camera, params, 6).value();
  EXPECT_NE(one.data, other.data);
  KinectNoiseParams reseeded = params;
  reseeded.seed = 99;
  EXPECT_NE(ApplyKinectNoise(clean.depth, clean.normals_C, camera, reseeded, 5).value().data,
            one.data);
  // Everything off: the clean image.
  const KinectNoiseParams off = Only(false, false, false);
  EXPECT_EQ(ApplyKinectNoise(clean.depth, {}, camera, off, 0).value().data, clean.depth.data);
}

TEST(SensorNoise, RefusesBadInput) {
  const PinholeCamera camera = test::TestCamera(160, 120);
  const DepthImage depth(160, 120, 1.f);
  EXPECT_FALSE(ApplyKinectNoise(DepthImage(80, 60, 1.f), {}, camera, {}, 0).ok());
  EXPECT_FALSE(ApplyKinectNoise(depth, Image<Eigen::Vector3f>(10, 10, Eigen::Vector3f::Zero()),
                                camera, {}, 0)
                   .ok());
  KinectNoiseParams bad;
  bad.edge_dropout_probability = 1.5f;
  EXPECT_FALSE(ApplyKinectNoise(depth, {}, camera, bad, 0).ok());
  bad = {};
  bad.baseline_m = 0.f;
  EXPECT_FALSE(bad.Validate().ok());
  bad = {};
  bad.max_incidence_deg = 120.f;
  EXPECT_FALSE(bad.Validate().ok());
}

}  // namespace
}  // namespace voxplan
