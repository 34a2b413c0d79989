#pragma once
// Frame-to-model camera tracking (KinectFusion / VoxelHashing style): the new depth frame is
// bilateral-filtered, put in a 3-level pyramid and aligned by point-to-plane ICP with projective
// data association (distance and normal-angle gates, Huber weights, Gauss-Newton on SE(3)) to
// the model raycast at the predicted pose, optionally with a photometric term on colour. A
// constant-velocity prior predicts the pose. Loss is detected from the inlier ratio, the
// residual and the conditioning of the normal equations; a lost frame must not be integrated.
#include <array>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/pose.h"
#include "core/raycast.h"
#include "core/status.h"
#include "core/volume.h"

namespace voxplan {

struct TrackingParams {
  // Per pyramid level, finest first; the finest level costs 4x the coarsest (with the stride
  // below) and converges in 1-2 steps after the coarse ones (more did not change ATE on
  // ICL-NUIM or 7-Scenes).
  std::array<int, 3> iterations = {2, 5, 4};
  // The finest level takes every n-th pixel of every n-th row (normals still from the direct
  // neighbours): 2 quarters its cost and left ATE on ICL-NUIM and 7-Scenes unchanged.
  int finest_level_stride = 2;
  float max_correspondence_m = 0.10f;  // projective association distance gate
  float max_normal_angle_deg = 20.0f;
  float huber_delta_m = 0.005f;
  // Colour term: cost = sum Huber(point-to-plane [m]) + weight * sum Huber(intensity in [0, 1]).
  float photometric_weight = 0.0f;  // 0: geometry only; > 0 weighs in the colour term
  float photometric_huber_delta = 0.1f;
  float bilateral_sigma_depth_m = 0.03f;
  float bilateral_sigma_space_px = 4.5f;
  int bilateral_diameter_px = 5;
  float pyramid_depth_gate_m = 0.05f;  // neighbours averaged into a coarse pixel lie this close
  // The model is raycast at this pyramid level (0: full resolution; 1: half, a quarter the cost;
  // 2: a sixteenth, with the same ATE on ICL-NUIM and 7-Scenes as 1).
  int model_level = 2;
  // The finest level stops iterating once the increment is smaller (rad, m); level l, whose
  // pixels are 2^l times larger, once it is smaller than 2^l times this.
  float min_update = 5e-4f;
  bool constant_velocity = true;
  // Loss detection.
  float min_inlier_ratio = 0.25f;    // of valid input pixels, at the finest level
  float max_residual_rms_m = 0.02f;  // point-to-plane RMS of inliers at the end
  // Of the 6x6 normal equations with rotation about the centroid, scaled by the spread of the
  // points: 7-Scenes kitchen 4-40, ICL-NUIM office (walls) up to 280, a single plane ~9000.
  float max_condition_number = 1000.f;
  float max_motion_m = 0.3f;  // a larger jump from the prediction is a failure
  RaycastParams raycast;      // of the model; its depth range also bounds the input depth
};

struct TrackingResult {
  bool ok = false;
  Pose3f T_W_C = Pose3f::Identity();  // estimate (the prediction when !ok)
  float inlier_ratio = 0.f;
  // Lost because the model shows (almost) no surface in view: nothing to register against, as
  // opposed to a surface the frame does not align with.
  bool no_model = false;
  float residual_rms_m = 0.f;
  float condition_number = 0.f;
  int iterations = 0;                               // Gauss-Newton steps over all levels
  std::array<int, 3> level_iterations = {0, 0, 0};  // per pyramid level, finest first
  size_t inliers = 0;                               // correspondences at the finest level
  double track_ms = 0.0;                            // everything below together
  double filter_ms = 0.0;  // bilateral filter, pyramid, vertex and normal maps
  double raycast_ms = 0.0;
  double icp_ms = 0.0;
  std::string failure;  // why the frame was lost (empty when ok)
};

// Keeps the last poses for the motion prior. Track() aligns one frame to the volume; the caller
// integrates the frame with result.T_W_C only when result.ok, then calls Accept().
class FrameTracker {
 public:
  // Throws std::invalid_argument for an invalid camera, one too small for the pyramid or an
  // out-of-range model_level.
  FrameTracker(const PinholeCamera& camera, const TrackingParams& params);
  ~FrameTracker();
  FrameTracker(FrameTracker&&) noexcept;
  FrameTracker& operator=(FrameTracker&&) noexcept;
  // The pose of the first frame (from the dataset, or identity).
  void Reset(const Pose3f& T_W_C);
  Result<TrackingResult> Track(const DepthImage& depth, const ColorImage& color,
                               const TsdfVolume& volume);
  // The same from a prediction the caller has (a robot's odometry) instead of Predict()'s.
  Result<TrackingResult> Track(const DepthImage& depth, const ColorImage& color,
                               const TsdfVolume& volume, const Pose3f& T_W_C_pred);
  // Records a tracked pose (successful frames) for the next prediction.
  void Accept(const Pose3f& T_W_C);
  Pose3f Predict() const;

 private:
  PinholeCamera camera_;
  TrackingParams params_;
  Pose3f last_T_W_C_ = Pose3f::Identity();
  std::optional<Pose3f> previous_T_W_C_;
  struct Workspace;
  std::unique_ptr<Workspace> workspace_;
};

}  // namespace voxplan
