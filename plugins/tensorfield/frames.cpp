// The window crop, the filled key-frame field and the carry-over of the previous key frame.
#include "plugins/tensorfield/frames.h"

#include <algorithm>
#include <cmath>

namespace voxplan::tensorfield {

FloorWindow CropFloor(const FloorInput& floor, const Eigen::Vector2d& centre_m, double radius_m) {
  FloorWindow w;
  const omt::RasterGeometry& fg = floor.geometry;
  const double res = fg.resolution_m;
  const int half = std::max(1, static_cast<int>(std::ceil(radius_m / res)));
  const Eigen::Vector2d q = (centre_m - fg.origin_m) / res;
  const int cx = static_cast<int>(std::floor(q.x())), cy = static_cast<int>(std::floor(q.y()));
  w.x0 = cx - half;
  w.y0 = cy - half;
  w.geometry.width = w.geometry.height = 2 * half + 1;
  w.geometry.resolution_m = res;
  w.geometry.origin_m = fg.origin_m + res * Eigen::Vector2d(w.x0, w.y0);
  const std::size_t n = static_cast<std::size_t>(w.geometry.NumCells());
  w.codes.assign(n, kFloorUnknown);
  w.raster.geometry = w.geometry;
  w.raster.cells.assign(n, omt::Cell::kUnknown);
  w.clearance.geometry = w.geometry;
  w.clearance.clearance_m.assign(n, 0.f);
  const bool surface = !floor.surface.empty();
  if (surface) {
    w.surface.uncertainty.assign(n, 0.f);
    w.surface.normal.assign(n, Eigen::Vector2f::Zero());
  }
  for (int y = 0; y < w.geometry.height; ++y) {
    const int fy = w.y0 + y;
    if (fy < 0 || fy >= fg.height) continue;
    for (int x = 0; x < w.geometry.width; ++x) {
      const int fx = w.x0 + x;
      if (fx < 0 || fx >= fg.width) continue;
      const std::size_t src = static_cast<std::size_t>(fg.Index(fx, fy));
      const std::size_t dst = static_cast<std::size_t>(w.geometry.Index(x, y));
      const std::uint8_t code = floor.cells[src];
      w.codes[dst] = code;
      w.raster.cells[dst] = code == kFloorObstacle                         ? omt::Cell::kOccupied
                            : code == kFloorFree || code == kFloorFrontier ? omt::Cell::kFree
                                                                           : omt::Cell::kUnknown;
      w.clearance.clearance_m[dst] = floor.clearance_m[src];
      if (surface) {
        w.surface.uncertainty[dst] = floor.surface.uncertainty[src];
        w.surface.normal[dst] = floor.surface.normal[src];
      }
    }
  }
  return w;
}

namespace {

TensorRaster Blend(FieldKind kind, const omt::RasterGeometry& geometry,
                   std::span<const BoundarySample> samples, std::span<const std::uint8_t> domain,
                   const KeyFrameParams& params) {
  if (kind == FieldKind::kTensor) return BlendTensorField(geometry, samples, domain, params);
  VectorRaster v = BlendVectorField(
      geometry, samples, domain,
      kind == FieldKind::kVectorNormal ? VectorConstraint::kNormal : VectorConstraint::kTangent,
      params);
  TensorRaster field;
  field.geometry = v.geometry;
  field.tau11 = std::move(v.vx);
  field.tau12 = std::move(v.vy);
  field.domain = std::move(v.domain);
  return field;
}

}  // namespace

TensorRaster WindowKeyFrame(const FloorWindow& window, const KeyFrameParams& params,
                            const FillParams& fill, std::vector<BoundarySample>* samples_out,
                            FieldKind kind) {
  std::vector<BoundarySample> samples = SampleBoundary(window.raster, params);
  const std::vector<std::uint8_t> domain = FieldDomain(window.raster, params.include_unknown);
  TensorRaster field = Blend(kind, window.geometry, samples, domain, params);
  if (fill.enabled && !samples.empty()) {
    // The wide blend on a coarse grid over the same extent (its cells' centres need not match).
    const int f = std::max(1, fill.coarse_factor);
    omt::RasterGeometry coarse;
    coarse.resolution_m = window.geometry.resolution_m * f;
    coarse.width = (window.geometry.width + f - 1) / f + 1;
    coarse.height = (window.geometry.height + f - 1) / f + 1;
    coarse.origin_m =
        window.geometry.origin_m - 0.5 * coarse.resolution_m * Eigen::Vector2d::Ones();
    KeyFrameParams wide = params;
    wide.sigma_per_spacing *= fill.sigma_factor;
    const TensorRaster broad = Blend(kind, coarse, samples, {}, wide);
    // Every cell the first blend may fill: the domain plus its value band.
    const std::vector<std::uint8_t> support =
        field.domain.empty() ? std::vector<std::uint8_t>{}
                             : DilateMask(window.geometry, field.domain, params.value_band_cells);
    for (int i = 0; i < window.geometry.NumCells(); ++i) {
      if (!support.empty() && support[static_cast<std::size_t>(i)] == 0) continue;
      const std::optional<Eigen::Vector2d> t = SampleTensor(broad, window.geometry.Center(i));
      if (!t) continue;
      field.tau11[static_cast<std::size_t>(i)] += fill.weight * t->x();
      field.tau12[static_cast<std::size_t>(i)] += fill.weight * t->y();
    }
  }
  if (samples_out != nullptr) *samples_out = std::move(samples);
  return field;
}

TensorRaster Reindex(const TensorRaster& field, const TensorRaster& fallback) {
  TensorRaster out = fallback;
  const omt::RasterGeometry& from = field.geometry;
  const omt::RasterGeometry& to = fallback.geometry;
  if (std::abs(from.resolution_m - to.resolution_m) > 1e-9 * to.resolution_m) return out;
  const Eigen::Vector2d d = (to.origin_m - from.origin_m) / to.resolution_m;
  const int dx = static_cast<int>(std::lround(d.x())), dy = static_cast<int>(std::lround(d.y()));
  if (out.domain.empty()) out.domain.assign(static_cast<std::size_t>(to.NumCells()), 1);
  for (int y = 0; y < to.height; ++y) {
    const int sy = y + dy;
    if (sy < 0 || sy >= from.height) continue;
    for (int x = 0; x < to.width; ++x) {
      const int sx = x + dx;
      if (sx < 0 || sx >= from.width) continue;
      const std::size_t s = static_cast<std::size_t>(from.Index(sx, sy));
      const std::size_t t = static_cast<std::size_t>(to.Index(x, y));
      out.tau11[t] = field.tau11[s];
      out.tau12[t] = field.tau12[s];
      out.domain[t] = field.InDomain(static_cast<int>(s)) ? 1 : 0;
    }
  }
  return out;
}

}  // namespace voxplan::tensorfield
