// Tensor rasters, boundary constraints and the Gaussian blend of X eq. 3 (tensor and vector).
#include "plugins/tensorfield/algorithms/tensor_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxplan::tensorfield {
namespace {

using omt::Cell;

Eigen::Vector2d Perp(const Eigen::Vector2d& v) { return {-v.y(), v.x()}; }

// Separable, truncated Gaussian splat of one constant value per sample onto the support cells:
// out[c] += exp(-|centre(c) - p|² / σ²) * value(sample), for |centre(c) - p| <= truncation σ.
template <typename ValueOf>
void SplatGaussian(const omt::RasterGeometry& geometry, std::span<const BoundarySample> samples,
                   std::span<const std::uint8_t> support, const KeyFrameParams& params,
                   ValueOf value_of, std::vector<double>* out_a, std::vector<double>* out_b) {
  const double sigma = params.sigma_per_spacing * params.sample_spacing_m;
  if (!(sigma > 0.0) || geometry.width <= 0 || geometry.height <= 0) return;
  const double inv_s2 = 1.0 / (sigma * sigma);
  const double reach = std::max(0.0, params.truncation_sigmas) * sigma;
  const double reach2 = reach * reach;
  const double res = geometry.resolution_m;
  const int r_cells = static_cast<int>(std::ceil(reach / res)) + 1;
  std::vector<double> wx, dx2;
  for (const BoundarySample& s : samples) {
    const Eigen::Vector2d value = value_of(s);
    const Eigen::Vector2d q = (s.position_m - geometry.origin_m) / res;
    const int cx = static_cast<int>(std::floor(q.x()));
    const int cy = static_cast<int>(std::floor(q.y()));
    const int x0 = std::max(0, cx - r_cells), x1 = std::min(geometry.width - 1, cx + r_cells);
    const int y0 = std::max(0, cy - r_cells), y1 = std::min(geometry.height - 1, cy + r_cells);
    if (x0 > x1 || y0 > y1) continue;
    wx.resize(static_cast<std::size_t>(x1 - x0 + 1));
    dx2.resize(wx.size());
    for (int x = x0; x <= x1; ++x) {
      const double d = geometry.origin_m.x() + (x + 0.5) * res - s.position_m.x();
      dx2[static_cast<std::size_t>(x - x0)] = d * d;
      wx[static_cast<std::size_t>(x - x0)] = std::exp(-d * d * inv_s2);
    }
    for (int y = y0; y <= y1; ++y) {
      const double d = geometry.origin_m.y() + (y + 0.5) * res - s.position_m.y();
      const double dy2 = d * d;
      if (dy2 > reach2) continue;
      const double wy = std::exp(-dy2 * inv_s2);
      const int row = y * geometry.width;
      for (int x = x0; x <= x1; ++x) {
        const std::size_t k = static_cast<std::size_t>(x - x0);
        if (dx2[k] + dy2 > reach2) continue;
        const std::size_t c = static_cast<std::size_t>(row + x);
        if (!support.empty() && support[c] == 0) continue;
        const double w = wx[k] * wy;
        (*out_a)[c] += w * value.x();
        (*out_b)[c] += w * value.y();
      }
    }
  }
}

std::vector<std::uint8_t> SupportOf(const omt::RasterGeometry& geometry,
                                    std::span<const std::uint8_t> domain, int band_cells) {
  if (domain.empty()) return {};
  return DilateMask(geometry, domain, band_cells);
}

}  // namespace

TensorRaster MakeTensorRaster(const omt::RasterGeometry& geometry) {
  TensorRaster field;
  field.geometry = geometry;
  const std::size_t n = static_cast<std::size_t>(std::max(0, geometry.NumCells()));
  field.tau11.assign(n, 0.0);
  field.tau12.assign(n, 0.0);
  return field;
}

std::optional<Eigen::Vector2d> SampleTensor(const TensorRaster& field, const Eigen::Vector2d& p_m) {
  const omt::RasterGeometry& g = field.geometry;
  if (g.width <= 0 || g.height <= 0) return std::nullopt;
  const Eigen::Vector2d q = (p_m - g.origin_m) / g.resolution_m;
  if (!(q.x() >= 0.0 && q.y() >= 0.0 && q.x() <= g.width && q.y() <= g.height)) return std::nullopt;
  // Continuous cell-centre coordinates, clamped to the outermost centres.
  const double u = std::clamp(q.x() - 0.5, 0.0, static_cast<double>(g.width - 1));
  const double v = std::clamp(q.y() - 0.5, 0.0, static_cast<double>(g.height - 1));
  const int x0 = std::min(static_cast<int>(u), std::max(0, g.width - 2));
  const int y0 = std::min(static_cast<int>(v), std::max(0, g.height - 2));
  const int x1 = std::min(x0 + 1, g.width - 1), y1 = std::min(y0 + 1, g.height - 1);
  const double fu = u - x0, fv = v - y0;
  const Eigen::Vector2d a = field.At(g.Index(x0, y0)), b = field.At(g.Index(x1, y0));
  const Eigen::Vector2d c = field.At(g.Index(x0, y1)), d = field.At(g.Index(x1, y1));
  return (1.0 - fv) * ((1.0 - fu) * a + fu * b) + fv * ((1.0 - fu) * c + fu * d);
}

std::vector<std::uint8_t> DilateMask(const omt::RasterGeometry& geometry,
                                     std::span<const std::uint8_t> mask, int radius_cells) {
  const int w = geometry.width, h = geometry.height;
  std::vector<std::uint8_t> out(mask.begin(), mask.end());
  for (auto& m : out) m = m != 0 ? 1 : 0;
  if (radius_cells <= 0 || w <= 0 || h <= 0) return out;
  // Separable max filter: rows, then columns, each with a running count over the window.
  std::vector<std::uint8_t> tmp(out.size(), 0);
  for (int y = 0; y < h; ++y) {
    int count = 0;
    for (int x = 0; x <= std::min(w - 1, radius_cells - 1); ++x) count += out[y * w + x];
    for (int x = 0; x < w; ++x) {
      if (x + radius_cells < w) count += out[y * w + x + radius_cells];
      if (x - radius_cells - 1 >= 0) count -= out[y * w + x - radius_cells - 1];
      tmp[y * w + x] = count > 0 ? 1 : 0;
    }
  }
  for (int x = 0; x < w; ++x) {
    int count = 0;
    for (int y = 0; y <= std::min(h - 1, radius_cells - 1); ++y) count += tmp[y * w + x];
    for (int y = 0; y < h; ++y) {
      if (y + radius_cells < h) count += tmp[(y + radius_cells) * w + x];
      if (y - radius_cells - 1 >= 0) count -= tmp[(y - radius_cells - 1) * w + x];
      out[y * w + x] = count > 0 ? 1 : 0;
    }
  }
  return out;
}

std::vector<int> BoundaryCells(const omt::OccupancyRaster& raster, bool eight_connected) {
  const omt::RasterGeometry& g = raster.geometry;
  std::vector<int> cells;
  if (raster.cells.size() != static_cast<std::size_t>(std::max(0, g.NumCells()))) return cells;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      if (raster.At(g.Index(x, y)) != Cell::kOccupied) continue;
      bool boundary = false;
      for (int dy = -1; dy <= 1 && !boundary; ++dy) {
        for (int dx = -1; dx <= 1 && !boundary; ++dx) {
          if ((dx == 0 && dy == 0) || (!eight_connected && dx != 0 && dy != 0)) continue;
          if (g.InBounds(x + dx, y + dy) && raster.At(g.Index(x + dx, y + dy)) == Cell::kFree) {
            boundary = true;
          }
        }
      }
      if (boundary) cells.push_back(g.Index(x, y));
    }
  }
  return cells;
}

std::vector<std::uint8_t> FieldDomain(const omt::OccupancyRaster& raster, bool include_unknown) {
  std::vector<std::uint8_t> domain(raster.cells.size(), 0);
  for (std::size_t i = 0; i < raster.cells.size(); ++i) {
    const Cell c = raster.cells[i];
    domain[i] = (c == Cell::kFree || (include_unknown && c == Cell::kUnknown)) ? 1 : 0;
  }
  return domain;
}

std::vector<BoundarySample> SampleBoundary(const omt::OccupancyRaster& raster,
                                           const KeyFrameParams& params) {
  const omt::RasterGeometry& g = raster.geometry;
  const std::vector<int> boundary = BoundaryCells(raster, params.eight_connected_boundary);
  std::vector<BoundarySample> samples;
  if (boundary.empty()) return samples;
  const std::size_t n = boundary.size();
  std::vector<std::uint8_t> is_boundary(static_cast<std::size_t>(g.NumCells()), 0);
  for (int c : boundary) is_boundary[static_cast<std::size_t>(c)] = 1;

  // Line fit of every boundary cell: PCA of the boundary cells in its (2r+1)² window (the
  // official code's 5-point fit along a straight wall), the normal towards the free cells there,
  // and the corner score λ_min / λ_max of the fit (0 on a straight wall, about 0.3 at a
  // right-angled corner).
  const int r = std::max(1, params.tangent_fit_radius_cells);
  std::vector<BoundarySample> fits(n);
  std::vector<double> corner(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const int cell = boundary[i];
    const int sx = g.X(cell), sy = g.Y(cell);
    double sum_x = 0.0, sum_y = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
    int count = 0;
    Eigen::Vector2d free_dir = Eigen::Vector2d::Zero();
    for (int y = sy - r; y <= sy + r; ++y) {
      for (int x = sx - r; x <= sx + r; ++x) {
        if (!g.InBounds(x, y)) continue;
        const int c = g.Index(x, y);
        const double ox = x - sx, oy = y - sy;
        if (is_boundary[static_cast<std::size_t>(c)] != 0) {
          sum_x += ox;
          sum_y += oy;
          sxx += ox * ox;
          syy += oy * oy;
          sxy += ox * oy;
          ++count;
        } else if (raster.At(c) == Cell::kFree) {
          free_dir += Eigen::Vector2d(ox, oy);
        }
      }
    }
    Eigen::Vector2d tangent = Eigen::Vector2d::UnitX();
    bool fitted = false;
    if (count >= 2) {
      const double mx = sum_x / count, my = sum_y / count;
      const double cxx = sxx / count - mx * mx, cyy = syy / count - my * my;
      const double cxy = sxy / count - mx * my;
      const double half_gap = std::hypot(0.5 * (cxx - cyy), cxy);
      if (half_gap > 1e-9) {
        const double angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
        tangent = {std::cos(angle), std::sin(angle)};
        fitted = true;
        const double mean = 0.5 * (cxx + cyy);
        corner[i] = (mean - half_gap) / (mean + half_gap);
      }
    }
    if (!fitted && free_dir.norm() > 1e-9) tangent = -Perp(free_dir.normalized());
    Eigen::Vector2d normal = Perp(tangent);
    if (normal.dot(free_dir) < 0.0) normal = -normal;
    BoundarySample& s = fits[i];
    s.cell = cell;
    s.position_m = g.Center(cell);
    s.normal = normal;
    s.tangent = {normal.y(), -normal.x()};  // normal turned by -90°: free space on the left
  }

  // Farthest-point sampling, O(boundary × samples): a few million updates on a large floor.
  std::vector<double> px(n), py(n), dist2(n, std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < n; ++i) {
    px[i] = fits[i].position_m.x();
    py[i] = fits[i].position_m.y();
  }
  const double spacing2 = params.sample_spacing_m * params.sample_spacing_m;
  std::vector<std::size_t> chosen;
  auto choose = [&](std::size_t k) {
    chosen.push_back(k);
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = px[i] - px[k], dy = py[i] - py[k];
      dist2[i] = std::min(dist2[i], dx * dx + dy * dy);
    }
  };
  // Corner seeds first (strongest first, ties to the lower index, kept d_s apart). Along
  // axis-aligned walls the blended τ12 is exactly zero unless a sample sits on the corner, and
  // whether the field turns one way or the other there (a trisector at a T junction, or none)
  // would depend on where plain farthest-point sampling happened to land.
  if (params.corner_min_ratio > 0.0) {
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < n; ++i) {
      if (corner[i] >= params.corner_min_ratio) order.push_back(i);
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return corner[a] > corner[b]; });
    for (std::size_t k : order) {
      if (dist2[k] >= spacing2) choose(k);
    }
  }
  if (chosen.empty()) choose(0);
  while (chosen.size() < n) {
    std::size_t best_i = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (dist2[i] > dist2[best_i]) best_i = i;
    }
    if (!(dist2[best_i] >= spacing2)) break;
    choose(best_i);
  }
  samples.reserve(chosen.size());
  for (std::size_t k : chosen) samples.push_back(fits[k]);
  return samples;
}

TensorRaster BlendTensorField(const omt::RasterGeometry& geometry,
                              std::span<const BoundarySample> samples,
                              std::span<const std::uint8_t> domain, const KeyFrameParams& params) {
  TensorRaster field = MakeTensorRaster(geometry);
  if (domain.size() == field.tau11.size()) field.domain.assign(domain.begin(), domain.end());
  const std::vector<std::uint8_t> support =
      SupportOf(geometry, field.domain, params.value_band_cells);
  SplatGaussian(
      geometry, samples, support, params,
      [&](const BoundarySample& s) {
        return BasisTensor(std::atan2(s.tangent.y(), s.tangent.x()), params.basis_magnitude);
      },
      &field.tau11, &field.tau12);
  return field;
}

TensorRaster KeyFrameField(const omt::OccupancyRaster& raster, const KeyFrameParams& params,
                           std::vector<BoundarySample>* samples_out) {
  std::vector<BoundarySample> samples = SampleBoundary(raster, params);
  const std::vector<std::uint8_t> domain = FieldDomain(raster, params.include_unknown);
  TensorRaster field = BlendTensorField(raster.geometry, samples, domain, params);
  if (samples_out != nullptr) *samples_out = std::move(samples);
  return field;
}

VectorRaster BlendVectorField(const omt::RasterGeometry& geometry,
                              std::span<const BoundarySample> samples,
                              std::span<const std::uint8_t> domain, VectorConstraint constraint,
                              const KeyFrameParams& params) {
  VectorRaster field;
  field.geometry = geometry;
  const std::size_t n = static_cast<std::size_t>(std::max(0, geometry.NumCells()));
  field.vx.assign(n, 0.0);
  field.vy.assign(n, 0.0);
  if (domain.size() == n) field.domain.assign(domain.begin(), domain.end());
  const std::vector<std::uint8_t> support =
      SupportOf(geometry, field.domain, params.value_band_cells);
  SplatGaussian(
      geometry, samples, support, params,
      [&](const BoundarySample& s) -> Eigen::Vector2d {
        return params.basis_magnitude *
               (constraint == VectorConstraint::kNormal ? s.normal : s.tangent);
      },
      &field.vx, &field.vy);
  return field;
}

}  // namespace voxplan::tensorfield
