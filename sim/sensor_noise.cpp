#include "sim/sensor_noise.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace voxplan {

namespace {

// Counter-based randomness: every draw is a hash of (seed, frame, pixel, stream), so a pixel's
// noise is the same whichever thread computes it. One 64-bit hash gives two 32-bit uniforms.
enum Stream : uint64_t { kEdge = 0, kLateral = 1, kAxial = 2, kNumStreams = 3 };

uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

constexpr double kTwoPow32 = 4294967296.0;

struct PixelRng {
  uint64_t frame_key;
  uint64_t Bits(size_t pixel, uint64_t stream) const {
    return SplitMix64(frame_key ^ (uint64_t(pixel) * kNumStreams + stream));
  }
  // Two uniforms in [0, 1) from one hash.
  std::pair<double, double> Uniform2(size_t pixel, uint64_t stream) const {
    const uint64_t b = Bits(pixel, stream);
    return {double(b >> 32) / kTwoPow32, double(b & 0xffffffffu) / kTwoPow32};
  }
  // A standard normal (Box-Muller, one of the pair); |x| <= 6.7 with 32-bit uniforms.
  float Gaussian(size_t pixel, uint64_t stream) const {
    const auto [a, b] = Uniform2(pixel, stream);
    const float u1 = float(1.0 - a);  // (0, 1]: log stays finite
    return std::sqrt(-2.f * std::log(u1)) * std::cos(2.f * std::numbers::pi_v<float> * float(b));
  }
};

// The pixel shift round(N(0, σ)) by inverse CDF over a small table: two uniform draws per pixel
// instead of a Box-Muller pair (log, sqrt, sin, cos dominated the noise pass).
class RoundedGaussian {
 public:
  explicit RoundedGaussian(float sigma) {
    if (!(sigma > 0.f)) return;
    const int k_max = std::min(64, int(std::ceil(6.f * sigma)) + 1);
    offset_ = -k_max;
    for (int k = -k_max; k < k_max; ++k)  // cdf_[i] = P(round(x) <= offset_ + i)
      cdf_.push_back(0.5 * std::erfc(-(double(k) + 0.5) / (double(sigma) * std::numbers::sqrt2)));
  }
  int Sample(double uniform) const {
    if (cdf_.empty()) return 0;
    return offset_ + int(std::upper_bound(cdf_.begin(), cdf_.end(), uniform) - cdf_.begin());
  }

 private:
  int offset_ = 0;
  std::vector<double> cdf_;
};

PixelRng MakeRng(uint64_t seed, uint64_t frame) {
  return {SplitMix64(SplitMix64(seed) ^ SplitMix64(frame + 0x632be59bd9b4e019ull))};
}

}  // namespace

Status KinectNoiseParams::Validate() const {
  auto bad = [](const std::string& what) { return InvalidArgument("KinectNoiseParams: " + what); };
  if (!(max_incidence_deg > 0.f && max_incidence_deg <= 90.f))
    return bad("max_incidence_deg must be in (0, 90], got " + std::to_string(max_incidence_deg));
  if (edge_radius_px < 0 || edge_radius_px > 8)
    return bad("edge_radius_px must be in [0, 8], got " + std::to_string(edge_radius_px));
  if (!(edge_jump_m >= 0.f) || !(edge_jump_fraction >= 0.f))
    return bad("edge jump thresholds must be >= 0");
  if (!(edge_dropout_probability >= 0.f && edge_dropout_probability <= 1.f))
    return bad("edge_dropout_probability must be in [0, 1]");
  if (!(lateral_sigma_px >= 0.f && lateral_sigma_px <= 10.f))
    return bad("lateral_sigma_px must be in [0, 10], got " + std::to_string(lateral_sigma_px));
  if (!(axial_sigma0_m >= 0.f) || !(axial_sigma2 >= 0.f) || !std::isfinite(axial_z0_m))
    return bad("axial noise coefficients must be finite and >= 0");
  if (!(baseline_m > 0.f) || !(disparity_step_px > 0.f))
    return bad("baseline_m and disparity_step_px must be > 0");
  return Status::Ok();
}

float AxialSigma(const KinectNoiseParams& params, float z_m) {
  const float dz = z_m - params.axial_z0_m;
  return params.axial_sigma0_m + params.axial_sigma2 * dz * dz;
}

float QuantizeDepth(const KinectNoiseParams& params, float focal_px, float z_m) {
  if (!(z_m > 0.f)) return 0.f;
  const float fb = std::abs(focal_px) * params.baseline_m;
  const float steps = std::floor(fb / (z_m * params.disparity_step_px) + 0.5f);
  if (steps < 1.f) return 0.f;  // beyond the farthest representable disparity: no return
  return fb / (steps * params.disparity_step_px);
}

Image<Eigen::Vector3f> NormalsFromDepth(const DepthImage& depth, const PinholeCamera& camera,
                                        float max_jump_m) {
  Image<Eigen::Vector3f> normals(depth.width, depth.height, Eigen::Vector3f::Zero());
  const int w = depth.width, h = depth.height;
  ParallelFor(size_t(std::max(h - 2, 0)), 8, [&](size_t begin, size_t end) {
    for (size_t row = begin; row < end; ++row) {
      const int v = int(row) + 1;
      for (int u = 1; u + 1 < w; ++u) {
        const float z = depth.at(u, v), zl = depth.at(u - 1, v), zr = depth.at(u + 1, v);
        const float zu = depth.at(u, v - 1), zd = depth.at(u, v + 1);
        if (!(z > 0.f && zl > 0.f && zr > 0.f && zu > 0.f && zd > 0.f)) continue;
        if (std::abs(zr - zl) > max_jump_m || std::abs(zd - zu) > max_jump_m) continue;
        const Eigen::Vector3f dx = camera.Unproject(float(u + 1), float(v), zr) -
                                   camera.Unproject(float(u - 1), float(v), zl);
        const Eigen::Vector3f dy = camera.Unproject(float(u), float(v + 1), zd) -
                                   camera.Unproject(float(u), float(v - 1), zu);
        Eigen::Vector3f n = dx.cross(dy);
        const float norm = n.norm();
        if (!(norm > 0.f)) continue;
        n /= norm;
        if (n.dot(camera.Unproject(float(u), float(v), z)) > 0.f) n = -n;
        normals.at(u, v) = n;
      }
    }
  });
  return normals;
}

Result<DepthImage> ApplyKinectNoise(const DepthImage& depth,
                                    const Image<Eigen::Vector3f>& normals_C,
                                    const PinholeCamera& camera, const KinectNoiseParams& params,
                                    uint64_t frame_index) {
  VOXPLAN_RETURN_IF_ERROR(params.Validate());
  if (!camera.Valid()) return InvalidArgument("ApplyKinectNoise: invalid camera");
  if (depth.width != camera.width || depth.height != camera.height)
    return InvalidArgument("ApplyKinectNoise: depth is " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + ", camera " +
                           std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!normals_C.empty() && (normals_C.width != depth.width || normals_C.height != depth.height))
    return InvalidArgument("ApplyKinectNoise: normals are " + std::to_string(normals_C.width) +
                           "x" + std::to_string(normals_C.height) + ", depth " +
                           std::to_string(depth.width) + "x" + std::to_string(depth.height));
  const int w = depth.width, h = depth.height;
  const PixelRng rng = MakeRng(params.seed, frame_index);

  Image<Eigen::Vector3f> computed_normals;
  const Image<Eigen::Vector3f>* normals = &normals_C;
  if (params.grazing_dropout && normals_C.empty()) {
    computed_normals = NormalsFromDepth(depth, camera);
    normals = &computed_normals;
  }
  const float min_cos = std::cos(params.max_incidence_deg * float(std::numbers::pi) / 180.f);

  // Per-column and per-row ray terms: the ray through (u, v) is (ray_x[u], ray_y[v], 1).
  std::vector<float> ray_x(static_cast<size_t>(w)), ray_y(static_cast<size_t>(h));
  for (int u = 0; u < w; ++u) ray_x[size_t(u)] = (float(u) - camera.cx) / camera.fx;
  for (int v = 0; v < h; ++v) ray_y[size_t(v)] = (float(v) - camera.cy) / camera.fy;

  // The nearest valid depth within edge_radius_px (a separable min filter; misses count as
  // infinitely far): a pixel farther than it by the jump lies on the far side of an edge.
  const bool edges = params.edge_dropout && params.edge_dropout_probability > 0.f;
  DepthImage nearest;
  if (edges) {
    const int r = params.edge_radius_px;
    const float far = std::numeric_limits<float>::infinity();
    DepthImage row_min(w, h, far);
    nearest = DepthImage(w, h, far);
    ParallelFor(size_t(h), 16, [&](size_t begin, size_t end) {
      for (size_t v = begin; v < end; ++v)
        for (int u = 0; u < w; ++u) {
          float m = far;
          for (int uu = std::max(0, u - r); uu <= std::min(w - 1, u + r); ++uu) {
            const float z = depth.at(uu, int(v));
            if (z > 0.f) m = std::min(m, z);
          }
          row_min.at(u, int(v)) = m;
        }
    });
    ParallelFor(size_t(h), 16, [&](size_t begin, size_t end) {
      for (size_t v = begin; v < end; ++v) {
        const int v0 = std::max(0, int(v) - r), v1 = std::min(h - 1, int(v) + r);
        for (int u = 0; u < w; ++u) {
          float m = far;
          for (int vv = v0; vv <= v1; ++vv) m = std::min(m, row_min.at(u, vv));
          nearest.at(u, int(v)) = m;
        }
      }
    });
  }

  // Pass 1: dropouts on the clean image.
  const float min_cos2 = min_cos * min_cos;
  DepthImage kept = depth;
  ParallelFor(size_t(h), 8, [&](size_t begin, size_t end) {
    for (size_t row = begin; row < end; ++row) {
      const int v = int(row);
      const float ry = ray_y[row];
      for (int u = 0; u < w; ++u) {
        const float z = depth.at(u, v);
        if (!(z > 0.f)) continue;
        if (params.grazing_dropout) {
          // |n . r| < cos(max) |r| with a unit normal, squared (no square roots).
          const Eigen::Vector3f& n = normals->at(u, v);
          const float rx = ray_x[size_t(u)];
          const float dot = n.x() * rx + n.y() * ry + n.z();
          if (n.squaredNorm() > 0.f && dot * dot < min_cos2 * (rx * rx + ry * ry + 1.f)) {
            kept.at(u, v) = 0.f;
            continue;
          }
        }
        if (edges && z - nearest.at(u, v) > params.edge_jump_m + params.edge_jump_fraction * z) {
          const size_t pixel = size_t(v) * size_t(w) + size_t(u);
          if (rng.Uniform2(pixel, kEdge).first < params.edge_dropout_probability)
            kept.at(u, v) = 0.f;
        }
      }
    }
  });

  // Pass 2: lateral jitter, axial noise and quantisation per output pixel.
  DepthImage out(w, h, 0.f);
  const float focal = std::abs(camera.fx);
  const RoundedGaussian shift(params.lateral_sigma_px);
  ParallelFor(size_t(h), 8, [&](size_t begin, size_t end) {
    for (size_t row = begin; row < end; ++row) {
      const int v = int(row);
      for (int u = 0; u < w; ++u) {
        const size_t pixel = size_t(v) * size_t(w) + size_t(u);
        int su = u, sv = v;
        if (params.lateral) {
          const auto [a, b] = rng.Uniform2(pixel, kLateral);
          su = std::clamp(u + shift.Sample(a), 0, w - 1);
          sv = std::clamp(v + shift.Sample(b), 0, h - 1);
        }
        float z = kept.at(su, sv);
        if (!(z > 0.f)) continue;
        if (params.axial) z += AxialSigma(params, z) * rng.Gaussian(pixel, kAxial);
        if (params.quantize) z = QuantizeDepth(params, focal, z);
        out.at(u, v) = z > 0.f ? z : 0.f;
      }
    }
  });
  return out;
}

}  // namespace voxplan
