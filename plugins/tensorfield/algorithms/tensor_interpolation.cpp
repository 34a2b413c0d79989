// Space-time interpolation between key frames (X eq. 4-5), solved matrix-free by Jacobi-
// preconditioned conjugate gradients on the mask cells, warm-started from the linear blend.
//
// Eq. 5's Laplacian at vertex (i; j), normalised by ω = Σ_N(i) ω_S + (temporal neighbours) ω_T:
//   (Δτ)(i; j) = τ(i; j) - (ω_S Σ_{k ∈ N(i)} τ(k; j) + ω_T τ(i; j-1) + ω_T τ(i; j+1)) / ω,
// N(i) the 4-neighbours of i inside the mask (so the mask's edge is a natural, zero-flux boundary)
// and, at frames 0 and K, only the one temporal neighbour there is. Unknowns are stored frame by
// frame: x[j * n + m] for mask cell m.
#include <algorithm>
#include <cmath>
#include <functional>

#include "plugins/tensorfield/algorithms/tensor_field.h"

namespace voxplan::tensorfield {
namespace {

using Vec = std::vector<double>;

struct SpaceTimeGrid {
  int n = 0;  // mask cells
  int frames = 0;
  std::vector<int> cell;      // compact -> raster index
  std::vector<int> neighbor;  // 4 per compact cell, -1 when absent
  std::vector<int> degree;
  double ws = 1.0, wt = 2.0;
  bool all_frames = true;

  bool HasRow(int j) const { return all_frames || (j > 0 && j < frames - 1); }
  double inv_omega[5][3] = {};  // 1 / ω by (spatial degree, temporal neighbours)
  void Prepare() {
    for (int d = 0; d <= 4; ++d) {
      for (int t = 0; t <= 2; ++t) {
        const double w = d * ws + t * wt;
        inv_omega[d][t] = w > 0.0 ? 1.0 / w : 0.0;
      }
    }
  }
  int Temporal(int j) const { return (j > 0 ? 1 : 0) + (j < frames - 1 ? 1 : 0); }
  double Omega(int m, int j) const {
    return degree[static_cast<std::size_t>(m)] * ws + Temporal(j) * wt;
  }
  double InvOmega(int m, int j) const {
    return inv_omega[degree[static_cast<std::size_t>(m)]][Temporal(j)];
  }
  std::size_t At(int m, int j) const { return static_cast<std::size_t>(j) * n + m; }
};

// y[row(m, j)] = (Δx)(m, j) for every row; rows without a Laplacian hold 0.
void ApplyLaplacian(const SpaceTimeGrid& g, const Vec& x, Vec* y) {
  y->assign(x.size(), 0.0);
  for (int j = 0; j < g.frames; ++j) {
    if (!g.HasRow(j)) continue;
    for (int m = 0; m < g.n; ++m) {
      double s = 0.0;
      for (int k = 0; k < 4; ++k) {
        const int nb = g.neighbor[static_cast<std::size_t>(4 * m + k)];
        if (nb >= 0) s += g.ws * x[g.At(nb, j)];
      }
      if (j > 0) s += g.wt * x[g.At(m, j - 1)];
      if (j < g.frames - 1) s += g.wt * x[g.At(m, j + 1)];
      (*y)[g.At(m, j)] = x[g.At(m, j)] - s * g.InvOmega(m, j);
    }
  }
}

// z += Δᵀ y (the scatter of ApplyLaplacian's rows).
void ApplyLaplacianTranspose(const SpaceTimeGrid& g, const Vec& y, Vec* z) {
  for (int j = 0; j < g.frames; ++j) {
    if (!g.HasRow(j)) continue;
    for (int m = 0; m < g.n; ++m) {
      const double v = y[g.At(m, j)];
      if (v == 0.0) continue;
      const double c = v * g.InvOmega(m, j);
      (*z)[g.At(m, j)] += v;
      for (int k = 0; k < 4; ++k) {
        const int nb = g.neighbor[static_cast<std::size_t>(4 * m + k)];
        if (nb >= 0) (*z)[g.At(nb, j)] -= g.ws * c;
      }
      if (j > 0) (*z)[g.At(m, j - 1)] -= g.wt * c;
      if (j < g.frames - 1) (*z)[g.At(m, j + 1)] -= g.wt * c;
    }
  }
}

double Energy(const SpaceTimeGrid& g, const Vec& x, const Vec& a, const Vec& b, double alpha,
              Vec* scratch) {
  ApplyLaplacian(g, x, scratch);
  double e = 0.0;
  for (double v : *scratch) e += v * v;
  const int last = g.frames - 1;
  for (int m = 0; m < g.n; ++m) {
    const double d0 = x[g.At(m, 0)] - a[static_cast<std::size_t>(m)];
    const double d1 = x[g.At(m, last)] - b[static_cast<std::size_t>(m)];
    e += alpha * (d0 * d0 + d1 * d1);
  }
  return e;
}

double Dot(const Vec& a, const Vec& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

// Jacobi-preconditioned CG for A x = rhs from the given x. Returns the iterations; *converged
// when |r| <= tolerance |r0|.
int ConjugateGradient(const std::function<void(const Vec&, Vec*)>& apply, const Vec& diagonal,
                      const Vec& rhs, int max_iterations, double tolerance, Vec* x,
                      bool* converged) {
  const std::size_t n = rhs.size();
  Vec r(n), z(n), p(n), ap(n);
  apply(*x, &ap);
  for (std::size_t i = 0; i < n; ++i) r[i] = rhs[i] - ap[i];
  const double r0 = std::sqrt(Dot(r, r));
  *converged = true;
  if (r0 == 0.0) return 0;
  for (std::size_t i = 0; i < n; ++i) z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : r[i];
  p = z;
  double rz = Dot(r, z);
  int it = 0;
  while (it < max_iterations) {
    apply(p, &ap);
    const double pap = Dot(p, ap);
    if (!(pap > 0.0)) break;
    const double step = rz / pap;
    for (std::size_t i = 0; i < n; ++i) {
      (*x)[i] += step * p[i];
      r[i] -= step * ap[i];
    }
    ++it;
    if (std::sqrt(Dot(r, r)) <= tolerance * r0) return it;
    for (std::size_t i = 0; i < n; ++i) z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : r[i];
    const double rz_next = Dot(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
  *converged = std::sqrt(Dot(r, r)) <= tolerance * r0;
  return it;
}

bool SameGeometry(const omt::RasterGeometry& a, const omt::RasterGeometry& b) {
  return a.width == b.width && a.height == b.height && a.resolution_m == b.resolution_m &&
         a.origin_m == b.origin_m;
}

// One component (τ11 or τ12) on the mask: x holds the linear blend on entry, the solution on
// exit. Returns CG iterations.
int SolveComponent(const SpaceTimeGrid& g, const Vec& a, const Vec& b,
                   const SpaceTimeParams& params, Vec* x, bool* converged) {
  const std::size_t size = x->size();
  const int last = g.frames - 1;
  Vec diagonal(size, 0.0), rhs(size, 0.0);
  std::function<void(const Vec&, Vec*)> apply;
  Vec scratch;
  if (g.all_frames) {
    // Normal equations (ΔᵀΔ + α P) x = α (P0ᵀ a + PKᵀ b).
    for (int j = 0; j < g.frames; ++j) {
      for (int m = 0; m < g.n; ++m) {
        const double w = g.InvOmega(m, j);
        diagonal[g.At(m, j)] += 1.0;
        for (int k = 0; k < 4; ++k) {
          const int nb = g.neighbor[static_cast<std::size_t>(4 * m + k)];
          if (nb >= 0) diagonal[g.At(nb, j)] += (g.ws * w) * (g.ws * w);
        }
        if (j > 0) diagonal[g.At(m, j - 1)] += (g.wt * w) * (g.wt * w);
        if (j < last) diagonal[g.At(m, j + 1)] += (g.wt * w) * (g.wt * w);
      }
    }
    for (int m = 0; m < g.n; ++m) {
      diagonal[g.At(m, 0)] += params.alpha;
      diagonal[g.At(m, last)] += params.alpha;
      rhs[g.At(m, 0)] = params.alpha * a[static_cast<std::size_t>(m)];
      rhs[g.At(m, last)] = params.alpha * b[static_cast<std::size_t>(m)];
    }
    apply = [&](const Vec& in, Vec* out) {
      ApplyLaplacian(g, in, &scratch);
      out->assign(in.size(), 0.0);
      ApplyLaplacianTranspose(g, scratch, out);
      for (int m = 0; m < g.n; ++m) {
        (*out)[g.At(m, 0)] += params.alpha * in[g.At(m, 0)];
        (*out)[g.At(m, last)] += params.alpha * in[g.At(m, last)];
      }
    };
  } else {
    // Key frames fixed; the interior rows' ω-scaled Laplacian is symmetric positive definite:
    // ω x(m,j) - ω_S Σ x(k,j) - ω_T (x(m,j-1) + x(m,j+1)) = 0, end-frame terms on the right.
    // End frames get identity rows, so the whole operator stays symmetric.
    for (int m = 0; m < g.n; ++m) {
      diagonal[g.At(m, 0)] = 1.0;
      diagonal[g.At(m, last)] = 1.0;
      rhs[g.At(m, 0)] = a[static_cast<std::size_t>(m)];
      rhs[g.At(m, last)] = b[static_cast<std::size_t>(m)];
      (*x)[g.At(m, 0)] = a[static_cast<std::size_t>(m)];
      (*x)[g.At(m, last)] = b[static_cast<std::size_t>(m)];
      for (int j = 1; j < last; ++j) diagonal[g.At(m, j)] = g.Omega(m, j);
      if (last > 1) {
        rhs[g.At(m, 1)] += g.wt * a[static_cast<std::size_t>(m)];
        rhs[g.At(m, last - 1)] += g.wt * b[static_cast<std::size_t>(m)];
      }
    }
    apply = [&](const Vec& in, Vec* out) {
      out->assign(in.size(), 0.0);
      for (int m = 0; m < g.n; ++m) {
        (*out)[g.At(m, 0)] = in[g.At(m, 0)];
        (*out)[g.At(m, last)] = in[g.At(m, last)];
      }
      for (int j = 1; j < last; ++j) {
        for (int m = 0; m < g.n; ++m) {
          double s = 0.0;
          for (int k = 0; k < 4; ++k) {
            const int nb = g.neighbor[static_cast<std::size_t>(4 * m + k)];
            if (nb >= 0) s += g.ws * in[g.At(nb, j)];
          }
          if (j > 1) s += g.wt * in[g.At(m, j - 1)];
          if (j < last - 1) s += g.wt * in[g.At(m, j + 1)];
          (*out)[g.At(m, j)] = g.Omega(m, j) * in[g.At(m, j)] - s;
        }
      }
    };
  }
  return ConjugateGradient(apply, diagonal, rhs, params.max_iterations, params.tolerance, x,
                           converged);
}

}  // namespace

std::vector<std::uint8_t> InterpolationMask(const TensorRaster& previous, const TensorRaster& next,
                                            const MaskParams& params) {
  const omt::RasterGeometry& g = next.geometry;
  const std::size_t n = static_cast<std::size_t>(std::max(0, g.NumCells()));
  std::vector<std::uint8_t> mask(n, 0);
  const bool prev_ok = previous.domain.empty() || previous.domain.size() == n;
  for (std::size_t i = 0; i < n; ++i) {
    const int c = static_cast<int>(i);
    mask[i] = (next.InDomain(c) || (prev_ok && previous.InDomain(c))) ? 1 : 0;
  }
  mask = DilateMask(g, mask, params.band_cells);
  if (params.use_window) {
    const double r2 = params.window_radius_m * params.window_radius_m;
    for (std::size_t i = 0; i < n; ++i) {
      if ((g.Center(static_cast<int>(i)) - params.window_centre_m).squaredNorm() > r2) mask[i] = 0;
    }
  }
  return mask;
}

SpaceTimeResult InterpolateFrames(const TensorRaster& previous, const TensorRaster& next,
                                  std::span<const std::uint8_t> mask,
                                  const SpaceTimeParams& params) {
  SpaceTimeResult result;
  const omt::RasterGeometry& geo = next.geometry;
  const std::size_t cells = static_cast<std::size_t>(std::max(0, geo.NumCells()));
  auto sized = [&](const TensorRaster& f) {
    return f.tau11.size() == cells && f.tau12.size() == cells &&
           (f.domain.empty() || f.domain.size() == cells);
  };
  if (!SameGeometry(previous.geometry, geo) || !sized(previous) || !sized(next)) {
    result.status = omt::Status::Error(omt::Status::Code::kInvalidInput,
                                       "key frames differ in geometry or size");
    return result;
  }
  if (params.substeps < 1 || (!mask.empty() && mask.size() != cells)) {
    result.status = omt::Status::Error(omt::Status::Code::kInvalidInput,
                                       "substeps must be >= 1 and the mask one byte per cell");
    return result;
  }
  const int k_frames = params.substeps + 1;

  // Linear blend everywhere; domain = union of the key frames' domains.
  std::vector<std::uint8_t> domain;
  if (!previous.domain.empty() && !next.domain.empty()) {
    domain.resize(cells);
    for (std::size_t i = 0; i < cells; ++i) {
      domain[i] = (previous.domain[i] != 0 || next.domain[i] != 0) ? 1 : 0;
    }
  }
  result.frames.reserve(static_cast<std::size_t>(k_frames));
  for (int j = 0; j < k_frames; ++j) {
    const double s = static_cast<double>(j) / params.substeps;
    TensorRaster f = MakeTensorRaster(geo);
    f.domain = domain;
    for (std::size_t i = 0; i < cells; ++i) {
      f.tau11[i] = (1.0 - s) * previous.tau11[i] + s * next.tau11[i];
      f.tau12[i] = (1.0 - s) * previous.tau12[i] + s * next.tau12[i];
    }
    result.frames.push_back(std::move(f));
  }

  SpaceTimeGrid g;
  g.frames = k_frames;
  g.ws = params.spatial_weight;
  g.wt = params.temporal_weight;
  g.all_frames = params.rows == SpaceTimeRows::kAllFrames;
  std::vector<int> compact(cells, -1);
  for (std::size_t i = 0; i < cells; ++i) {
    if (mask.empty() || mask[i] != 0) {
      compact[i] = g.n++;
      g.cell.push_back(static_cast<int>(i));
    }
  }
  g.neighbor.assign(static_cast<std::size_t>(4 * g.n), -1);
  g.degree.assign(static_cast<std::size_t>(g.n), 0);
  constexpr int kDx[4] = {1, -1, 0, 0};
  constexpr int kDy[4] = {0, 0, 1, -1};
  for (int m = 0; m < g.n; ++m) {
    const int c = g.cell[static_cast<std::size_t>(m)];
    const int x = geo.X(c), y = geo.Y(c);
    for (int k = 0; k < 4; ++k) {
      if (!geo.InBounds(x + kDx[k], y + kDy[k])) continue;
      const int nb = compact[static_cast<std::size_t>(geo.Index(x + kDx[k], y + kDy[k]))];
      if (nb < 0) continue;
      g.neighbor[static_cast<std::size_t>(4 * m + k)] = nb;
      ++g.degree[static_cast<std::size_t>(m)];
    }
  }
  g.Prepare();
  result.unknowns = g.n * k_frames;
  if (g.n == 0) return result;

  Vec scratch;
  for (int comp = 0; comp < 2; ++comp) {
    auto component = [&](const TensorRaster& f) -> const std::vector<double>& {
      return comp == 0 ? f.tau11 : f.tau12;
    };
    Vec a(static_cast<std::size_t>(g.n)), b(static_cast<std::size_t>(g.n));
    Vec x(static_cast<std::size_t>(g.n) * k_frames);
    for (int m = 0; m < g.n; ++m) {
      const std::size_t c = static_cast<std::size_t>(g.cell[static_cast<std::size_t>(m)]);
      a[static_cast<std::size_t>(m)] = component(previous)[c];
      b[static_cast<std::size_t>(m)] = component(next)[c];
      for (int j = 0; j < k_frames; ++j) x[g.At(m, j)] = component(result.frames[j])[c];
    }
    const double e_linear = Energy(g, x, a, b, params.alpha, &scratch);
    result.energy_linear += e_linear;
    if (params.mode == InterpolationMode::kLinear) {
      result.energy += e_linear;
      continue;
    }
    bool converged = true;
    result.iterations += SolveComponent(g, a, b, params, &x, &converged);
    result.converged = result.converged && converged;
    result.energy += Energy(g, x, a, b, params.alpha, &scratch);
    for (int j = 0; j < k_frames; ++j) {
      std::vector<double>& out = comp == 0 ? result.frames[static_cast<std::size_t>(j)].tau11
                                           : result.frames[static_cast<std::size_t>(j)].tau12;
      for (int m = 0; m < g.n; ++m) {
        out[static_cast<std::size_t>(g.cell[static_cast<std::size_t>(m)])] = x[g.At(m, j)];
      }
    }
  }
  return result;
}

}  // namespace voxplan::tensorfield
