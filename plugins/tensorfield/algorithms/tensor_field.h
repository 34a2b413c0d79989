// The tensor-field core of Xu et al. 2017 (X eq. 1-5, planner-wave.md G.2 items 1-3) over plain
// rasters: key-frame fields blended from boundary tangents, their degenerate points (wedges and
// trisectors) with separatrix directions, the space-time interpolation between key frames, and the
// vector-field baselines of X Fig. 2 (boundary normals or oriented tangents blended the same way)
// with their singularities, so that "a tensor field has fewer singular points" can be measured.
//
// A field is stored as its traceless part (X eq. 2 with λ = 0, as the paper uses it for paths):
// (τ11, τ12) = μ (cos 2θ, sin 2θ), θ the major eigenvector's angle. Everything is deterministic,
// single-threaded and prints nothing; expected failures come back as values.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::tensorfield {

// ---------------------------------------------------------------------------------------------
// Tensor basics (X eq. 1-2).

// Per cell (τ11, τ12) at the cell centre. domain marks the cells the field is defined on (free
// space): topology is searched there only. Cells outside it may still hold values (the key-frame
// field fills a thin band behind walls so that interpolation near a wall sees no artificial step).
struct TensorRaster {
  omt::RasterGeometry geometry;
  std::vector<double> tau11;
  std::vector<double> tau12;
  std::vector<std::uint8_t> domain;  // non-zero: defined; empty: every cell

  bool InDomain(int index) const {
    return domain.empty() || domain[static_cast<std::size_t>(index)] != 0;
  }
  Eigen::Vector2d At(int index) const {
    return {tau11[static_cast<std::size_t>(index)], tau12[static_cast<std::size_t>(index)]};
  }
};

// A zero field over `geometry` with an empty (everywhere) domain.
TensorRaster MakeTensorRaster(const omt::RasterGeometry& geometry);

// μ (cos 2θ, sin 2θ): the tensor whose major eigenvector has angle θ.
inline Eigen::Vector2d BasisTensor(double theta_rad, double magnitude = 1.0) {
  return magnitude * Eigen::Vector2d(std::cos(2.0 * theta_rad), std::sin(2.0 * theta_rad));
}
// Major eigenvector angle θ = atan2(τ12, τ11) / 2, in (-π/2, π/2]; 0 for the zero tensor.
inline double MajorAngle(const Eigen::Vector2d& tau) { return 0.5 * std::atan2(tau.y(), tau.x()); }
// μ = |(τ11, τ12)|, half the eigenvalue gap.
inline double TensorMagnitude(const Eigen::Vector2d& tau) { return tau.norm(); }
// Unit major eigenvector (cos θ, sin θ); the sign is arbitrary (a line field).
inline Eigen::Vector2d MajorEigenvector(const Eigen::Vector2d& tau) {
  const double theta = MajorAngle(tau);
  return {std::cos(theta), std::sin(theta)};
}

// Bilinear interpolation of (τ11, τ12) between cell centres at a world point (clamped to the
// outermost centres at the raster's edge); nullopt outside the raster. Domain is not consulted.
std::optional<Eigen::Vector2d> SampleTensor(const TensorRaster& field, const Eigen::Vector2d& p_m);

// ---------------------------------------------------------------------------------------------
// Key-frame field (X eq. 3, X L161-168).

struct KeyFrameParams {
  double sample_spacing_m = 0.2;     // d_s: farthest-point sampling stops below this gap (X L163)
  double sigma_per_spacing = 2.5;    // σ = 2.5 d_s = 0.5 m (X L168)
  double truncation_sigmas = 3.0;    // a basis field is cut off beyond this many σ
  double basis_magnitude = 1.0;      // μ of every basis tensor (silent in the paper)
  int tangent_fit_radius_cells = 2;  // line fit over boundary cells in a (2r+1)² window (5-point)
  // Boundary cells whose line fit has λ_min / λ_max at least this are corners and seed the
  // sampling (non-positive: plain farthest-point sampling from the lowest index).
  double corner_min_ratio = 0.15;
  bool eight_connected_boundary = false;  // boundary: occupied with a free 4- (or 8-) neighbour
  bool include_unknown = false;  // define the field on unknown cells too, not just free ones
  int value_band_cells = 2;      // also fill values this far outside the domain (not domain)
};

// One constraint point of X eq. 3: a boundary cell centre, the fitted tangent and the normal
// pointing into free space; tangent = normal turned by -90°, so free space lies on its left and
// tangents are consistently oriented along a contour (used by the vector baseline).
struct BoundarySample {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d tangent = Eigen::Vector2d::UnitX();
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();
  int cell = -1;
};

// Occupied cells with a free 4- (or 8-) neighbour, by increasing index.
std::vector<int> BoundaryCells(const omt::OccupancyRaster& raster, bool eight_connected);

// Cells the field is defined on: free cells (and unknown ones when include_unknown), as 0/1.
std::vector<std::uint8_t> FieldDomain(const omt::OccupancyRaster& raster, bool include_unknown);

// Farthest-point sampling of the boundary cells until every boundary cell is closer than d_s to a
// sample (ties to the lower index), seeded with the corners (see corner_min_ratio) or else the
// lowest index; each sample's tangent by PCA of the boundary cells in its window, its normal
// towards the free cells there.
std::vector<BoundarySample> SampleBoundary(const omt::OccupancyRaster& raster,
                                           const KeyFrameParams& params);

// X eq. 3: T(p) = Σ_i exp(-|p - p_i|² / σ²) T_i, T_i = μ (cos 2θ_i, sin 2θ_i) with θ_i the
// tangent angle, evaluated on the domain cells plus a value band of params.value_band_cells.
// domain: one byte per cell (empty: every cell).
TensorRaster BlendTensorField(const omt::RasterGeometry& geometry,
                              std::span<const BoundarySample> samples,
                              std::span<const std::uint8_t> domain, const KeyFrameParams& params);

// Cells within radius_cells (Chebyshev) of a non-zero cell of mask (one byte per cell), as 0/1.
std::vector<std::uint8_t> DilateMask(const omt::RasterGeometry& geometry,
                                     std::span<const std::uint8_t> mask, int radius_cells);

// SampleBoundary + FieldDomain + BlendTensorField. samples_out (optional) receives the samples.
TensorRaster KeyFrameField(const omt::OccupancyRaster& raster, const KeyFrameParams& params,
                           std::vector<BoundarySample>* samples_out = nullptr);

// ---------------------------------------------------------------------------------------------
// Degenerate points (X L312: tensor index on grid cells; separatrices after Delmarcelle &
// Hesselink 1994).

enum class DegenerateType : std::uint8_t {
  kWedge,      // tensor index +1/2
  kTrisector,  // tensor index -1/2
};

struct DegeneratePoint {
  DegenerateType type = DegenerateType::kWedge;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int cell_x = 0;  // the corner loop is cells (x, y), (x+1, y), (x+1, y+1), (x, y+1)
  int cell_y = 0;
  // Directions (world angles in [0, 2π), increasing) of the rays from the point along which the
  // major eigenvector is radial, from the field linearised at the point: one or three for a
  // wedge, three for a trisector (Delmarcelle & Hesselink). Empty when the linearisation is
  // degenerate (zero Jacobian).
  std::vector<double> separatrix_angles_rad;
  Eigen::Matrix2d jacobian = Eigen::Matrix2d::Zero();  // rows d(τ11), d(τ12) by (dx, dy), per m
};

struct TopologyParams {
  // Solve the bilinear τ11 = τ12 = 0 inside the loop's square (Newton); otherwise, or when that
  // fails, the square's centre (the cells' shared corner).
  bool refine_position = true;
  int separatrix_scan_steps = 720;  // angular scan for the radial directions, then bisection
  // Loops whose largest magnitude is below this share of the field's largest are flat, near-zero
  // regions (beyond ~2.5σ of every wall the blend is e^-6 of a basis tensor or exactly zero), where
  // solver noise of 1e-5 would otherwise draw dozens of meaningless points. A genuine degenerate
  // point keeps one corner of its loop at about |∇τ| × res, far above this.
  double min_relative_magnitude = 1e-3;
};

// Every 2x2 corner loop whose four cells lie in the domain (and that is not flat, see
// min_relative_magnitude); the wrapped changes of 2θ around it (counter-clockwise) sum to ±2π at a
// wedge / trisector. Sorted by (cell_y, cell_x).
std::vector<DegeneratePoint> FindDegeneratePoints(const TensorRaster& field,
                                                  const TopologyParams& params = {});

// Radial directions of the linear field τ(r) = J r around a degenerate point (J: rows τ11, τ12
// by x, y): the angles φ where J (cos φ, sin φ) points along (cos 2φ, sin 2φ).
std::vector<double> SeparatrixAngles(const Eigen::Matrix2d& jacobian, int scan_steps = 720);

// Tensor index of one closed loop of tensors (counter-clockwise): the sum of wrapped changes of
// 2θ over 4π, so ±1/2 at wedges / trisectors, 0 around regular regions.
double TensorIndex(std::span<const Eigen::Vector2d> loop);

// ---------------------------------------------------------------------------------------------
// Space-time interpolation (X eq. 4-5).

enum class InterpolationMode : std::uint8_t {
  kSpaceTime,  // eq. 4's energy minimised over the mask
  kLinear,     // point-wise linear blend (the ablation of X Fig. 6c, 14)
};

// Which space-time vertices carry a Laplacian row in ‖Δ_ST τ‖².
enum class SpaceTimeRows : std::uint8_t {
  // Every vertex, frames 0 and K included (their one temporal neighbour normalised in ω), with the
  // key frames as soft constraints of weight α: eq. 4 as written, least-squares-meshes style. The
  // end frames then move by O(1/α) and the minimiser is genuinely bi-harmonic.
  kAllFrames,
  // Frames 1..K-1 only, the key frames as exact Dirichlet data (X L170's wording). With as many
  // rows as unknowns the minimum is Δ_ST τ = 0: harmonic interpolation, and a better-conditioned
  // system (solved directly in its symmetric ω-scaled form).
  kInteriorFrames,
};

struct SpaceTimeParams {
  InterpolationMode mode = InterpolationMode::kSpaceTime;
  SpaceTimeRows rows = SpaceTimeRows::kAllFrames;
  int substeps = 10;             // K: frames 0..K are returned (X§6, Fig. 15)
  double alpha = 5e3;            // weight of the key-frame constraints (X L176)
  double spatial_weight = 1.0;   // ω_S (X eq. 5)
  double temporal_weight = 2.0;  // ω_T (X eq. 5)
  int max_iterations = 400;      // conjugate-gradient cap per component (τ11, τ12)
  // Stop when |residual| <= tolerance * |warm-start residual|. On a 20 m x 20 m apartment 1e-2
  // already leaves the energy within 1e-4 of its converged value (about 100 iterations).
  double tolerance = 1e-2;
};

// Cells the solve runs on: the union of both key frames' domains, dilated by band_cells
// (Chebyshev), optionally cut to a disc around window_centre_m (the robot).
struct MaskParams {
  int band_cells = 2;
  bool use_window = false;
  Eigen::Vector2d window_centre_m = Eigen::Vector2d::Zero();
  double window_radius_m = 3.0;
};
std::vector<std::uint8_t> InterpolationMask(const TensorRaster& previous, const TensorRaster& next,
                                            const MaskParams& params);

struct SpaceTimeResult {
  omt::Status status;
  std::vector<TensorRaster> frames;  // K + 1: frames[0] ≈ previous, frames[K] ≈ next
  // Eq. 4's energy over the mask, summed over τ11 and τ12: of the point-wise linear blend and of
  // the returned frames (equal in linear mode).
  double energy_linear = 0.0;
  double energy = 0.0;
  int unknowns = 0;       // mask cells × (K + 1)
  int iterations = 0;     // conjugate-gradient iterations, both components together
  bool converged = true;  // both components reached the tolerance within the cap
};

// The K + 1 frames between previous (frame 0) and next (frame K), which must share a geometry.
// Space-time mode solves on the mask cells (one byte per cell; empty: every cell) warm-started
// from the linear blend; cells outside the mask get the linear blend. Frames' domain is the union
// of the two key frames' domains.
SpaceTimeResult InterpolateFrames(const TensorRaster& previous, const TensorRaster& next,
                                  std::span<const std::uint8_t> mask,
                                  const SpaceTimeParams& params);

// ---------------------------------------------------------------------------------------------
// Vector-field baselines from the same constraints (X Fig. 2; planner-wave.md G.2 item 8).

enum class VectorConstraint : std::uint8_t {
  kNormal,   // boundary normals into free space (the potential-field style, "vector_normal")
  kTangent,  // tangents oriented with free space on their left ("vector_tangent")
};

struct VectorRaster {
  omt::RasterGeometry geometry;
  std::vector<double> vx;
  std::vector<double> vy;
  std::vector<std::uint8_t> domain;  // as TensorRaster::domain

  bool InDomain(int index) const {
    return domain.empty() || domain[static_cast<std::size_t>(index)] != 0;
  }
  Eigen::Vector2d At(int index) const {
    return {vx[static_cast<std::size_t>(index)], vy[static_cast<std::size_t>(index)]};
  }
};

// V(p) = Σ_i exp(-|p - p_i|² / σ²) v_i with the unit normal or tangent of each sample, with the
// key-frame field's σ, truncation, magnitude and value band.
VectorRaster BlendVectorField(const omt::RasterGeometry& geometry,
                              std::span<const BoundarySample> samples,
                              std::span<const std::uint8_t> domain, VectorConstraint constraint,
                              const KeyFrameParams& params);

struct VectorSingularity {
  int index = 0;  // Poincaré index, ±1 (a loop can in principle wind ±2; reported as is)
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  // the loop square's centre
  int cell_x = 0;
  int cell_y = 0;
};

// Every 2x2 corner loop in the domain around which the vector angle winds by a non-zero multiple
// of 2π, with the same flat-region rule as FindDegeneratePoints (params.min_relative_magnitude;
// the other fields are unused). Sorted by (cell_y, cell_x).
std::vector<VectorSingularity> FindVectorSingularities(const VectorRaster& field,
                                                       const TopologyParams& params = {});

// X Fig. 2's census from one key frame's constraints: the tensor blend's degenerate points and the
// normal-oriented vector blend's singularities (the tangent-oriented one is that field turned by
// -90° everywhere, so its count is the same). Both blends run to 6σ instead of params'
// truncation and without the flat-region rule, so that a room's interior is counted: at 3σ a room
// centre more than 1.5 m from every wall is exactly zero, and a convex room's one sink of the
// normal field lies there (against the tensor field's two wedges, index +1/2 each).
struct FieldCensus {
  int degenerate_points = 0;
  int vector_singularities = 0;
};
FieldCensus CountFieldCensus(const omt::RasterGeometry& geometry,
                             std::span<const BoundarySample> samples,
                             std::span<const std::uint8_t> domain, const KeyFrameParams& params);

}  // namespace voxplan::tensorfield
