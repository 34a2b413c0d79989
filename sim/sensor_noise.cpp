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
#include "sim/split_mix.h"

namespace voxplan {

namespace {

// Counter-based randomness: every draw is a hash of (seed, frame, pixel, stream), so a pixel's
// noise is the same whichever thread computes it. One 64-bit hash gives two 32-bit uniforms.
enum Stream : uint64_t { kEdge = 0, kLateral = 1, kAxial = 2, kNumStreams = 3 };

constexpr double kTwoPow32 = 4294967296.0;

struct PixelRng {
  uint64_t frame_key;
  uint64_t Bits(size_t pixel, uint64_t stream) const {
    return SplitMix64(frame_key ^ (uint64_t(pixel) * kNumStreams + stream));
  }
};

// Uniform in (0, 1] from 32 bits: log() of it stays finite.
double UniformOpen(uint64_t bits32) { return (double(bits32 & 0xffffffffu) + 1.0) / kTwoPow32; }

// Standard normals by Marsaglia and Tsang's ziggurat (2000, 128 layers): one 64-bit hash gives
// one draw ~98.8 % of the time with a compare and a multiply; Box-Muller's log, sqrt and cos per
// pixel cost as much as rendering the frame. The layer index comes from bits apart from the
// value's, which avoids the correlation of the original (one 32-bit word for both).
class Ziggurat {
 public:
  Ziggurat() {
    const double m1 = 2147483648.0;  // 2^31: |hz| of a signed 32-bit draw
    double dn = kR, tn = kR;
    const double q = kV / std::exp(-0.5 * dn * dn);
    kn_[0] = uint32_t(dn / q * m1);
    kn_[1] = 0;
    wn_[0] = q / m1;
    wn_[127] = dn / m1;
    fn_[0] = 1.0;
    fn_[127] = std::exp(-0.5 * dn * dn);
    for (int i = 126; i >= 1; --i) {
      dn = std::sqrt(-2.0 * std::log(kV / dn + std::exp(-0.5 * dn * dn)));
      kn_[i + 1] = uint32_t(dn / tn * m1);
      tn = dn;
      fn_[i] = std::exp(-0.5 * dn * dn);
      wn_[i] = dn / m1;
    }
  }

  // `bits` are the pixel's random word; `more()` gives further words for the rare rejections,
  // so the draw stays a function of the pixel's hash alone.
  template <class More>
  float Sample(uint64_t bits, More&& more) const {
    for (;;) {
      const int32_t hz = int32_t(uint32_t(bits >> 32));
      const uint32_t iz = uint32_t(bits) & 127u;
      const uint32_t mag = uint32_t(hz < 0 ? -int64_t(hz) : int64_t(hz));
      const double x = double(hz) * wn_[iz];
      if (mag < kn_[iz]) return float(x);  // inside the layer's rectangle
      if (iz == 0) {                       // the base layer's tail beyond kR (Marsaglia 1964)
        double xt = 0.0, y = 0.0;
        do {
          const uint64_t b = more();
          xt = -std::log(UniformOpen(b >> 32)) / kR;
          y = -std::log(UniformOpen(b));
        } while (y + y < xt * xt);
        return float(hz > 0 ? kR + xt : -(kR + xt));
      }
      // The wedge between the rectangle and the density.
      const double u = double(more() >> 11) * 0x1p-53;
      if (fn_[iz] + u * (fn_[iz - 1] - fn_[iz]) < std::exp(-0.5 * x * x)) return float(x);
      bits = more();
    }
  }

 private:
  static constexpr double kR = 3.442619855899;       // start of the tail
  static constexpr double kV = 9.91256303526217e-3;  // area of each layer
  uint32_t kn_[128];
  double wn_[128], fn_[128];
};

const Ziggurat& StandardNormal() {
  static const Ziggurat table;
  return table;
}

// The pixel shift round(N(0, σ)) by inverse CDF: the count of 32-bit thresholds a uniform word
// reaches. A table over the word's top byte answers at once wherever its bucket holds a single
// shift (all but a few of the 256); only buckets that straddle a threshold count.
class RoundedGaussian {
 public:
  explicit RoundedGaussian(float sigma) {
    if (!(sigma > 0.f)) return;
    const int k_max = std::min(64, int(std::ceil(6.f * sigma)) + 1);
    offset_ = -k_max;
    for (int k = -k_max; k < k_max; ++k) {
      // P(round(x) <= k) scaled to 32 bits: word >= threshold <=> word / 2^32 >= P.
      const double cdf =
          0.5 * std::erfc(-(double(k) + 0.5) / (double(sigma) * std::numbers::sqrt2));
      thresholds_.push_back(uint64_t(std::ceil(cdf * kTwoPow32)));
    }
    for (uint32_t b = 0; b < 256; ++b) {
      const int lo = Count(b << 24), hi = Count((b << 24) | 0xffffffu);
      bucket_[b] = lo == hi ? int8_t(offset_ + lo) : kStraddles;
    }
  }
  int Sample(uint32_t word) const {
    const int8_t s = bucket_[word >> 24];
    return s != kStraddles ? s : offset_ + Count(word);
  }
  bool empty() const { return thresholds_.empty(); }

 private:
  static constexpr int8_t kStraddles = -128;  // shifts are within [-64, 64]
  int Count(uint32_t word) const {
    int count = 0;
    for (uint64_t t : thresholds_) count += uint64_t(word) >= t ? 1 : 0;
    return count;
  }
  int offset_ = 0;
  std::vector<uint64_t> thresholds_;
  int8_t bucket_[256] = {};
};

// The disparity model with f b / step precomputed: one division to the disparity index, one back.
struct Quantizer {
  float fb_per_step;
  float operator()(float z_m) const {
    if (!(z_m > 0.f)) return 0.f;
    const float x = fb_per_step / z_m + 0.5f;
    if (x < 1.f) return 0.f;  // beyond the farthest representable disparity: no return
    // floor(): truncation for positive values, which fit an int below 2^24 (whole above).
    const float steps = x < 16777216.f ? float(int32_t(x)) : x;
    return fb_per_step / steps;
  }
};

Quantizer MakeQuantizer(const KinectNoiseParams& params, float focal_px) {
  return {std::abs(focal_px) * params.baseline_m / params.disparity_step_px};
}

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
  return MakeQuantizer(params, focal_px)(z_m);
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

  // Pass 1: which clean pixels survive the dropouts (1 = kept). The edge test compares a pixel
  // with the nearest valid depth within edge_radius_px (a separable min filter, misses counting
  // as infinitely far), done per chunk of rows with the r rows around it.
  const bool edges = params.edge_dropout && params.edge_dropout_probability > 0.f;
  const int r = edges ? params.edge_radius_px : 0;
  const float far = std::numeric_limits<float>::infinity();
  const float min_cos2 = min_cos * min_cos;
  std::vector<uint8_t> kept(size_t(w) * size_t(h), 0);
  ParallelFor(size_t(h), 16, [&](size_t begin, size_t end) {
    const int v_lo = std::max(0, int(begin) - r), v_hi = std::min(h, int(end) + r);
    std::vector<float> row_min;
    if (edges) {
      row_min.assign(size_t(v_hi - v_lo) * size_t(w), far);
      for (int v = v_lo; v < v_hi; ++v) {
        const float* z_row = &depth.at(0, v);
        float* m_row = &row_min[size_t(v - v_lo) * size_t(w)];
        for (int u = 0; u < w; ++u) {
          float m = far;
          for (int uu = std::max(0, u - r); uu <= std::min(w - 1, u + r); ++uu)
            m = std::min(m, z_row[uu] > 0.f ? z_row[uu] : far);
          m_row[u] = m;
        }
      }
    }
    std::vector<float> nearest(edges ? size_t(w) : 0);
    for (size_t row = begin; row < end; ++row) {
      const int v = int(row);
      const float* z_row = &depth.at(0, v);
      uint8_t* k_row = &kept[row * size_t(w)];
      if (edges) {
        const int v0 = std::max(0, v - r), v1 = std::min(h - 1, v + r);
        std::copy_n(&row_min[size_t(v0 - v_lo) * size_t(w)], w, nearest.begin());
        for (int vv = v0 + 1; vv <= v1; ++vv) {
          const float* m_row = &row_min[size_t(vv - v_lo) * size_t(w)];
          for (int u = 0; u < w; ++u) nearest[size_t(u)] = std::min(nearest[size_t(u)], m_row[u]);
        }
      }
      const float ry = ray_y[row];
      for (int u = 0; u < w; ++u) {
        const float z = z_row[u];
        if (!(z > 0.f)) continue;
        if (params.grazing_dropout) {
          // |n . r| < cos(max) |r| with a unit normal, squared (no square roots).
          const Eigen::Vector3f& n = normals->at(u, v);
          const float rx = ray_x[size_t(u)];
          const float dot = n.x() * rx + n.y() * ry + n.z();
          if (n.squaredNorm() > 0.f && dot * dot < min_cos2 * (rx * rx + ry * ry + 1.f)) continue;
        }
        if (edges && z - nearest[size_t(u)] > params.edge_jump_m + params.edge_jump_fraction * z) {
          const size_t pixel = size_t(v) * size_t(w) + size_t(u);
          if (double(rng.Bits(pixel, kEdge) >> 32) / kTwoPow32 < params.edge_dropout_probability)
            continue;
        }
        k_row[u] = 1;
      }
    }
  });

  // Pass 2: lateral jitter, axial noise and quantisation per output pixel.
  DepthImage out(w, h, 0.f);
  const RoundedGaussian shift(params.lateral_sigma_px);
  const bool lateral = params.lateral && !shift.empty();
  const Ziggurat& normal = StandardNormal();
  const Quantizer quantize = MakeQuantizer(params, camera.fx);
  const float s0 = params.axial_sigma0_m, s2 = params.axial_sigma2, z0 = params.axial_z0_m;
  ParallelFor(size_t(h), 16, [&](size_t begin, size_t end) {
    for (size_t row = begin; row < end; ++row) {
      const int v = int(row);
      float* out_row = &out.at(0, v);
      for (int u = 0; u < w; ++u) {
        const size_t pixel = size_t(v) * size_t(w) + size_t(u);
        int su = u, sv = v;
        if (lateral) {
          const uint64_t b = rng.Bits(pixel, kLateral);
          su = std::clamp(u + shift.Sample(uint32_t(b >> 32)), 0, w - 1);
          sv = std::clamp(v + shift.Sample(uint32_t(b)), 0, h - 1);
        }
        const size_t source = size_t(sv) * size_t(w) + size_t(su);
        if (!kept[source]) continue;
        float z = depth.data[source];
        if (params.axial) {
          uint64_t key = rng.Bits(pixel, kAxial);
          const float n = normal.Sample(key, [&key] { return key = SplitMix64(key); });
          const float dz = z - z0;
          z += (s0 + s2 * dz * dz) * n;
        }
        if (params.quantize) z = quantize(z);
        out_row[u] = z > 0.f ? z : 0.f;
      }
    }
  });
  return out;
}

}  // namespace voxplan
