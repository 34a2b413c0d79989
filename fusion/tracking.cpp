#include "fusion/tracking.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "core/parallel.h"
#include "core/stopwatch.h"

namespace voxplan {

namespace {

constexpr int kLevels = 3;
// Points per reduction chunk: the chunks are fixed by the point count, never by the scheduler,
// and summed in chunk order, so the normal equations are bit-identical for any thread count.
constexpr size_t kPointsPerChunk = 4096;
constexpr size_t kPointsPerFloatRun = 256;  // float partial sums stay short, then go to double
constexpr size_t kMinCorrespondences = 64;  // per level; fewer cannot constrain 6 DoF reliably
// A normal needs its four neighbours on the same surface: depth within this fraction of z.
constexpr float kNormalDepthGate = 0.05f;

using Vec6d = Eigen::Matrix<double, 6, 1>;
using Mat6d = Eigen::Matrix<double, 6, 6>;
// A pixel with a vertex and a normal, packed so the ICP loop streams through memory.
struct InputPoint {
  Eigen::Vector3f p_C;
  Eigen::Vector3f n_C;
  float intensity;  // [0, 1]; 0 without colour
  float pad;
};

struct InputLevel {
  PinholeCamera camera;
  DepthImage depth;
  Image<float> intensity;          // [0, 1]; empty without colour
  std::vector<InputPoint> points;  // pixels with a normal, row-major
  size_t valid_pixels = 0;
};

constexpr int kRowsPerBand = 16;  // rows of one parallel task when building the points

// Reuses the image's storage: the tracker keeps its buffers from frame to frame.
template <typename T>
void Reshape(Image<T>& image, int width, int height, T fill) {
  image.width = width;
  image.height = height;
  image.data.assign(size_t(width) * size_t(height), fill);
}

struct ModelImages {
  PinholeCamera camera;
  RaycastImages raycast;
  Image<float> intensity;                     // empty unless the photometric term is on
  Image<Eigen::Vector2f> intensity_gradient;  // per model pixel
};

// Pixel centres are integers, so coarse pixel u' covers fine pixels 2u' and 2u' + 1 whose centre
// is 2u' + 0.5: c' = (c - 0.5) / 2. The same holds for a negative fy.
PinholeCamera HalfCamera(const PinholeCamera& c) {
  PinholeCamera h;
  h.width = c.width / 2;
  h.height = c.height / 2;
  h.fx = 0.5f * c.fx;
  h.fy = 0.5f * c.fy;
  h.cx = 0.5f * c.cx - 0.25f;
  h.cy = 0.5f * c.cy - 0.25f;
  return h;
}

PinholeCamera LevelCamera(const PinholeCamera& c, int level) {
  PinholeCamera out = c;
  for (int l = 0; l < level; ++l) out = HalfCamera(out);
  return out;
}

// Calls fn(v_begin, v_end) on bands of rows in parallel; each row is written by one task only.
template <typename Fn>
void ForRowBands(int height, const Fn& fn) {
  const size_t num_bands = size_t((height + kRowsPerBand - 1) / kRowsPerBand);
  ParallelFor(num_bands, 1, [&](size_t b0, size_t b1) {
    fn(int(b0) * kRowsPerBand, std::min(int(b1) * kRowsPerBand, height));
  });
}

// Edge-preserving smoothing of valid depth; invalid pixels (0) stay invalid. A 0 neighbour is
// metres away in depth, so its range weight vanishes and it does not pull valid pixels down.
void FilterDepth(const DepthImage& depth, const TrackingParams& p, DepthImage& masked,
                 DepthImage& out) {
  const bool filter = p.bilateral_diameter_px > 0;
  DepthImage& valid = filter ? masked : out;
  Reshape(valid, depth.width, depth.height, 0.f);
  const float lo = p.raycast.min_depth_m, hi = p.raycast.max_depth_m;
  ForRowBands(depth.height, [&](int v0, int v1) {
    for (size_t i = size_t(v0) * size_t(depth.width); i < size_t(v1) * size_t(depth.width); ++i) {
      const float d = depth.data[i];
      valid.data[i] = d >= lo && d <= hi ? d : 0.f;
    }
  });
  if (!filter) return;
  Reshape(out, depth.width, depth.height, 0.f);
  const cv::Mat src(masked.height, masked.width, CV_32F, masked.data.data());
  cv::Mat dst(out.height, out.width, CV_32F, out.data.data());
  cv::bilateralFilter(src, dst, p.bilateral_diameter_px, p.bilateral_sigma_depth_m,
                      p.bilateral_sigma_space_px, cv::BORDER_REPLICATE);
  ForRowBands(depth.height, [&](int v0, int v1) {
    for (size_t i = size_t(v0) * size_t(depth.width); i < size_t(v1) * size_t(depth.width); ++i)
      if (masked.data[i] == 0.f || !std::isfinite(out.data[i])) out.data[i] = 0.f;
  });
}

// Average of the valid pixels of each 2x2 cell that lie within `gate` of the cell's nearest
// valid depth: no averaging across depth edges, so no flying pixels.
void DownsampleDepth(const DepthImage& d, float gate, DepthImage& out) {
  Reshape(out, d.width / 2, d.height / 2, 0.f);
  ForRowBands(out.height, [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v)
      for (int u = 0; u < out.width; ++u) {
        const float z[4] = {d.at(2 * u, 2 * v), d.at(2 * u + 1, 2 * v), d.at(2 * u, 2 * v + 1),
                            d.at(2 * u + 1, 2 * v + 1)};
        float ref = std::numeric_limits<float>::infinity();
        for (float zi : z)
          if (zi > 0.f) ref = std::min(ref, zi);
        if (!std::isfinite(ref)) continue;
        float sum = 0.f;
        int n = 0;
        for (float zi : z)
          if (zi > 0.f && zi - ref <= gate) sum += zi, ++n;
        out.at(u, v) = sum / float(n);
      }
  });
}

float Luma(uint32_t c) {
  return (0.299f * Red(c) + 0.587f * Green(c) + 0.114f * Blue(c)) * (1.f / 255.f);
}

void Intensity(const ColorImage& color, Image<float>& out) {
  Reshape(out, color.width, color.height, 0.f);
  for (size_t i = 0; i < color.data.size(); ++i) out.data[i] = Luma(color.data[i]);
}

void DownsampleIntensity(const Image<float>& in, Image<float>& out) {
  Reshape(out, in.width / 2, in.height / 2, 0.f);
  for (int v = 0; v < out.height; ++v)
    for (int u = 0; u < out.width; ++u)
      out.at(u, v) = 0.25f * (in.at(2 * u, 2 * v) + in.at(2 * u + 1, 2 * v) +
                              in.at(2 * u, 2 * v + 1) + in.at(2 * u + 1, 2 * v + 1));
}

// Points with normals from the cross product of central differences, facing the camera. Depth
// edges (a neighbour off the surface) leave a pixel out. Bands of rows run in parallel and are
// concatenated in order, so the points stay row-major whatever the thread count.
// With stride > 1 only every stride-th pixel of every stride-th row becomes a point (and counts
// as valid); its normal still comes from its direct neighbours.
void BuildPoints(InputLevel& level, int stride, std::vector<std::vector<InputPoint>>& bands) {
  const PinholeCamera& cam = level.camera;
  const DepthImage& d = level.depth;
  const bool has_intensity = !level.intensity.empty();
  const float inv_fx = 1.f / cam.fx, inv_fy = 1.f / cam.fy;
  const size_t num_bands = size_t((d.height + kRowsPerBand - 1) / kRowsPerBand);
  if (bands.size() < num_bands) bands.resize(num_bands);
  std::vector<size_t> band_valid(num_bands, 0);
  ParallelFor(num_bands, 1, [&](size_t b0, size_t b1) {
    for (size_t b = b0; b < b1; ++b) {
      std::vector<InputPoint>& out = bands[b];
      out.clear();
      const int v_begin = int(b) * kRowsPerBand;
      const int v_end = std::min(v_begin + kRowsPerBand, d.height);
      for (int v = (v_begin + stride - 1) / stride * stride; v < v_end; v += stride)
        for (int u = 0; u < d.width; u += stride) {
          const float z = d.at(u, v);
          if (z <= 0.f) continue;
          ++band_valid[b];
          if (u == 0 || v == 0 || u + 1 == d.width || v + 1 == d.height) continue;
          const float gate = kNormalDepthGate * z;
          const float zl = d.at(u - 1, v), zr = d.at(u + 1, v), zu = d.at(u, v - 1),
                      zd = d.at(u, v + 1);
          if (!(std::abs(zl - z) <= gate && std::abs(zr - z) <= gate && std::abs(zu - z) <= gate &&
                std::abs(zd - z) <= gate))
            continue;  // also rejects an invalid (0) neighbour
          // Back-projection with the inverse focal lengths: no division per pixel.
          const float xu = (float(u) - cam.cx) * inv_fx, yv = (float(v) - cam.cy) * inv_fy;
          const Eigen::Vector3f dx((xu + inv_fx) * zr - (xu - inv_fx) * zl, yv * (zr - zl),
                                   zr - zl);
          const Eigen::Vector3f dy(xu * (zd - zu), (yv + inv_fy) * zd - (yv - inv_fy) * zu,
                                   zd - zu);
          Eigen::Vector3f n = dx.cross(dy);
          const float norm2 = n.squaredNorm();
          if (!(norm2 > 0.f)) continue;
          n *= 1.f / std::sqrt(norm2);
          const Eigen::Vector3f p_C(xu * z, yv * z, z);
          // The sign of the cross product flips with fy; orient by the viewing ray instead.
          if (n.dot(p_C) > 0.f) n = -n;
          out.push_back({p_C, n, has_intensity ? level.intensity.at(u, v) : 0.f, 0.f});
        }
    }
  });
  level.valid_pixels = 0;
  size_t total = 0;
  for (size_t b = 0; b < num_bands; ++b) {
    level.valid_pixels += band_valid[b];
    total += bands[b].size();
  }
  level.points.clear();
  level.points.reserve(total);
  for (size_t b = 0; b < num_bands; ++b)
    level.points.insert(level.points.end(), bands[b].begin(), bands[b].end());
}

// SE(3) exponential of xi = (v, w): rotation exp(w), translation V(w) v.
Pose3d ExpSe3(const Vec6d& xi) {
  const Eigen::Vector3d v = xi.head<3>(), w = xi.tail<3>();
  const double theta = w.norm();
  Eigen::Matrix3d W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity(), V = Eigen::Matrix3d::Identity();
  if (theta < 1e-10) {
    R += W;
    V += 0.5 * W;
  } else {
    const double a = std::sin(theta) / theta, b = (1 - std::cos(theta)) / (theta * theta),
                 c = (theta - std::sin(theta)) / (theta * theta * theta);
    R += a * W + b * W * W;
    V += b * W + c * W * W;
  }
  Pose3d T = Pose3d::Identity();
  T.linear() = R;
  T.translation() = V * v;
  return T;
}

struct NormalEquations {
  Mat6d H = Mat6d::Zero();
  Vec6d g = Vec6d::Zero();
  double geometric_r2 = 0.0;  // unweighted point-to-plane residuals of the inliers
  Eigen::Vector3d sum_p_W = Eigen::Vector3d::Zero();  // of the inliers, for the conditioning
  double sum_p_W2 = 0.0;
  size_t inliers = 0;
  size_t model_hits = 0;  // input points that land on a model pixel with a surface
  size_t photometric = 0;
};

// Weighted residual terms of one short run, stored column-wise ([J, r] and the weight) and
// reduced after the run in eight fixed lanes: the products then vectorise across terms without
// reassociating anything, so the sums stay deterministic.
struct TermBatch {
  static constexpr int kCapacity = 2 * int(kPointsPerFloatRun);  // geometric + photometric
  static constexpr int kLanes = 8;
  alignas(32) float jr[7][kCapacity];  // J_0..J_5, r
  alignas(32) float w[kCapacity];
  int n = 0;
  float r2 = 0.f;
  float p[4] = {};  // x, y, z, squared norm of the inliers

  void Clear() {
    n = 0;
    r2 = 0.f;
    for (float& v : p) v = 0.f;
  }
  void Add(const float (&Jr)[7], float weight) {
    for (int k = 0; k < 7; ++k) jr[k][n] = Jr[k];
    w[n] = weight;
    ++n;
  }
  // Adds sum_k w_k J_i,k [J, r]_j,k for i < 6, j in [i, 7) into a[i][j].
  void ReduceInto(double (&a)[6][8]) {
    const int padded = (n + kLanes - 1) / kLanes * kLanes;
    for (int k = n; k < padded; ++k) {
      w[k] = 0.f;
      for (int c = 0; c < 7; ++c) jr[c][k] = 0.f;
    }
    alignas(32) float wj[kCapacity];
    for (int i = 0; i < 6; ++i) {
      for (int k = 0; k < padded; ++k) wj[k] = w[k] * jr[i][k];
      for (int j = i; j < 7; ++j) {
        float lane[kLanes] = {};
        for (int k = 0; k < padded; k += kLanes)
          for (int l = 0; l < kLanes; ++l) lane[l] += wj[k + l] * jr[j][k + l];
        float sum = 0.f;
        for (int l = 0; l < kLanes; ++l) sum += lane[l];
        a[i][j] += double(sum);
      }
    }
  }
};

// Per chunk in double, from short float runs, so precision does not depend on the image size.
struct ChunkSums {
  double a[6][8] = {};
  double r2 = 0.0;
  double p[4] = {};
  size_t inliers = 0;
  size_t model_hits = 0;
  size_t photometric = 0;

  void Add(TermBatch& batch) {
    batch.ReduceInto(a);
    r2 += double(batch.r2);
    for (int k = 0; k < 4; ++k) p[k] += double(batch.p[k]);
  }
  void Add(const ChunkSums& c) {
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 8; ++j) a[i][j] += c.a[i][j];
    r2 += c.r2;
    for (int k = 0; k < 4; ++k) p[k] += c.p[k];
    inliers += c.inliers;
    model_hits += c.model_hits;
    photometric += c.photometric;
  }
};

float HuberWeight(float r, float delta) {
  const float a = std::abs(r);
  return a <= delta ? 1.f : delta / a;
}

// Bilinear sample of the model intensity and its gradient at (x, y); false unless all four
// neighbours hold a hit.
bool SampleModelIntensity(const ModelImages& m, float x, float y, float* value,
                          Eigen::Vector2f* gradient) {
  const int u0 = int(std::floor(x)), v0 = int(std::floor(y));
  if (u0 < 1 || v0 < 1 || u0 + 2 >= m.camera.width || v0 + 2 >= m.camera.height) return false;
  const float fx = x - float(u0), fy = y - float(v0);
  const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  const int us[4] = {u0, u0 + 1, u0, u0 + 1}, vs[4] = {v0, v0, v0 + 1, v0 + 1};
  float val = 0.f;
  Eigen::Vector2f grad = Eigen::Vector2f::Zero();
  for (int k = 0; k < 4; ++k) {
    if (m.raycast.status.at(us[k], vs[k]) != uint8_t(RayStatus::kHit)) return false;
    val += w[k] * m.intensity.at(us[k], vs[k]);
    grad += w[k] * m.intensity_gradient.at(us[k], vs[k]);
  }
  *value = val;
  *gradient = grad;
  return true;
}

// One Gauss-Newton system for the input level at the current estimate. Input vertices move
// with T_W_C, are projected into the model image (raycast at T_W_C_pred) and paired with the
// model pixel they land on; increments are left-multiplied: T <- exp(xi) T, so dp_W/dxi =
// [I, -[p_W]x] and d(n . (p_W - q_W))/dxi = [n, p_W x n].
NormalEquations BuildSystem(const InputLevel& in, const ModelImages& model, const Pose3f& T_W_C,
                            const Pose3f& T_C_W_pred, const TrackingParams& p, bool photometric) {
  const size_t num_points = in.points.size();
  const size_t num_chunks = (num_points + kPointsPerChunk - 1) / kPointsPerChunk;
  std::vector<ChunkSums> partial(num_chunks);
  const float cos_gate = std::cos(p.max_normal_angle_deg * float(M_PI) / 180.f);
  const float max_dist2 = p.max_correspondence_m * p.max_correspondence_m;
  const Eigen::Matrix3f R_W_C = T_W_C.linear();
  const Eigen::Vector3f t_W_C = T_W_C.translation();
  const Eigen::Matrix3f R_Cp_W = T_C_W_pred.linear();
  // Input camera straight to the predicted (model) camera: the world point is only needed once
  // a pixel is hit.
  const Pose3f T_Cp_C = T_C_W_pred * T_W_C;
  const Eigen::Matrix3f R_Cp_C = T_Cp_C.linear();
  const Eigen::Vector3f t_Cp_C = T_Cp_C.translation();
  const PinholeCamera& mc = model.camera;
  const float photo_weight = p.photometric_weight;
  const float max_x = float(mc.width) - 0.5f, max_y = float(mc.height) - 0.5f;

  ParallelFor(num_chunks, 1, [&](size_t c0, size_t c1) {
    const auto batch = std::make_unique<TermBatch>();  // 16 kB: off the task's stack
    for (size_t c = c0; c < c1; ++c) {
      ChunkSums& sums = partial[c];
      const size_t end = std::min((c + 1) * kPointsPerChunk, num_points);
      for (size_t run = c * kPointsPerChunk; run < end; run += kPointsPerFloatRun) {
        TermBatch& f = *batch;
        f.Clear();
        const size_t run_end = std::min(run + kPointsPerFloatRun, end);
        for (size_t i = run; i < run_end; ++i) {
          const InputPoint& pt = in.points[i];
          const Eigen::Vector3f p_Cp = R_Cp_C * pt.p_C + t_Cp_C;
          if (p_Cp.z() <= 0.f) continue;
          const float inv_z = 1.f / p_Cp.z();
          const float x = mc.fx * p_Cp.x() * inv_z + mc.cx, y = mc.fy * p_Cp.y() * inv_z + mc.cy;
          // Nearest model pixel; the range test first keeps the int conversion defined.
          if (!(x > -0.5f && y > -0.5f && x < max_x && y < max_y)) continue;
          const int mu = int(x + 0.5f), mv = int(y + 0.5f);
          const Eigen::Vector3f& q_W = model.raycast.vertex_W.at(mu, mv);
          if (!std::isfinite(q_W.x())) continue;
          ++sums.model_hits;
          const Eigen::Vector3f p_W = R_W_C * pt.p_C + t_W_C;
          const Eigen::Vector3f diff = p_W - q_W;
          if (diff.squaredNorm() > max_dist2) continue;
          const Eigen::Vector3f& n_W = model.raycast.normal_W.at(mu, mv);
          if (!((R_W_C * pt.n_C).dot(n_W) >= cos_gate)) continue;  // also rejects a NaN normal
          const float r = n_W.dot(diff);
          const Eigen::Vector3f pxn = p_W.cross(n_W);
          const float J[7] = {n_W.x(), n_W.y(), n_W.z(), pxn.x(), pxn.y(), pxn.z(), r};
          f.Add(J, HuberWeight(r, p.huber_delta_m));
          f.r2 += r * r;
          f.p[0] += p_W.x(), f.p[1] += p_W.y(), f.p[2] += p_W.z();
          f.p[3] += p_W.squaredNorm();
          ++sums.inliers;
          if (!photometric) continue;
          float model_i;
          Eigen::Vector2f grad;
          if (!SampleModelIntensity(model, x, y, &model_i, &grad)) continue;
          const float rp = model_i - pt.intensity;
          const float wp = HuberWeight(rp, p.photometric_huber_delta);
          // d pixel / d p_Cp, then back to world: the gradient as a world-space direction.
          const Eigen::Vector3f d_pix_x(mc.fx * inv_z, 0.f, -mc.fx * p_Cp.x() * inv_z * inv_z);
          const Eigen::Vector3f d_pix_y(0.f, mc.fy * inv_z, -mc.fy * p_Cp.y() * inv_z * inv_z);
          const Eigen::Vector3f g_Cp = grad.x() * d_pix_x + grad.y() * d_pix_y;
          const Eigen::Vector3f g_W = R_Cp_W.transpose() * g_Cp;
          const Eigen::Vector3f pxg = p_W.cross(g_W);
          const float Jp[7] = {g_W.x(), g_W.y(), g_W.z(), pxg.x(), pxg.y(), pxg.z(), rp};
          f.Add(Jp, photo_weight * wp);
          ++sums.photometric;
        }
        sums.Add(f);
      }
    }
  });
  ChunkSums total;
  for (const ChunkSums& cs : partial) total.Add(cs);  // fixed order: deterministic
  NormalEquations ne;
  for (int i = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) ne.H(i, j) = ne.H(j, i) = total.a[i][j];
    ne.g(i) = total.a[i][6];
  }
  ne.geometric_r2 = total.r2;
  ne.sum_p_W = Eigen::Vector3d(total.p[0], total.p[1], total.p[2]);
  ne.sum_p_W2 = total.p[3];
  ne.inliers = total.inliers;
  ne.model_hits = total.model_hits;
  ne.photometric = total.photometric;
  return ne;
}

// Condition number of the system re-expressed with rotations about the centroid of the
// correspondences and scaled by their spread (radians to metres): it then measures the geometry,
// not where the world origin lies or how far away the scene is.
double NormalizedConditionNumber(const NormalEquations& ne) {
  const double n = double(ne.inliers);
  const Eigen::Vector3d c = ne.sum_p_W / n;
  const double spread = std::sqrt(std::max(ne.sum_p_W2 / n - c.squaredNorm(), 1e-12));
  Eigen::Matrix3d c_x;
  c_x << 0, -c.z(), c.y(), c.z(), 0, -c.x(), -c.y(), c.x(), 0;
  // J' = M J with J = [n; p x n]: rows 3-5 become (p - c) x n / spread.
  Mat6d M = Mat6d::Identity();
  M.block<3, 3>(3, 0) = -c_x;
  M.bottomRows<3>() /= spread;
  const Mat6d H = M * ne.H * M.transpose();
  const Eigen::SelfAdjointEigenSolver<Mat6d> eig(H, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()(0), hi = eig.eigenvalues()(5);
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

ModelImages BuildModel(const TsdfVolume& volume, const PinholeCamera& camera,
                       const Pose3f& T_W_C_pred, const TrackingParams& p, bool photometric) {
  ModelImages m;
  m.camera = camera;
  m.raycast = Raycast(volume, camera, T_W_C_pred, p.raycast);
  if (!photometric) return m;
  Intensity(m.raycast.color, m.intensity);
  m.intensity_gradient =
      Image<Eigen::Vector2f>(camera.width, camera.height, Eigen::Vector2f::Zero());
  const auto hit = [&](int u, int v) {
    return m.raycast.status.at(u, v) == uint8_t(RayStatus::kHit);
  };
  for (int v = 1; v + 1 < camera.height; ++v)
    for (int u = 1; u + 1 < camera.width; ++u) {
      // Differences across a silhouette would be background, not texture: left at zero.
      if (!hit(u - 1, v) || !hit(u + 1, v) || !hit(u, v - 1) || !hit(u, v + 1)) continue;
      m.intensity_gradient.at(u, v) = {
          0.5f * (m.intensity.at(u + 1, v) - m.intensity.at(u - 1, v)),
          0.5f * (m.intensity.at(u, v + 1) - m.intensity.at(u, v - 1))};
    }
  return m;
}

bool IsFinite(const Pose3d& T) { return T.matrix().allFinite(); }

}  // namespace

// Buffers kept from frame to frame (the input pyramid is a few MB at 640x480).
struct FrameTracker::Workspace {
  std::array<InputLevel, kLevels> levels;
  DepthImage masked_depth;
  std::vector<std::vector<InputPoint>> bands;
};

FrameTracker::~FrameTracker() = default;
FrameTracker::FrameTracker(FrameTracker&&) noexcept = default;
FrameTracker& FrameTracker::operator=(FrameTracker&&) noexcept = default;

FrameTracker::FrameTracker(const PinholeCamera& camera, const TrackingParams& params)
    : camera_(camera), params_(params), workspace_(std::make_unique<Workspace>()) {
  if (!camera.Valid()) throw std::invalid_argument("FrameTracker: invalid camera");
  if (camera.width < 4 << (kLevels - 1) || camera.height < 4 << (kLevels - 1))
    throw std::invalid_argument("FrameTracker: image too small for the pyramid");
  if (params.model_level < 0 || params.model_level >= kLevels)
    throw std::invalid_argument("FrameTracker: model_level must be in [0, 3)");
  if (params.finest_level_stride < 1)
    throw std::invalid_argument("FrameTracker: finest_level_stride must be at least 1");
}

void FrameTracker::Reset(const Pose3f& T_W_C) {
  last_T_W_C_ = T_W_C;
  previous_T_W_C_.reset();
}

void FrameTracker::Accept(const Pose3f& T_W_C) {
  previous_T_W_C_ = last_T_W_C_;
  last_T_W_C_ = T_W_C;
}

Pose3f FrameTracker::Predict() const {
  if (!params_.constant_velocity || !previous_T_W_C_) return last_T_W_C_;
  // The last inter-frame motion, expressed in the last camera frame, applied once more.
  const Pose3d last = last_T_W_C_.cast<double>();
  const Pose3d T_prev_last = previous_T_W_C_->cast<double>().inverse() * last;
  Pose3d pred = last * T_prev_last;
  // Re-orthonormalise so repeated prediction does not drift off SO(3).
  pred.linear() = Eigen::Quaterniond(pred.linear()).normalized().toRotationMatrix();
  return pred.cast<float>();
}

Result<TrackingResult> FrameTracker::Track(const DepthImage& depth, const ColorImage& color,
                                           const TsdfVolume& volume) {
  return Track(depth, color, volume, Predict());
}

Result<TrackingResult> FrameTracker::Track(const DepthImage& depth, const ColorImage& color,
                                           const TsdfVolume& volume, const Pose3f& T_W_C_pred) {
  if (depth.width != camera_.width || depth.height != camera_.height)
    return InvalidArgument("Track: depth is " + std::to_string(depth.width) + "x" +
                           std::to_string(depth.height) + ", camera is " +
                           std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  if (!color.empty() && (color.width != depth.width || color.height != depth.height))
    return InvalidArgument("Track: colour and depth sizes differ");
  const Stopwatch total_clock;
  TrackingResult result;
  result.T_W_C = T_W_C_pred;
  const bool photometric = params_.photometric_weight > 0.f && !color.empty();

  // Input pyramid.
  Stopwatch clock;
  std::array<InputLevel, kLevels>& levels = workspace_->levels;
  levels[0].camera = camera_;
  FilterDepth(depth, params_, workspace_->masked_depth, levels[0].depth);
  if (photometric) Intensity(color, levels[0].intensity);
  for (int l = 1; l < kLevels; ++l) {
    levels[l].camera = HalfCamera(levels[l - 1].camera);
    DownsampleDepth(levels[l - 1].depth, params_.pyramid_depth_gate_m, levels[l].depth);
    if (photometric) DownsampleIntensity(levels[l - 1].intensity, levels[l].intensity);
  }
  for (int l = 0; l < kLevels; ++l) {
    InputLevel& level = levels[size_t(l)];
    if (!photometric) level.intensity = Image<float>();
    BuildPoints(level, l == 0 ? params_.finest_level_stride : 1, workspace_->bands);
  }
  result.filter_ms = clock.ElapsedMs();
  const auto finish = [&](std::string failure) {
    result.ok = failure.empty();
    result.failure = std::move(failure);
    if (!result.ok) result.T_W_C = T_W_C_pred;
    result.track_ms = total_clock.ElapsedMs();
    return result;
  };
  if (levels[0].valid_pixels == 0) return finish("no valid depth in the frame");

  clock.Restart();
  const ModelImages model = BuildModel(volume, LevelCamera(camera_, params_.model_level),
                                       T_W_C_pred, params_, photometric);
  result.raycast_ms = clock.ElapsedMs();

  clock.Restart();
  const Pose3f T_C_W_pred = T_W_C_pred.inverse();
  Pose3d T_W_C = T_W_C_pred.cast<double>();
  NormalEquations last;
  for (int l = kLevels - 1; l >= 0; --l) {
    for (int it = 0; it < params_.iterations[size_t(l)]; ++it) {
      last = BuildSystem(levels[size_t(l)], model, T_W_C.cast<float>(), T_C_W_pred, params_,
                         photometric);
      ++result.iterations;
      ++result.level_iterations[size_t(l)];
      if (last.inliers < kMinCorrespondences) {
        result.icp_ms = clock.ElapsedMs();
        result.no_model = last.model_hits < kMinCorrespondences;
        return finish("too few correspondences with the model (" + std::to_string(last.inliers) +
                      " at level " + std::to_string(l) + ")");
      }
      result.condition_number = float(NormalizedConditionNumber(last));
      // A degenerate system has no unique solution; solving it would only move the pose
      // along the free directions. Coarse levels, with few and smoothed points, may be
      // degenerate where the full frame is not: they hand over to the next level unchanged;
      // the finest level decides.
      if (!(result.condition_number <= params_.max_condition_number)) {
        if (l > 0) break;
        result.icp_ms = clock.ElapsedMs();
        return finish("degenerate geometry: condition number " +
                      std::to_string(result.condition_number) + " > " +
                      std::to_string(params_.max_condition_number));
      }
      const Vec6d xi = last.H.ldlt().solve(-last.g);
      if (!xi.allFinite()) {
        result.icp_ms = clock.ElapsedMs();
        return finish("non-finite Gauss-Newton update");
      }
      T_W_C = ExpSe3(xi) * T_W_C;
      // A coarse level only has to bring the pose into the next level's reach: its pixels are
      // 2^l times larger, and so is the increment at which it stops.
      if (xi.norm() < params_.min_update * float(1 << l)) break;
    }
  }
  result.icp_ms = clock.ElapsedMs();
  T_W_C.linear() = Eigen::Quaterniond(T_W_C.linear()).normalized().toRotationMatrix();

  // Statistics of the finest level's last system (one step before the final pose).
  result.inliers = last.inliers;
  result.inlier_ratio = float(double(last.inliers) / double(levels[0].valid_pixels));
  result.residual_rms_m = float(std::sqrt(last.geometric_r2 / double(last.inliers)));
  if (!IsFinite(T_W_C)) return finish("non-finite pose estimate");
  result.T_W_C = T_W_C.cast<float>();
  if (result.inlier_ratio < params_.min_inlier_ratio)
    return finish("inlier ratio " + std::to_string(result.inlier_ratio) + " < " +
                  std::to_string(params_.min_inlier_ratio));
  if (result.residual_rms_m > params_.max_residual_rms_m)
    return finish("residual RMS " + std::to_string(result.residual_rms_m) + " m > " +
                  std::to_string(params_.max_residual_rms_m) + " m");
  const float jump_m = (result.T_W_C.translation() - T_W_C_pred.translation()).norm();
  if (jump_m > params_.max_motion_m)
    return finish("jump from the prediction " + std::to_string(jump_m) + " m > " +
                  std::to_string(params_.max_motion_m) + " m");
  return finish("");
}

}  // namespace voxplan
