#pragma once
// A Kinect-like depth noise model (structured light, after Nguyen et al. 2012 and Handa et al.
// 2014), applied to a clean rendered depth image. Each effect can be switched off; the noise is a
// function of (seed, frame, pixel) only, so results do not depend on threads or call order.
//
// Effects, in the order applied:
//  1. dropout at grazing angles: the angle between the pixel's ray and the surface normal beyond
//     max_incidence_deg gives no return (the projected pattern is too stretched to decode);
//  2. dropout at depth edges: a pixel on the far side of a depth jump (a neighbour within
//     edge_radius_px nearer by more than edge_jump_m + edge_jump_fraction * z) is dropped with
//     probability edge_dropout_probability (the projector's shadow);
//  3. lateral jitter: each pixel takes the clean depth of a pixel shifted by N(0, σ_lat) in u and
//     v, rounded to the nearest pixel (no mixing across edges, so no invented flying pixels);
//  4. axial noise: z += N(0, σ_z(z)), σ_z(z) = axial_sigma0_m + axial_sigma2 (z - axial_z0_m)²;
//  5. disparity quantisation: z -> f b / (round(f b / (z step)) step), step in pixels.
#include <Eigen/Core>
#include <cstdint>

#include "core/camera.h"
#include "core/image.h"
#include "core/status.h"

namespace voxplan {

struct KinectNoiseParams {
  uint64_t seed = 0;

  bool grazing_dropout = true;
  float max_incidence_deg = 80.0f;  // angle between ray and normal; beyond it, no return

  bool edge_dropout = true;
  int edge_radius_px = 1;
  float edge_jump_m = 0.05f;
  float edge_jump_fraction = 0.05f;  // of the pixel's depth
  float edge_dropout_probability = 0.8f;

  bool lateral = true;
  float lateral_sigma_px = 0.5f;

  bool axial = true;
  float axial_sigma0_m = 0.0012f;  // Nguyen 2012: 0.0012 + 0.0019 (z - 0.4)^2
  float axial_sigma2 = 0.0019f;    // per m^2
  float axial_z0_m = 0.4f;

  bool quantize = true;
  float baseline_m = 0.075f;         // Kinect v1 projector-camera baseline
  float disparity_step_px = 0.125f;  // 1/8 pixel sub-pixel disparity

  // Returns an empty Status when the parameters make sense, else names the bad one.
  Status Validate() const;
};

// σ_z of the axial model at depth z (metres).
float AxialSigma(const KinectNoiseParams& params, float z_m);
// The depth quantisation of the disparity model: the nearest representable depth to z.
float QuantizeDepth(const KinectNoiseParams& params, float focal_px, float z_m);

// Unit normals (camera frame, facing the camera) from central differences of the back-projected
// depth; zero where a neighbour is missing or the differences jump by more than `max_jump_m`.
Image<Eigen::Vector3f> NormalsFromDepth(const DepthImage& depth, const PinholeCamera& camera,
                                        float max_jump_m = 0.1f);

// The noisy image for frame `frame_index` of a sequence. `normals_C` (camera-frame normals, as
// MeshRaycaster renders them) may be empty: normals then come from NormalsFromDepth. Refuses
// images whose sizes differ from each other or from the camera, and invalid parameters.
Result<DepthImage> ApplyKinectNoise(const DepthImage& depth,
                                    const Image<Eigen::Vector3f>& normals_C,
                                    const PinholeCamera& camera, const KinectNoiseParams& params,
                                    uint64_t frame_index);

}  // namespace voxplan
