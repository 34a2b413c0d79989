#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <vector>

#include "core/parallel.h"
#include "fusion/integrate.h"
#include "fusion/tracking.h"
#include "io/dataset.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

using test::Box;
using test::Plane;
using test::Sphere;

// Named bounds.
constexpr float kMaxRotationErrorDeg = 0.05f;
constexpr float kMaxTranslationErrorM = 0.001f;
constexpr float kPhotometricSlackM = 0.001f;  // colour may not worsen translation by more
constexpr double kMaxIclAteM = 0.03;          // first 60 ICL-NUIM frames, tracked

struct Scene {
  std::vector<Plane> planes;
  std::vector<Sphere> spheres;
  std::vector<Box> boxes;
};

// A corner of three planes with a box and a sphere: every DoF is constrained.
Scene CornerScene() {
  Scene s;
  s.planes = {{Eigen::Vector3f::UnitZ(), 0.f},
              {Eigen::Vector3f::UnitX(), -1.f},
              {Eigen::Vector3f::UnitY(), -1.f}};
  s.boxes = {{Eigen::Vector3f(0.f, 0.f, 0.f), Eigen::Vector3f(0.4f, 0.4f, 0.4f)}};
  s.spheres = {{Eigen::Vector3f(0.2f, -0.5f, 0.3f), 0.25f}};
  return s;
}

Scene PlaneScene() {
  Scene s;
  s.planes = {{Eigen::Vector3f::UnitZ(), 0.f}};
  return s;
}

// Nearest surface of all primitives (depth 0 where every ray misses).
DepthImage RenderScene(const Scene& scene, const PinholeCamera& cam, const Pose3f& T_W_C) {
  DepthImage out(cam.width, cam.height, 0.f);
  const auto merge = [&](const DepthImage& d) {
    for (size_t i = 0; i < d.data.size(); ++i)
      if (d.data[i] > 0.f && (out.data[i] == 0.f || d.data[i] < out.data[i]))
        out.data[i] = d.data[i];
  };
  for (const Plane& p : scene.planes) merge(test::RenderDepth(p, cam, T_W_C));
  for (const Sphere& s : scene.spheres) merge(test::RenderDepth(s, cam, T_W_C));
  for (const Box& b : scene.boxes) merge(test::RenderDepth(b, cam, T_W_C));
  return out;
}

// Smooth texture fixed to the world, coarse enough for 2 cm voxels to hold it.
ColorImage RenderTexture(const DepthImage& depth, const PinholeCamera& cam, const Pose3f& T_W_C) {
  ColorImage out(cam.width, cam.height, 0);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const float z = depth.at(u, v);
      if (z <= 0.f) continue;
      const Eigen::Vector3f p_W = T_W_C * cam.Unproject(float(u), float(v), z);
      const float k = 2.f * float(M_PI) / 0.4f;
      const float i = 0.5f + 0.2f * std::sin(k * p_W.x()) +
                      0.2f * std::sin(k * p_W.y()) * std::cos(k * p_W.z());
      const auto c = uint8_t(std::clamp(i, 0.f, 1.f) * 255.f);
      out.at(u, v) = PackRgb(c, c, c);
    }
  return out;
}

Pose3f Nominal() {
  return LookAt(Eigen::Vector3f(1.8f, 1.6f, 1.4f), Eigen::Vector3f(-0.3f, -0.3f, 0.2f));
}
// Looking steeply down at the floor, where the TSDF of a plane is clean (no grazing rays), so
// only the geometry is degenerate.
Pose3f NominalAbovePlane() {
  return LookAt(Eigen::Vector3f(0.4f, 0.3f, 1.5f), Eigen::Vector3f::Zero());
}

// 3 degrees about a skew axis and 5 cm, in the camera frame.
Pose3f Perturbation() {
  Pose3f d = Pose3f::Identity();
  d.linear() =
      Eigen::AngleAxisf(3.f * float(M_PI) / 180.f, Eigen::Vector3f(1.f, 2.f, 3.f).normalized())
          .toRotationMatrix();
  d.translation() = Eigen::Vector3f(0.03f, -0.03f, 0.025f);
  return d;
}

struct Fixture {
  PinholeCamera camera = test::TestCamera(320, 240);
  TsdfVolume volume{VolumeParams{0.02f, 0.08f}};
  IntegrateParams integrate;

  // Fuses exact frames from a few poses around the nominal one.
  Fixture(const Scene& scene, bool textured, const Pose3f& nominal = Nominal()) {
    integrate.max_depth_m = 5.f;
    for (int k = -2; k <= 2; ++k) {
      Pose3f T_W_C = nominal;
      T_W_C.linear() =
          Eigen::AngleAxisf(0.04f * float(k), Eigen::Vector3f::UnitZ()) * T_W_C.linear();
      T_W_C.translation() += Eigen::Vector3f(0.05f * float(k), -0.05f * float(k), 0.f);
      const DepthImage depth = RenderScene(scene, camera, T_W_C);
      const ColorImage color = textured ? RenderTexture(depth, camera, T_W_C) : ColorImage();
      EXPECT_TRUE(IntegrateFrame(depth, color, camera, T_W_C, integrate, volume).ok());
    }
  }
};

float RotationErrorDeg(const Pose3f& a, const Pose3f& b) {
  return Eigen::AngleAxisf((a.linear().transpose() * b.linear()).eval()).angle() * 180.f /
         float(M_PI);
}
float TranslationError(const Pose3f& a, const Pose3f& b) {
  return (a.translation() - b.translation()).norm();
}

TEST(FrameTracker, RecoversPerturbedPoseOnCornerScene) {
  const Scene scene = CornerScene();
  Fixture f(scene, false);
  const Pose3f T_W_C_true = Nominal() * Perturbation();
  const DepthImage depth = RenderScene(scene, f.camera, T_W_C_true);

  FrameTracker tracker(f.camera, TrackingParams{});
  tracker.Reset(Nominal());
  const Result<TrackingResult> r = tracker.Track(depth, ColorImage(), f.volume);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->ok) << r->failure;
  EXPECT_TRUE(r->failure.empty());
  RecordProperty("rotation_error_deg", std::to_string(RotationErrorDeg(r->T_W_C, T_W_C_true)));
  RecordProperty("translation_error_mm",
                 std::to_string(1000.f * TranslationError(r->T_W_C, T_W_C_true)));
  EXPECT_LT(RotationErrorDeg(r->T_W_C, T_W_C_true), kMaxRotationErrorDeg);
  EXPECT_LT(TranslationError(r->T_W_C, T_W_C_true), kMaxTranslationErrorM);
  EXPECT_GT(r->inlier_ratio, 0.5f);
  EXPECT_LT(r->residual_rms_m, 0.01f);
  EXPECT_GT(r->iterations, 0);
  // The start was off by the perturbation itself.
  EXPECT_GT(TranslationError(Nominal(), T_W_C_true), 0.04f);
}

// The finest level on every pixel or on a subsampled grid: both recover the pose.
TEST(FrameTracker, FinestLevelStrideKeepsAccuracy) {
  const Scene scene = CornerScene();
  Fixture f(scene, false);
  const Pose3f T_W_C_true = Nominal() * Perturbation();
  const DepthImage depth = RenderScene(scene, f.camera, T_W_C_true);
  for (int stride : {1, 2, 3}) {
    TrackingParams params;
    params.finest_level_stride = stride;
    FrameTracker tracker(f.camera, params);
    tracker.Reset(Nominal());
    const Result<TrackingResult> r = tracker.Track(depth, ColorImage(), f.volume);
    ASSERT_TRUE(r.ok() && r->ok) << "stride " << stride;
    EXPECT_LT(RotationErrorDeg(r->T_W_C, T_W_C_true), kMaxRotationErrorDeg) << "stride " << stride;
    EXPECT_LT(TranslationError(r->T_W_C, T_W_C_true), kMaxTranslationErrorM) << "stride " << stride;
    EXPECT_GT(r->inlier_ratio, 0.5f) << "stride " << stride;
  }
  TrackingParams bad;
  bad.finest_level_stride = 0;
  EXPECT_THROW(FrameTracker(f.camera, bad), std::invalid_argument);
}

TEST(FrameTracker, DeterministicAcrossThreadCounts) {
  const Scene scene = CornerScene();
  Fixture f(scene, false);
  const DepthImage depth = RenderScene(scene, f.camera, Nominal() * Perturbation());
  Pose3f poses[2];
  for (int i = 0; i < 2; ++i) {
    ThreadLimit limit(i == 0 ? 1 : 2);
    FrameTracker tracker(f.camera, TrackingParams{});
    tracker.Reset(Nominal());
    const Result<TrackingResult> r = tracker.Track(depth, ColorImage(), f.volume);
    ASSERT_TRUE(r.ok() && r->ok);
    poses[i] = r->T_W_C;
  }
  EXPECT_EQ(poses[0].matrix(), poses[1].matrix());
}

TEST(FrameTracker, PhotometricTermDoesNotHurtOnTexturedScene) {
  const Scene scene = CornerScene();
  Fixture f(scene, true);
  const Pose3f T_W_C_true = Nominal() * Perturbation();
  const DepthImage depth = RenderScene(scene, f.camera, T_W_C_true);
  const ColorImage color = RenderTexture(depth, f.camera, T_W_C_true);

  float translation_error[2], rotation_error[2];
  for (int i = 0; i < 2; ++i) {
    TrackingParams params;
    params.photometric_weight = i == 0 ? 0.f : 0.1f;
    FrameTracker tracker(f.camera, params);
    tracker.Reset(Nominal());
    const Result<TrackingResult> r = tracker.Track(depth, color, f.volume);
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(r->ok) << "photometric_weight " << params.photometric_weight << ": " << r->failure;
    translation_error[i] = TranslationError(r->T_W_C, T_W_C_true);
    rotation_error[i] = RotationErrorDeg(r->T_W_C, T_W_C_true);
  }
  EXPECT_LT(translation_error[1], kMaxTranslationErrorM);
  EXPECT_LT(rotation_error[1], kMaxRotationErrorDeg);
  RecordProperty("translation_error_mm_geometric", std::to_string(1000.f * translation_error[0]));
  RecordProperty("translation_error_mm_photometric", std::to_string(1000.f * translation_error[1]));
  EXPECT_LE(translation_error[1], translation_error[0] + kPhotometricSlackM);
}

TEST(FrameTracker, SinglePlaneIsDegenerate) {
  const Scene scene = PlaneScene();
  Fixture f(scene, false, NominalAbovePlane());
  const DepthImage depth = RenderScene(scene, f.camera, NominalAbovePlane() * Perturbation());
  FrameTracker tracker(f.camera, TrackingParams{});
  tracker.Reset(NominalAbovePlane());
  const Result<TrackingResult> r = tracker.Track(depth, ColorImage(), f.volume);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->ok);
  EXPECT_NE(r->failure.find("degenerate"), std::string::npos) << r->failure;
  RecordProperty("condition_number", std::to_string(r->condition_number));
  EXPECT_GT(r->condition_number, TrackingParams{}.max_condition_number);
  // A lost frame reports the prediction.
  EXPECT_EQ(r->T_W_C.matrix(), NominalAbovePlane().matrix());
}

// A frame of one depth everywhere (0: no valid pixel), tracked against the corner scene's model
// from the nominal pose.
TrackingResult TrackFlatFrame(float depth_m) {
  Fixture f(CornerScene(), false);
  FrameTracker tracker(f.camera, TrackingParams{});
  tracker.Reset(Nominal());
  const DepthImage flat(f.camera.width, f.camera.height, depth_m);
  Result<TrackingResult> r = tracker.Track(flat, ColorImage(), f.volume);
  EXPECT_TRUE(r.ok()) << r.status().message();
  return r.ok() ? *r : TrackingResult{};
}

TEST(FrameTracker, AllInvalidFrameIsLost) {
  const TrackingResult r = TrackFlatFrame(0.f);
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.failure.empty());
}

TEST(FrameTracker, EmptyModelIsLost) {
  const PinholeCamera camera = test::TestCamera(320, 240);
  const TsdfVolume volume(VolumeParams{0.02f, 0.08f});
  FrameTracker tracker(camera, TrackingParams{});
  tracker.Reset(Nominal());
  const Result<TrackingResult> r =
      tracker.Track(RenderScene(CornerScene(), camera, Nominal()), ColorImage(), volume);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->ok);
  EXPECT_NE(r->failure.find("correspondences"), std::string::npos) << r->failure;
  EXPECT_TRUE(r->no_model);  // nothing to register against, not a surface out of place
}

// A surface the model does not hold, right in front of the camera: no correspondence either,
// but the model is in view, so the frame did not align rather than saw nothing known.
TEST(FrameTracker, UnknownSurfaceBeforeTheModelIsNotNoModel) {
  const TrackingResult r = TrackFlatFrame(0.6f);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.failure.find("correspondences"), std::string::npos) << r.failure;
  EXPECT_FALSE(r.no_model);
}

TEST(FrameTracker, JumpBeyondMaxMotionIsLost) {
  const Scene scene = CornerScene();
  Fixture f(scene, false);
  TrackingParams params;
  params.max_motion_m = 0.02f;  // below the 5 cm perturbation
  FrameTracker tracker(f.camera, params);
  tracker.Reset(Nominal());
  const Result<TrackingResult> r = tracker.Track(
      RenderScene(scene, f.camera, Nominal() * Perturbation()), ColorImage(), f.volume);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->ok);
  EXPECT_NE(r->failure.find("jump"), std::string::npos) << r->failure;
  EXPECT_FALSE(r->no_model);
}

TEST(FrameTracker, RefusesMismatchedImages) {
  Fixture f(CornerScene(), false);
  FrameTracker tracker(f.camera, TrackingParams{});
  EXPECT_FALSE(tracker.Track(DepthImage(10, 10, 1.f), ColorImage(), f.volume).ok());
  EXPECT_FALSE(tracker.Track(DepthImage(), ColorImage(), f.volume).ok());
  const DepthImage depth(f.camera.width, f.camera.height, 1.f);
  EXPECT_FALSE(tracker.Track(depth, ColorImage(3, 3, 0), f.volume).ok());
  EXPECT_THROW(FrameTracker(PinholeCamera{}, TrackingParams{}), std::invalid_argument);
}

TEST(FrameTracker, ConstantVelocityPrediction) {
  const PinholeCamera camera = test::TestCamera();
  Pose3f T0 = Pose3f::Identity(), T1 = Pose3f::Identity();
  T0.translation() = Eigen::Vector3f(1.f, 2.f, 3.f);
  T1.linear() = Eigen::AngleAxisf(0.1f, Eigen::Vector3f::UnitY()).toRotationMatrix();
  T1.translation() = Eigen::Vector3f(1.1f, 2.f, 3.f);
  const Pose3f expected = T1 * (T0.inverse() * T1);

  FrameTracker tracker(camera, TrackingParams{});
  tracker.Reset(T0);
  EXPECT_TRUE(tracker.Predict().isApprox(T0));  // no motion known yet
  tracker.Accept(T1);
  EXPECT_TRUE(tracker.Predict().isApprox(expected, 1e-5f));
  // Twice the step: translation 1.2 + rotation 0.2 rad about y.
  EXPECT_NEAR(RotationErrorDeg(tracker.Predict(), T0), 0.2f * 180.f / float(M_PI), 1e-3f);
  tracker.Reset(T1);
  EXPECT_TRUE(tracker.Predict().isApprox(T1));  // Reset forgets the motion

  TrackingParams still;
  still.constant_velocity = false;
  FrameTracker static_tracker(camera, still);
  static_tracker.Reset(T0);
  static_tracker.Accept(T1);
  EXPECT_TRUE(static_tracker.Predict().isApprox(T1));
}

// System: ICL-NUIM office (noise-free, fy < 0), first 60 frames fused with tracked poses.
TEST(FrameTracker, IclNuimFirstFramesStayOnTrajectory) {
  const std::filesystem::path root = test::SharedDataDir() / "rgbd" / "iclnuim_office_traj0";
  if (!std::filesystem::exists(root)) GTEST_SKIP() << "no " << root;
  Result<std::unique_ptr<Dataset>> dataset = OpenDataset(root.string());
  ASSERT_TRUE(dataset.ok()) << dataset.status().message();
  const DatasetInfo& info = (*dataset)->info();
  ASSERT_LT(info.camera.fy, 0.f);
  TsdfVolume volume(VolumeParams{0.01f, 0.04f});
  FrameTracker tracker(info.camera, TrackingParams{});
  std::vector<Eigen::Vector3d> estimated, truth;
  int lost = 0;
  for (size_t i = 0; i < std::min<size_t>(60, info.num_frames); ++i) {
    Result<Frame> frame = (*dataset)->Load(i);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    if (!frame->T_W_C) continue;
    const Pose3f T_W_C_true = frame->T_W_C->cast<float>();
    Pose3f T_W_C = T_W_C_true;
    if (estimated.empty()) {
      tracker.Reset(T_W_C);
    } else {
      const Result<TrackingResult> r = tracker.Track(frame->depth, frame->color, volume);
      ASSERT_TRUE(r.ok()) << r.status().message();
      T_W_C = r->T_W_C;
      if (!r->ok) {
        ++lost;
        estimated.push_back(T_W_C.translation().cast<double>());
        truth.push_back(frame->T_W_C->translation());
        continue;
      }
      tracker.Accept(T_W_C);
    }
    ASSERT_TRUE(IntegrateFrame(frame->depth, frame->color, info.camera, T_W_C, {}, volume).ok());
    estimated.push_back(T_W_C.translation().cast<double>());
    truth.push_back(frame->T_W_C->translation());
  }
  ASSERT_GE(estimated.size(), 50u);
  EXPECT_EQ(lost, 0);
  Eigen::Matrix3Xd a(3, estimated.size()), b(3, truth.size());
  for (size_t k = 0; k < estimated.size(); ++k)
    a.col(Eigen::Index(k)) = estimated[k], b.col(Eigen::Index(k)) = truth[k];
  const Eigen::Matrix4d S = Eigen::umeyama(a, b, false);
  const Eigen::Matrix3Xd aligned =
      (S.topLeftCorner<3, 3>() * a).colwise() + S.topRightCorner<3, 1>();
  const double ate_m = std::sqrt((aligned - b).colwise().squaredNorm().mean());
  RecordProperty("ate_mm", std::to_string(ate_m * 1000.0));
  EXPECT_LT(ate_m, kMaxIclAteM);
}

}  // namespace
}  // namespace voxplan
