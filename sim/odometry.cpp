#include "sim/odometry.h"

#include <Eigen/Geometry>
#include <cmath>

#include "sim/split_mix.h"

namespace voxplan {

namespace {

// Standard normal number k of (seed, stream) by Box-Muller over two 32-bit uniforms in (0, 1].
double Normal(uint64_t seed, uint64_t stream, uint64_t k) {
  const uint64_t bits = SplitMix64(SplitMix64(seed ^ 0x0d0e7e11ull) ^ (stream * 8 + k));
  const double u1 = (double(bits & 0xffffffffu) + 1.0) / 4294967296.0;
  const double u2 = (double(bits >> 32) + 1.0) / 4294967296.0;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

}  // namespace

Pose3f NoisyOdometry(const Pose3f& delta_C, const OdometryNoiseParams& params, uint64_t seed,
                     uint64_t stream) {
  const Eigen::Vector3d t = delta_C.translation().cast<double>();
  const double moved = t.norm();
  const double turned = Eigen::AngleAxisd(delta_C.linear().cast<double>()).angle();
  const double sigma_t = double(params.translation_per_m) * moved;
  const double sigma_r =
      double(params.rotation_per_rad) * turned + double(params.rotation_per_m) * moved;
  Eigen::Vector3d dt, dr;
  for (int a = 0; a < 3; ++a) {
    dt[a] = sigma_t * Normal(seed, stream, uint64_t(a));
    dr[a] = sigma_r * Normal(seed, stream, uint64_t(3 + a));
  }
  Eigen::Isometry3d noisy = delta_C.cast<double>();
  noisy.translation() += dt;
  if (dr.norm() > 0.0)
    noisy.linear() =
        noisy.linear() * Eigen::AngleAxisd(dr.norm(), dr.normalized()).toRotationMatrix();
  return noisy.cast<float>();
}

}  // namespace voxplan
