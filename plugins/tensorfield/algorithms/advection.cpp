// Pathline advection over (time-varying) tensor fields with RK4, stop conditions, the wall push
// and the wedge speed profile (X L182-195, L308).
#include "plugins/tensorfield/algorithms/advection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "plugins/omt/algorithms/raster_ops.h"

namespace voxplan::tensorfield {
namespace {

constexpr double kArcSlack_m = 1e-9;

// The field at (p, s): one raster, or the blend of the two frames around s.
struct FieldAt {
  std::span<const TensorRaster> frames;
  double spacing_m = 0.0;
  // AdvectionParams::vector_field: the components are a vector, followed with this sign.
  bool vector = false;
  double sign = 1.0;

  // Frame index at or before s, and the blend weight of the next one.
  std::pair<std::size_t, double> Locate(double s_m) const {
    if (frames.size() <= 1 || spacing_m <= 0.0) return {0, 0.0};
    const double t = std::max(0.0, s_m / spacing_m);
    const std::size_t k = static_cast<std::size_t>(std::floor(t));
    if (k + 1 >= frames.size()) return {frames.size() - 1, 0.0};
    return {k, t - static_cast<double>(k)};
  }
  const TensorRaster& Frame(double s_m) const { return frames[Locate(s_m).first]; }
  std::optional<Eigen::Vector2d> Sample(const Eigen::Vector2d& p_m, double s_m) const {
    const auto [k, a] = Locate(s_m);
    const std::optional<Eigen::Vector2d> t0 = SampleTensor(frames[k], p_m);
    if (!t0 || a == 0.0) return t0;
    const std::optional<Eigen::Vector2d> t1 = SampleTensor(frames[k + 1], p_m);
    if (!t1) return std::nullopt;
    return (1.0 - a) * *t0 + a * *t1;
  }
  std::optional<Eigen::Vector2d> Direction(const Eigen::Vector2d& p_m, double s_m,
                                           const Eigen::Vector2d& reference) const {
    const std::optional<Eigen::Vector2d> tau = Sample(p_m, s_m);
    if (!tau) return std::nullopt;
    if (vector) {
      const double n = tau->norm();
      return n > 0.0 ? Eigen::Vector2d(sign * *tau / n) : Eigen::Vector2d::Zero();
    }
    Eigen::Vector2d e = MajorEigenvector(*tau);
    if (e.dot(reference) < 0.0) e = -e;
    return e;
  }
};

// One classical RK4 step of arc length h, every stage oriented to agree with the direction of
// travel, so the step itself does (the robot never turns by more than 90° in one step). nullopt
// when a stage leaves the raster.
std::optional<Eigen::Vector2d> Rk4Step(const FieldAt& field, const Eigen::Vector2d& p, double s,
                                       double h, const Eigen::Vector2d& reference) {
  const std::optional<Eigen::Vector2d> k1 = field.Direction(p, s, reference);
  if (!k1) return std::nullopt;
  const std::optional<Eigen::Vector2d> k2 =
      field.Direction(p + 0.5 * h * *k1, s + 0.5 * h, reference);
  if (!k2) return std::nullopt;
  const std::optional<Eigen::Vector2d> k3 =
      field.Direction(p + 0.5 * h * *k2, s + 0.5 * h, reference);
  if (!k3) return std::nullopt;
  const std::optional<Eigen::Vector2d> k4 = field.Direction(p + h * *k3, s + h, reference);
  if (!k4) return std::nullopt;
  return Eigen::Vector2d(p + (h / 6.0) * (*k1 + 2.0 * *k2 + 2.0 * *k3 + *k4));
}

// Clearance at p (infinite without a raster).
double ClearanceAt(const AdvectionObstacles& obstacles, const Eigen::Vector2d& p) {
  if (obstacles.clearance == nullptr || obstacles.clearance->geometry.NumCells() == 0) {
    return std::numeric_limits<double>::infinity();
  }
  return omt::ClearanceBilinear(*obstacles.clearance, p);
}

bool Traversable(const AdvectionObstacles& obstacles, const AdvectionParams& params,
                 const Eigen::Vector2d& q, double clearance_from) {
  if (obstacles.traversable && !obstacles.traversable(q)) return false;
  const double c = ClearanceAt(obstacles, q);
  return !(c < params.block_clearance_m && c < clearance_from - 1e-9);
}

// Unit gradient of the clearance at p (away from the nearest wall); zero on a ridge or plateau
// (where the distance function's gradient is far from unit length).
Eigen::Vector2d WallNormal(const omt::ClearanceRaster& clearance, const Eigen::Vector2d& p) {
  const double h = 0.5 * clearance.geometry.resolution_m;
  const Eigen::Vector2d dx(h, 0.0), dy(0.0, h);
  const Eigen::Vector2d g(
      (omt::ClearanceBilinear(clearance, p + dx) - omt::ClearanceBilinear(clearance, p - dx)) /
          (2.0 * h),
      (omt::ClearanceBilinear(clearance, p + dy) - omt::ClearanceBilinear(clearance, p - dy)) /
          (2.0 * h));
  const double n = g.norm();
  return n < 0.5 ? Eigen::Vector2d::Zero() : Eigen::Vector2d(g / n);
}

// Per tracked degenerate point: distance at the previous point, and whether the line has moved
// towards it while inside its capture radius.
struct Approach {
  int index = 0;
  double radius = 0.0;
  double previous = 0.0;
  bool approached = false;
};

AdvectionStop StopFor(DegenerateType type) {
  return type == DegenerateType::kWedge ? AdvectionStop::kWedge : AdvectionStop::kTrisector;
}

void FillHeadings(std::vector<PathPoint>* points, double start_heading) {
  const std::size_t n = points->size();
  if (n == 0) return;
  if (n == 1) {
    (*points)[0].heading_rad = omt::WrapAngle(start_heading);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1;
    const std::size_t b = i + 1 == n ? n - 1 : i + 1;
    const Eigen::Vector2d d = (*points)[b].position_m - (*points)[a].position_m;
    (*points)[i].heading_rad = std::atan2(d.y(), d.x());
  }
}

Pathline Advect(FieldAt field, const Eigen::Vector2d& start_m, double heading_rad,
                std::span<const DegeneratePoint> degenerate, const AdvectionParams& params,
                const AdvectionObstacles& obstacles) {
  Pathline line;
  const std::optional<Eigen::Vector2d> at_start =
      field.frames.empty() ? std::nullopt : field.Sample(start_m, 0.0);
  if (!at_start) {
    line.stop = AdvectionStop::kLeftDomain;
    return line;
  }
  field.vector = params.vector_field;
  if (field.vector)
    field.sign = at_start->dot(Eigen::Vector2d(std::cos(heading_rad), std::sin(heading_rad))) < 0.0
                     ? -1.0
                     : 1.0;
  const double threshold = params.min_magnitude >= 0.0
                               ? params.min_magnitude
                               : params.min_relative_magnitude * MaxFieldMagnitude(field.frames[0]);
  const double step = std::max(params.step_m, 1e-6);
  const double main_length = std::max(0.0, params.max_length_m);
  const double lookahead =
      params.stop_at_wedges ? main_length + std::max(0.0, params.slowdown_distance_m) : main_length;

  std::vector<Approach> approaches;
  for (std::size_t i = 0; i < degenerate.size(); ++i) {
    const bool wedge = degenerate[i].type == DegenerateType::kWedge;
    if (wedge ? !params.stop_at_wedges : !params.stop_at_trisectors) continue;
    Approach a;
    a.index = static_cast<int>(i);
    a.radius = wedge ? params.wedge_capture_radius_m : params.trisector_capture_radius_m;
    a.previous = (start_m - degenerate[i].position_m).norm();
    approaches.push_back(a);
  }

  std::vector<PathPoint> points;
  points.push_back({start_m, 0.0, heading_rad, 0.0});
  Eigen::Vector2d p = start_m;
  Eigen::Vector2d reference(std::cos(heading_rad), std::sin(heading_rad));
  double s = 0.0;
  double clearance_p = ClearanceAt(obstacles, p);
  std::size_t main_end = 0;  // last point of the returned line once s reaches main_length
  bool main_done = main_length <= kArcSlack_m;
  AdvectionStop stop = AdvectionStop::kLength;
  int stop_point = -1;
  int pushes = 0;

  while (true) {
    if (s >= lookahead - kArcSlack_m) break;
    const std::optional<Eigen::Vector2d> tau = field.Sample(p, s);
    if (!tau || (s >= params.magnitude_check_after_m && TensorMagnitude(*tau) < threshold)) {
      stop = AdvectionStop::kDegenerate;
      // Near (not exactly on) a point the line approaches, the field vanishes before the capture
      // rule fires: that is arriving there.
      for (const Approach& a : approaches) {
        const double d = (p - degenerate[static_cast<std::size_t>(a.index)].position_m).norm();
        if (a.approached && d <= a.radius &&
            (stop_point < 0 ||
             d < (p - degenerate[static_cast<std::size_t>(stop_point)].position_m).norm())) {
          stop_point = a.index;
        }
      }
      if (stop_point >= 0) stop = StopFor(degenerate[static_cast<std::size_t>(stop_point)].type);
      break;
    }
    const double target = main_done ? lookahead : main_length;
    const double h = std::min(step, target - s);
    std::optional<Eigen::Vector2d> q = Rk4Step(field, p, s, h, reference);
    if (!q) {
      stop = AdvectionStop::kLeftDomain;
      break;
    }
    if ((*q - p).norm() < 1e-3 * h) {  // the stages cancel: a degenerate point
      stop = AdvectionStop::kDegenerate;
      break;
    }
    // X L308: too close to a known wall, move away along its normal if the known space allows.
    if (obstacles.clearance != nullptr && params.wall_clearance_m > 0.0) {
      const double c = ClearanceAt(obstacles, *q);
      if (c < params.wall_clearance_m) {
        const Eigen::Vector2d n = WallNormal(*obstacles.clearance, *q);
        if (n.squaredNorm() > 0.0) {
          const Eigen::Vector2d pushed =
              *q + std::min(params.wall_clearance_m - c, params.wall_push_per_step_m) * n;
          const int cell = field.Frame(s + h).geometry.IndexOf(pushed);
          const bool in_domain =
              cell >= 0 && (!params.stop_outside_domain || field.Frame(s + h).InDomain(cell));
          if (in_domain && Traversable(obstacles, params, pushed, clearance_p)) {
            q = pushed;
            if (!main_done) ++pushes;
          }
        }
      }
    }
    if (!Traversable(obstacles, params, *q, clearance_p)) {
      stop = AdvectionStop::kBlocked;
      break;
    }
    const double s_new = s + (*q - p).norm();
    if (s_new - s < 1e-3 * h) {  // the wall push undid the step: the wall blocks the way
      stop = AdvectionStop::kBlocked;
      break;
    }
    const TensorRaster& frame = field.Frame(s_new);
    const int cell = frame.geometry.IndexOf(*q);
    if (cell < 0 || (params.stop_outside_domain && !frame.InDomain(cell))) {
      stop = AdvectionStop::kLeftDomain;
      break;
    }
    reference = (*q - p) / (*q - p).norm();
    points.push_back({*q, s_new, 0.0, 0.0});

    // Degenerate points: arrival, or the closest approach inside the capture radius.
    double best = std::numeric_limits<double>::infinity();
    bool pop = false;
    for (Approach& a : approaches) {
      const double d = (*q - degenerate[static_cast<std::size_t>(a.index)].position_m).norm();
      if (d <= params.arrive_radius_m && d < best) {
        best = d;
        stop_point = a.index;
        pop = false;
      } else if (a.approached && d > a.previous && a.previous <= a.radius && a.previous < best) {
        best = a.previous;
        stop_point = a.index;
        pop = true;  // the previous point was the closest
      }
      if (d < a.previous && d <= a.radius) a.approached = true;
      a.previous = d;
    }
    if (stop_point >= 0) {
      if (pop) points.pop_back();
      stop = StopFor(degenerate[static_cast<std::size_t>(stop_point)].type);
      if (!main_done && points.back().arc_length_m >= main_length - kArcSlack_m) {
        main_done = true;
        main_end = points.size() - 1;
      }
      break;
    }
    // A closed loop.
    bool loop = false;
    for (const PathPoint& earlier : points) {
      if (earlier.arc_length_m > s_new - params.loop_min_arc_m) break;
      if ((earlier.position_m - *q).norm() <= params.loop_radius_m) {
        loop = true;
        break;
      }
    }
    p = *q;
    s = s_new;
    clearance_p = ClearanceAt(obstacles, p);
    if (!main_done && s >= main_length - kArcSlack_m) {
      main_done = true;
      main_end = points.size() - 1;
    }
    if (loop) {
      stop = AdvectionStop::kLoop;
      break;
    }
  }

  if (!main_done) {  // the line ended before max_length: that is its stop
    line.stop = stop;
    line.stop_point = stop_point;
    main_end = points.size() - 1;
  } else {
    line.stop = AdvectionStop::kLength;
    // A wedge or trisector reached exactly at the main end still stops the line there.
    const bool at_point = stop == AdvectionStop::kWedge || stop == AdvectionStop::kTrisector;
    if (at_point && points.size() - 1 == main_end) {
      line.stop = stop;
      line.stop_point = stop_point;
    }
  }
  if (stop == AdvectionStop::kWedge && stop_point >= 0) {
    line.wedge_ahead = stop_point;
    line.wedge_ahead_arc_m = points.back().arc_length_m;
  }
  points.resize(main_end + 1);
  FillHeadings(&points, heading_rad);
  for (PathPoint& pt : points) {
    pt.speed_mps = SpeedBeforeWedge(pt.arc_length_m, line.wedge_ahead_arc_m, params);
  }
  line.points = std::move(points);
  line.wall_pushes = pushes;
  return line;
}

}  // namespace

double MaxFieldMagnitude(const TensorRaster& field) {
  double best = 0.0;
  for (int i = 0; i < field.geometry.NumCells(); ++i) {
    if (field.InDomain(i)) best = std::max(best, TensorMagnitude(field.At(i)));
  }
  return best;
}

std::optional<Eigen::Vector2d> OrientedDirection(const TensorRaster& field,
                                                 const Eigen::Vector2d& p_m,
                                                 const Eigen::Vector2d& reference) {
  const FieldAt f{std::span<const TensorRaster>(&field, 1), 0.0, false, 1.0};
  return f.Direction(p_m, 0.0, reference);
}

double SpeedBeforeWedge(double s_m, double wedge_arc_m, const AdvectionParams& params) {
  if (wedge_arc_m < 0.0) return params.max_speed_mps;
  const double remaining = std::max(0.0, wedge_arc_m - s_m);
  if (params.slowdown_distance_m <= 0.0) {
    return remaining > 0.0 ? params.max_speed_mps : params.min_speed_mps;
  }
  const double a = std::min(1.0, remaining / params.slowdown_distance_m);
  return params.min_speed_mps + a * (params.max_speed_mps - params.min_speed_mps);
}

Pathline AdvectPathline(const TensorRaster& field, const Eigen::Vector2d& start_m,
                        double heading_rad, std::span<const DegeneratePoint> degenerate_points,
                        const AdvectionParams& params, const AdvectionObstacles& obstacles) {
  return Advect(FieldAt{std::span<const TensorRaster>(&field, 1), 0.0, false, 1.0}, start_m,
                heading_rad, degenerate_points, params, obstacles);
}

Pathline AdvectPathline(std::span<const TensorRaster> frames, const Eigen::Vector2d& start_m,
                        double heading_rad, std::span<const DegeneratePoint> degenerate_points,
                        const AdvectionParams& params, const AdvectionObstacles& obstacles) {
  return Advect(FieldAt{frames, params.frame_spacing_m, false, 1.0}, start_m, heading_rad,
                degenerate_points, params, obstacles);
}

}  // namespace voxplan::tensorfield
