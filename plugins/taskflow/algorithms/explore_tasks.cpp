#include "plugins/taskflow/algorithms/explore_tasks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::taskflow {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-9;

bool IsFreeLike(FloorCell c) { return c == FloorCell::kFree || c == FloorCell::kFrontier; }

omt::Status Invalid(const char* message) {
  return omt::Status::Error(omt::Status::Code::kInvalidInput, message);
}

omt::Status CheckInput(const ExploreInput& input) {
  const auto n = static_cast<std::size_t>(input.floor.geometry.NumCells());
  if (input.floor.geometry.width <= 0 || input.floor.geometry.height <= 0 ||
      !(input.floor.geometry.resolution_m > 0.0))
    return Invalid("empty floor raster");
  if (input.floor.cells.size() != n || input.floor.clearance_m.size() != n)
    return Invalid("floor arrays do not match the raster");
  if (input.geodesic_m.size() != input.robots_xy_m.size())
    return Invalid("one geodesic field per robot is needed");
  for (const auto& field : input.geodesic_m)
    if (field.size() != n) return Invalid("geodesic field does not match the raster");
  if (!(input.camera.horizontal_fov_rad > 0.0) || !(input.camera.max_range_m > 0.0))
    return Invalid("explorer camera needs a FOV and range");
  return omt::Status::Ok();
}

// Covers the uncovered samples visible from `cell`: the FOV window holding the most of them
// (ties: the narrowest spread, then the lower first bearing), heading at the window's middle.
// Returns false when none is visible.
bool BestHeading(const ExploreInput& input, const std::vector<int>& samples,
                 const std::vector<std::uint8_t>& covered, int cell, double* theta_rad,
                 std::vector<int>* view_covers) {
  const omt::RasterGeometry& g = input.floor.geometry;
  const Eigen::Vector2d p = g.Center(cell);
  struct Bearing {
    double angle;
    int sample;
  };
  std::vector<Bearing> bearings;
  for (int s = 0; s < static_cast<int>(samples.size()); ++s) {
    if (covered[s]) continue;
    const Eigen::Vector2d d = g.Center(samples[s]) - p;
    const double r = d.norm();
    if (r < input.camera.min_range_m - kEps || r > input.camera.max_range_m + kEps) continue;
    if (samples[s] == cell || !LineOfSight(input.floor, cell, samples[s])) continue;
    bearings.push_back({std::atan2(d.y(), d.x()), s});
  }
  if (bearings.empty()) return false;
  std::sort(bearings.begin(), bearings.end(), [](const Bearing& a, const Bearing& b) {
    return a.angle != b.angle ? a.angle < b.angle : a.sample < b.sample;
  });
  const int n = static_cast<int>(bearings.size());
  const double fov = std::min(input.camera.horizontal_fov_rad, 2.0 * omt::kPi);
  int best_start = 0, best_count = 0;
  double best_span = kInf;
  for (int i = 0; i < n; ++i) {
    // Window [angle_i, angle_i + fov] counter-clockwise; bearings past index n − 1 wrap.
    int count = 0;
    double span = 0.0;
    for (int j = 0; j < n; ++j) {
      const int k = (i + j) % n;
      const double delta =
          bearings[k].angle - bearings[i].angle + (i + j >= n ? 2.0 * omt::kPi : 0.0);
      if (delta > fov + kEps) break;
      ++count;
      span = delta;
    }
    if (count > best_count || (count == best_count && span < best_span - kEps)) {
      best_start = i;
      best_count = count;
      best_span = span;
    }
  }
  *theta_rad = omt::WrapAngle(bearings[best_start].angle + 0.5 * best_span);
  view_covers->clear();
  for (int j = 0; j < best_count; ++j)
    view_covers->push_back(bearings[(best_start + j) % n].sample);
  std::sort(view_covers->begin(), view_covers->end());
  return true;
}

}  // namespace

std::vector<int> SampleFrontiers(const FloorView& floor, double spacing_m) {
  const omt::RasterGeometry& g = floor.geometry;
  std::vector<int> frontier;
  for (int i = 0; i < g.NumCells(); ++i)
    if (floor.At(i) == FloorCell::kFrontier) frontier.push_back(i);
  std::vector<int> samples;
  if (frontier.empty()) return samples;
  std::vector<Eigen::Vector2d> centre(frontier.size());
  for (std::size_t f = 0; f < frontier.size(); ++f) centre[f] = g.Center(frontier[f]);
  std::vector<double> nearest(frontier.size(), kInf);
  std::size_t pick = 0;
  while (true) {
    samples.push_back(frontier[pick]);
    std::size_t next = 0;
    double next_d = -1.0;
    for (std::size_t f = 0; f < frontier.size(); ++f) {
      nearest[f] = std::min(nearest[f], (centre[f] - centre[pick]).norm());
      if (nearest[f] > next_d) {
        next_d = nearest[f];
        next = f;
      }
    }
    if (next_d < spacing_m || next_d <= 0.0) break;
    pick = next;
  }
  return samples;
}

std::vector<float> NonFreeDistance(const FloorView& floor) {
  omt::OccupancyRaster raster;
  raster.geometry = floor.geometry;
  raster.cells.resize(static_cast<std::size_t>(floor.geometry.NumCells()));
  for (int i = 0; i < floor.geometry.NumCells(); ++i) {
    const FloorCell c = floor.At(i);
    raster.cells[static_cast<std::size_t>(i)] = IsFreeLike(c)              ? omt::Cell::kFree
                                                : c == FloorCell::kUnknown ? omt::Cell::kUnknown
                                                                           : omt::Cell::kOccupied;
  }
  return omt::ComputeClearance(raster, /*unknown_is_obstacle=*/true).clearance_m;
}

bool LineOfSight(const FloorView& floor, int from_cell, int to_cell) {
  if (from_cell == to_cell) return true;
  const omt::RasterGeometry& g = floor.geometry;
  const Eigen::Vector2d a = g.Center(from_cell);
  const Eigen::Vector2d d = g.Center(to_cell) - a;
  const double length = d.norm();
  // The target cell is entered at t <= length − res/2; later cells are beyond it.
  const double last_entry = length - 0.5 * g.resolution_m + kEps;
  bool clear = true;
  omt::TraverseRay(g, a, d / length, length, [&](int cell, double t) {
    if (cell == to_cell || t > last_entry) return false;
    if (cell != from_cell && !IsFreeLike(floor.At(cell))) {
      clear = false;
      return false;
    }
    return true;
  });
  return clear;
}

std::vector<std::uint8_t> TraversableCells(const ExploreInput& input, double min_clearance_m) {
  const int n = input.floor.geometry.NumCells();
  std::vector<std::uint8_t> out(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    if (!IsFreeLike(input.floor.At(i)) || input.floor.clearance_m[i] < min_clearance_m) continue;
    for (const auto& field : input.geodesic_m)
      if (std::isfinite(field[i])) {
        out[static_cast<std::size_t>(i)] = 1;
        break;
      }
  }
  return out;
}

std::vector<ViewCandidate> ViewCandidates(const ExploreInput& input,
                                          const std::vector<int>& frontier_samples,
                                          const std::vector<float>& non_free_distance_m,
                                          const ExploreParams& params) {
  const omt::RasterGeometry& g = input.floor.geometry;
  const std::vector<std::uint8_t> traversable = TraversableCells(input, params.min_clearance_m);
  const int stride =
      std::max(1, static_cast<int>(std::lround(params.candidate_spacing_m / g.resolution_m)));
  const int reach = static_cast<int>(std::ceil(params.max_view_distance_m / g.resolution_m));
  std::vector<int> slot(static_cast<std::size_t>(g.NumCells()), -1);
  std::vector<ViewCandidate> candidates;
  for (int s = 0; s < static_cast<int>(frontier_samples.size()); ++s) {
    const int fx = g.X(frontier_samples[s]);
    const int fy = g.Y(frontier_samples[s]);
    const Eigen::Vector2d f = g.Center(frontier_samples[s]);
    // Lattice cells (x, y multiples of stride) in the band's bounding box.
    const int x0 = (std::max(0, fx - reach) + stride - 1) / stride * stride;
    const int y0 = (std::max(0, fy - reach) + stride - 1) / stride * stride;
    for (int y = y0; y <= std::min(g.height - 1, fy + reach); y += stride) {
      for (int x = x0; x <= std::min(g.width - 1, fx + reach); x += stride) {
        const int cell = g.Index(x, y);
        if (!traversable[static_cast<std::size_t>(cell)] || cell == frontier_samples[s]) continue;
        const double r = (g.Center(cell) - f).norm();
        if (r < params.min_view_distance_m - kEps || r > params.max_view_distance_m + kEps)
          continue;
        if (!LineOfSight(input.floor, cell, frontier_samples[s])) continue;
        if (slot[static_cast<std::size_t>(cell)] < 0) {
          slot[static_cast<std::size_t>(cell)] = static_cast<int>(candidates.size());
          candidates.push_back({});
          candidates.back().cell = cell;
        }
        candidates[static_cast<std::size_t>(slot[static_cast<std::size_t>(cell)])]
            .frontiers.push_back(s);
      }
    }
  }
  for (ViewCandidate& c : candidates) {
    c.d_free_m = non_free_distance_m[static_cast<std::size_t>(c.cell)];
    c.d_robot_m = kInf;
    for (const auto& field : input.geodesic_m)
      c.d_robot_m = std::min(c.d_robot_m, static_cast<double>(field[c.cell]));
    c.score = params.paper_sign ? c.d_robot_m - c.d_free_m : c.d_free_m - c.d_robot_m;
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const ViewCandidate& a, const ViewCandidate& b) { return a.cell < b.cell; });
  return candidates;
}

ExploreResult GenerateExplorationTasks(const ExploreInput& input, const ExploreParams& params) {
  ExploreResult result;
  result.status = CheckInput(input);
  if (!result.status.ok()) return result;
  result.frontier_samples = SampleFrontiers(input.floor, params.frontier_spacing_m);
  const std::vector<float> non_free = NonFreeDistance(input.floor);
  std::vector<ViewCandidate> candidates =
      ViewCandidates(input, result.frontier_samples, non_free, params);
  result.num_candidates = static_cast<int>(candidates.size());
  const int max_views = params.max_views > 0
                            ? params.max_views
                            : params.views_per_robot * static_cast<int>(input.robots_xy_m.size());
  std::vector<std::uint8_t> covered(result.frontier_samples.size(), 0);
  std::vector<std::uint8_t> alive(candidates.size(), 1);
  while (static_cast<int>(result.views.size()) < max_views) {
    int best = -1;
    for (int c = 0; c < static_cast<int>(candidates.size()); ++c)
      if (alive[c] && (best < 0 || candidates[c].score > candidates[best].score)) best = c;
    if (best < 0) break;
    alive[best] = 0;
    ExploreView view;
    if (!BestHeading(input, result.frontier_samples, covered, candidates[best].cell,
                     &view.theta_rad, &view.covered))
      continue;  // its samples lie outside the camera's range
    view.cell = candidates[best].cell;
    view.xy_m = input.floor.geometry.Center(view.cell);
    view.score = candidates[best].score;
    for (int s : view.covered) covered[s] = 1;
    result.views.push_back(std::move(view));
    for (int c = 0; c < static_cast<int>(candidates.size()); ++c) {
      if (!alive[c]) continue;
      const auto& f = candidates[c].frontiers;
      if (std::all_of(f.begin(), f.end(), [&](int s) { return covered[s] != 0; })) alive[c] = 0;
    }
  }
  result.uncovered = static_cast<int>(std::count(covered.begin(), covered.end(), 0));
  return result;
}

}  // namespace voxplan::taskflow
