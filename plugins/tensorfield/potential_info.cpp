#include "plugins/tensorfield/potential_info.h"

#include <algorithm>
#include <cmath>

#include "plugins/tensorfield/frames.h"

namespace voxplan::tensorfield {
namespace {

// One pass of a 1-D convolution with `kernel` (odd length, centred) along x (stride 1) or y
// (stride width); beyond the raster counts as zero.
std::vector<double> Convolve(const omt::RasterGeometry& g, const std::vector<double>& in,
                             const std::vector<double>& kernel, bool along_x) {
  std::vector<double> out(in.size(), 0.0);
  const int r = static_cast<int>(kernel.size() / 2);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const int lo = std::max(-r, along_x ? -x : -y);
      const int hi = std::min(r, along_x ? g.width - 1 - x : g.height - 1 - y);
      double sum = 0.0;
      for (int k = lo; k <= hi; ++k) {
        const int i = along_x ? g.Index(x + k, y) : g.Index(x, y + k);
        sum += kernel[static_cast<std::size_t>(k + r)] * in[static_cast<std::size_t>(i)];
      }
      out[static_cast<std::size_t>(g.Index(x, y))] = sum;
    }
  return out;
}

}  // namespace

std::vector<double> SolvePotentialInfo(const omt::RasterGeometry& g,
                                       std::span<const std::uint8_t> codes,
                                       std::span<const float> clearance_m,
                                       const PotentialInfoParams& params) {
  const std::size_t n = static_cast<std::size_t>(std::max(0, g.NumCells()));
  std::vector<double> phi(n, 0.0);
  if (codes.size() != n || clearance_m.size() != n || n == 0) return phi;
  std::vector<double> info(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    info[i] = codes[i] == kFloorUnknown || codes[i] == kFloorFrontier ? 1.0 : 0.0;
  const double sigma_cells = std::max(1e-6, params.sigma_m / g.resolution_m);
  const int r = static_cast<int>(std::ceil(params.truncation_sigmas * sigma_cells));
  std::vector<double> kernel(static_cast<std::size_t>(2 * r + 1));
  for (int k = -r; k <= r; ++k)
    kernel[static_cast<std::size_t>(k + r)] = std::exp(-0.5 * k * k / (sigma_cells * sigma_cells));
  const std::vector<double> blurred = Convolve(g, Convolve(g, info, kernel, true), kernel, false);
  const double top = *std::max_element(blurred.begin(), blurred.end());
  const double scale = top > 0.0 ? 1.0 / top : 0.0;
  const double c0 = params.repulse_within_m;
  for (std::size_t i = 0; i < n; ++i) {
    const double c = std::max(1e-3, static_cast<double>(clearance_m[i]));
    const double rep = c < c0 ? params.repulse_gain * std::pow(1.0 / c - 1.0 / c0, 2) : 0.0;
    phi[i] = -scale * blurred[i] + rep;
  }
  return phi;
}

}  // namespace voxplan::tensorfield
