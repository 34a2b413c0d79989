// Degenerate points of tensor rasters and singularities of vector rasters by index on 2x2 corner
// loops, with Delmarcelle & Hesselink separatrix directions (X L312).
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kPi = omt::kPi;

// Sum of wrapped angle changes around a closed loop of angles, in radians.
template <std::size_t N>
double Winding(const std::array<double, N>& angles) {
  double sum = 0.0;
  for (std::size_t i = 0; i < N; ++i) sum += omt::WrapAngle(angles[(i + 1) % N] - angles[i]);
  return sum;
}

// The four cells of the loop at (x, y), counter-clockwise (y grows upwards in the world).
std::array<int, 4> LoopCells(const omt::RasterGeometry& g, int x, int y) {
  return {g.Index(x, y), g.Index(x + 1, y), g.Index(x + 1, y + 1), g.Index(x, y + 1)};
}

// Bilinear (τ11, τ12) over the unit square between four cell centres.
struct Bilinear {
  Eigen::Vector2d f00, f10, f01, f11;
  Eigen::Vector2d Value(double u, double v) const {
    return f00 + (f10 - f00) * u + (f01 - f00) * v + (f11 - f10 - f01 + f00) * (u * v);
  }
  Eigen::Matrix2d Jacobian(double u, double v) const {  // columns d/du, d/dv
    const Eigen::Vector2d e = f11 - f10 - f01 + f00;
    Eigen::Matrix2d j;
    j.col(0) = (f10 - f00) + e * v;
    j.col(1) = (f01 - f00) + e * u;
    return j;
  }
};

// Newton's method for Value(u, v) = 0 inside the square, from a few starts; false when none
// converges inside.
bool SolveZero(const Bilinear& b, Eigen::Vector2d* uv) {
  const double scale = std::max({b.f00.norm(), b.f10.norm(), b.f01.norm(), b.f11.norm(), 1e-300});
  constexpr std::array<std::array<double, 2>, 5> kStarts = {
      {{0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}}};
  constexpr double kSlack = 1e-9;
  for (const auto& start : kStarts) {
    Eigen::Vector2d p(start[0], start[1]);
    for (int it = 0; it < 30; ++it) {
      const Eigen::Vector2d f = b.Value(p.x(), p.y());
      if (f.norm() <= 1e-12 * scale) break;
      const Eigen::Matrix2d j = b.Jacobian(p.x(), p.y());
      const double det = j.determinant();
      if (std::abs(det) <= 1e-300) break;
      p -= j.inverse() * f;
      if (!std::isfinite(p.x()) || !std::isfinite(p.y())) break;
    }
    if (std::isfinite(p.x()) && std::isfinite(p.y()) && p.x() >= -kSlack && p.y() >= -kSlack &&
        p.x() <= 1.0 + kSlack && p.y() <= 1.0 + kSlack &&
        b.Value(p.x(), p.y()).norm() <= 1e-9 * scale) {
      *uv = p.cwiseMax(0.0).cwiseMin(1.0);
      return true;
    }
  }
  return false;
}

// atan2 of (a, b) + ε (0.6, 0.8), ε = 1e-9 × the largest magnitude: a symbolic perturbation in
// a generic direction. Fields blended from axis-aligned walls have components that are exactly
// zero (τ12 ≡ 0, or v_x ≡ 0 between opposite walls); exact ties would otherwise turn into
// wrapped changes of exactly π, and every loop straddling a sign change of the other component
// would count as a spurious singularity. Real values are far larger than ε (the Gaussian tails are
// truncated at 3σ, e^-9 ≈ 1e-4 of a basis tensor), so only exact ties are affected.
// Also returns each cell's magnitude and the largest one (over the domain).
struct LoopData {
  std::vector<double> angle;
  std::vector<double> magnitude;
  double max_magnitude = 0.0;
};
LoopData PerturbedAngles(const std::vector<double>& a, const std::vector<double>& b,
                         const std::vector<std::uint8_t>& domain) {
  LoopData d;
  d.magnitude.resize(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    d.magnitude[i] = std::hypot(a[i], b[i]);
    if (domain.empty() || domain[i] != 0)
      d.max_magnitude = std::max(d.max_magnitude, d.magnitude[i]);
  }
  const double eps = 1e-9 * (d.max_magnitude > 0.0 ? d.max_magnitude : 1.0);
  d.angle.resize(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    d.angle[i] = std::atan2(b[i] + 0.8 * eps, a[i] + 0.6 * eps);
  }
  return d;
}

// Winding of the loop at cells (counter-clockwise) in radians; 0 for flat loops.
double LoopWinding(const LoopData& d, const std::array<int, 4>& cells, double min_relative) {
  double largest = 0.0;
  for (int c : cells) largest = std::max(largest, d.magnitude[static_cast<std::size_t>(c)]);
  if (!(largest > 0.0) || largest < min_relative * d.max_magnitude) return 0.0;
  return Winding<4>(
      {d.angle[static_cast<std::size_t>(cells[0])], d.angle[static_cast<std::size_t>(cells[1])],
       d.angle[static_cast<std::size_t>(cells[2])], d.angle[static_cast<std::size_t>(cells[3])]});
}

}  // namespace

double TensorIndex(std::span<const Eigen::Vector2d> loop) {
  double sum = 0.0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Eigen::Vector2d& a = loop[i];
    const Eigen::Vector2d& b = loop[(i + 1) % loop.size()];
    sum += omt::WrapAngle(std::atan2(b.y(), b.x()) - std::atan2(a.y(), a.x()));
  }
  return sum / (4.0 * kPi);
}

// Delmarcelle & Hesselink 1994: near a degenerate point the field is linear, τ(r) = J r. Along
// the ray of angle φ the tensor is J (cos φ, sin φ), whose major eigenvector has angle
// atan2(τ12, τ11) / 2; the ray is a separatrix candidate where that angle equals φ (mod π), i.e.
// where J (cos φ, sin φ) points along (cos 2φ, sin 2φ). Instead of the equivalent cubic in
// tan φ we scan g(φ) = τ12 cos 2φ - τ11 sin 2φ (the cross product) over [0, 2π), bisect every
// sign change, and keep roots where the dot product is positive (the major, not the minor,
// eigenvector is radial there). A wedge has one or three such rays, a trisector three.
std::vector<double> SeparatrixAngles(const Eigen::Matrix2d& jacobian, int scan_steps) {
  std::vector<double> angles;
  if (!(jacobian.norm() > 1e-300)) return angles;
  const Eigen::Matrix2d j = jacobian / jacobian.norm();
  auto tau = [&](double phi) -> Eigen::Vector2d {
    return j * Eigen::Vector2d(std::cos(phi), std::sin(phi));
  };
  auto cross = [&](double phi) {
    const Eigen::Vector2d t = tau(phi);
    return t.y() * std::cos(2.0 * phi) - t.x() * std::sin(2.0 * phi);
  };
  auto dot = [&](double phi) {
    const Eigen::Vector2d t = tau(phi);
    return t.x() * std::cos(2.0 * phi) + t.y() * std::sin(2.0 * phi);
  };
  const int steps = std::max(16, scan_steps);
  const double step = 2.0 * kPi / steps;
  double g0 = cross(0.0);
  for (int k = 0; k < steps; ++k) {
    const double a = k * step, b = (k + 1) * step;
    // The last interval ends where the first starts: a root at φ = 0 is found once, whichever
    // side of it rounding puts cross(0) and cross(2π).
    const double g1 = k + 1 < steps ? cross(b) : cross(0.0);
    double root = -1.0;
    if (g0 == 0.0) {
      root = a;
    } else if ((g0 < 0.0) != (g1 < 0.0) && g1 != 0.0) {
      double lo = a, hi = b, glo = g0;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double gm = cross(mid);
        if ((gm < 0.0) == (glo < 0.0)) {
          lo = mid;
          glo = gm;
        } else {
          hi = mid;
        }
      }
      root = 0.5 * (lo + hi);
    }
    if (root >= 0.0 && dot(root) > 0.0) angles.push_back(root);
    g0 = g1;
  }
  return angles;
}

namespace {

// Calls found(x, y, cells, turns) for every 2x2 corner loop inside the domain around which the
// angle of (a, b) winds by a non-zero number of turns (row by row: the output's order).
template <typename Field, typename Found>
void ForEachWindingLoop(const Field& field, const std::vector<double>& a,
                        const std::vector<double>& b, const TopologyParams& params, Found found) {
  const omt::RasterGeometry& g = field.geometry;
  const std::size_t n = static_cast<std::size_t>(std::max(0, g.NumCells()));
  if (a.size() != n || b.size() != n) return;
  if (!field.domain.empty() && field.domain.size() != n) return;
  const LoopData data = PerturbedAngles(a, b, field.domain);
  for (int y = 0; y + 1 < g.height; ++y) {
    for (int x = 0; x + 1 < g.width; ++x) {
      const std::array<int, 4> cells = LoopCells(g, x, y);
      if (!std::all_of(cells.begin(), cells.end(), [&](int c) { return field.InDomain(c); })) {
        continue;
      }
      const double winding = LoopWinding(data, cells, params.min_relative_magnitude);
      const long turns = std::lround(winding / (2.0 * kPi));
      if (turns != 0) found(x, y, cells, turns);
    }
  }
}

}  // namespace

std::vector<DegeneratePoint> FindDegeneratePoints(const TensorRaster& field,
                                                  const TopologyParams& params) {
  std::vector<DegeneratePoint> points;
  const omt::RasterGeometry& g = field.geometry;
  const double res = g.resolution_m;
  // 2θ winds by a multiple of 2π; ±2π (index ±1/2) is the generic case.
  ForEachWindingLoop(field, field.tau11, field.tau12, params,
                     [&](int x, int y, const std::array<int, 4>& cells, long turns) {
                       DegeneratePoint p;
                       p.type = turns > 0 ? DegenerateType::kWedge : DegenerateType::kTrisector;
                       p.cell_x = x;
                       p.cell_y = y;
                       const Bilinear b{field.At(cells[0]), field.At(cells[1]), field.At(cells[3]),
                                        field.At(cells[2])};
                       Eigen::Vector2d uv(0.5, 0.5);
                       if (params.refine_position && !SolveZero(b, &uv)) uv = {0.5, 0.5};
                       p.position_m = g.Center(x, y) + res * uv;
                       p.jacobian = b.Jacobian(uv.x(), uv.y()) / res;
                       p.separatrix_angles_rad =
                           SeparatrixAngles(p.jacobian, params.separatrix_scan_steps);
                       points.push_back(std::move(p));
                     });
  return points;
}

std::vector<VectorSingularity> FindVectorSingularities(const VectorRaster& field,
                                                       const TopologyParams& params) {
  std::vector<VectorSingularity> out;
  const omt::RasterGeometry& g = field.geometry;
  ForEachWindingLoop(
      field, field.vx, field.vy, params, [&](int x, int y, const std::array<int, 4>&, long turns) {
        VectorSingularity s;
        s.index = static_cast<int>(turns);
        s.cell_x = x;
        s.cell_y = y;
        s.position_m = g.Center(x, y) + 0.5 * g.resolution_m * Eigen::Vector2d::Ones();
        out.push_back(s);
      });
  return out;
}

FieldCensus CountFieldCensus(const omt::RasterGeometry& geometry,
                             std::span<const BoundarySample> samples,
                             std::span<const std::uint8_t> domain, const KeyFrameParams& params) {
  // e^-36 ≈ 2e-16 of a basis field at 6σ: below PerturbedAngles' ε (1e-9 of the largest
  // magnitude), so the tails beyond would not turn an angle.
  constexpr double kCensusSigmas = 6.0;
  KeyFrameParams p = params;
  p.truncation_sigmas = std::max(p.truncation_sigmas, kCensusSigmas);
  TopologyParams tp;
  tp.min_relative_magnitude = 0.0;  // no solver noise in a blend; ε alone decides flat loops
  tp.refine_position = false;       // counts only
  FieldCensus census;
  census.degenerate_points = static_cast<int>(
      FindDegeneratePoints(BlendTensorField(geometry, samples, domain, p), tp).size());
  census.vector_singularities = static_cast<int>(
      FindVectorSingularities(
          BlendVectorField(geometry, samples, domain, VectorConstraint::kNormal, p), tp)
          .size());
  return census;
}

}  // namespace voxplan::tensorfield
