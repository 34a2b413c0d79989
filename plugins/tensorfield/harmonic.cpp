#include "plugins/tensorfield/harmonic.h"

#include <algorithm>
#include <cmath>

#include "plugins/tensorfield/frames.h"

namespace voxplan::tensorfield {

std::vector<double> SolveHarmonic(const omt::RasterGeometry& g, std::span<const std::uint8_t> codes,
                                  const HarmonicParams& params) {
  const int n = g.NumCells();
  std::vector<double> phi(static_cast<std::size_t>(n), 1.0);
  if (codes.size() != static_cast<std::size_t>(n)) return phi;
  for (int i = 0; i < n; ++i)
    if (codes[static_cast<std::size_t>(i)] == kFloorFrontier)
      phi[static_cast<std::size_t>(i)] = 0.0;
  const auto free = [&](int i) { return codes[static_cast<std::size_t>(i)] == kFloorFree; };
  // Gauss-Seidel order, row by row: the same sweeps give the same φ bit for bit.
  for (int sweep = 0; sweep < params.max_sweeps; ++sweep) {
    double change = 0.0;
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x) {
        const int i = g.Index(x, y);
        if (!free(i)) continue;
        // Beyond the window's edge counts as unknown (1).
        const double l = x > 0 ? phi[static_cast<std::size_t>(i - 1)] : 1.0;
        const double r = x + 1 < g.width ? phi[static_cast<std::size_t>(i + 1)] : 1.0;
        const double d = y > 0 ? phi[static_cast<std::size_t>(i - g.width)] : 1.0;
        const double u = y + 1 < g.height ? phi[static_cast<std::size_t>(i + g.width)] : 1.0;
        double& v = phi[static_cast<std::size_t>(i)];
        const double next = v + params.omega * (0.25 * (l + r + d + u) - v);
        change = std::max(change, std::abs(next - v));
        v = next;
      }
    if (change < params.tolerance) break;
  }
  return phi;
}

namespace {

// φ bilinear between cell centres, clamped to the raster.
double Sample(const omt::RasterGeometry& g, std::span<const double> phi, const Eigen::Vector2d& p) {
  const Eigen::Vector2d q = (p - g.origin_m) / g.resolution_m - Eigen::Vector2d(0.5, 0.5);
  const double fx = std::clamp(q.x(), 0.0, double(g.width - 1));
  const double fy = std::clamp(q.y(), 0.0, double(g.height - 1));
  const int x0 = std::min(int(fx), g.width - 2 < 0 ? 0 : g.width - 2);
  const int y0 = std::min(int(fy), g.height - 2 < 0 ? 0 : g.height - 2);
  const int x1 = std::min(x0 + 1, g.width - 1), y1 = std::min(y0 + 1, g.height - 1);
  const double ax = fx - x0, ay = fy - y0;
  const auto at = [&](int x, int y) { return phi[static_cast<std::size_t>(g.Index(x, y))]; };
  return (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x1, y0)) +
         ay * ((1 - ax) * at(x0, y1) + ax * at(x1, y1));
}

}  // namespace

std::vector<Eigen::Vector2d> DescendPotential(const omt::RasterGeometry& g,
                                              std::span<const double> phi,
                                              std::span<const std::uint8_t> codes,
                                              const Eigen::Vector2d& start, double length_m,
                                              const std::function<bool(const Eigen::Vector2d&)>& ok,
                                              const HarmonicParams& params) {
  std::vector<Eigen::Vector2d> out = {start};
  if (g.NumCells() <= 0 || phi.size() != static_cast<std::size_t>(g.NumCells()) ||
      codes.size() != phi.size())
    return out;
  const double h = g.resolution_m;
  Eigen::Vector2d p = start;
  for (double travelled = 0.0; travelled + 1e-9 < length_m;) {
    const int c = g.IndexOf(p);
    if (c < 0 || codes[static_cast<std::size_t>(c)] == kFloorFrontier) break;
    const Eigen::Vector2d grad(
        (Sample(g, phi, p + Eigen::Vector2d(h, 0)) - Sample(g, phi, p - Eigen::Vector2d(h, 0))) /
            (2 * h),
        (Sample(g, phi, p + Eigen::Vector2d(0, h)) - Sample(g, phi, p - Eigen::Vector2d(0, h))) /
            (2 * h));
    if (!(grad.norm() > params.min_gradient)) break;
    const double step = std::min(params.step_m, length_m - travelled);
    const Eigen::Vector2d next = p - step * grad.normalized();
    if (ok && !ok(next)) break;
    out.push_back(next);
    travelled += step;
    p = next;
  }
  return out;
}

}  // namespace voxplan::tensorfield
