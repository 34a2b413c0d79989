#include "plugins/taskflow/algorithms/completion.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>

namespace voxplan::taskflow {
namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInf = std::numeric_limits<float>::infinity();

// SplitMix64: a fixed, portable generator (std:: distributions differ between libraries).
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t Next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
};

// Static k-d tree over a point span (the span must outlive it): median splits on the axis of
// largest spread, small leaves scanned linearly.
class KdTree {
 public:
  explicit KdTree(std::span<const Eigen::Vector3f> points) : points_(points) {
    index_.resize(points.size());
    std::iota(index_.begin(), index_.end(), 0);
    if (!index_.empty()) Build(0, static_cast<int>(index_.size()));
  }

  float NearestSquared(const Eigen::Vector3f& q) const {
    float best = kInf;
    if (!nodes_.empty()) Search(0, q, &best);
    return best;
  }

 private:
  static constexpr int kLeafSize = 8;
  struct Node {
    int begin = 0, end = 0;
    int left = -1, right = -1;
    int axis = 0;
    float split = 0.0f;
  };

  int Build(int begin, int end) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back({begin, end});
    if (end - begin <= kLeafSize) return id;
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(kInf), hi = -lo;
    for (int i = begin; i < end; ++i) {
      lo = lo.cwiseMin(points_[index_[i]]);
      hi = hi.cwiseMax(points_[index_[i]]);
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const int mid = (begin + end) / 2;
    std::nth_element(index_.begin() + begin, index_.begin() + mid, index_.begin() + end,
                     [&](int a, int b) {
                       const float pa = points_[a][axis], pb = points_[b][axis];
                       return pa < pb || (pa == pb && a < b);
                     });
    const float split = points_[index_[mid]][axis];
    const int left = Build(begin, mid);
    const int right = Build(mid, end);
    nodes_[id].left = left;
    nodes_[id].right = right;
    nodes_[id].axis = axis;
    nodes_[id].split = split;
    return id;
  }

  void Search(int id, const Eigen::Vector3f& q, float* best) const {
    const Node& n = nodes_[id];
    if (n.left < 0) {
      for (int i = n.begin; i < n.end; ++i)
        *best = std::min(*best, (points_[index_[i]] - q).squaredNorm());
      return;
    }
    // Left holds coordinates <= split, right >= split: the far side is at least |diff| away.
    const float diff = q[n.axis] - n.split;
    Search(diff < 0.0f ? n.left : n.right, q, best);
    if (diff * diff < *best) Search(diff < 0.0f ? n.right : n.left, q, best);
  }

  std::span<const Eigen::Vector3f> points_;
  std::vector<int> index_;
  std::vector<Node> nodes_;
};

// Points with outward normals, appended part by part.
struct Samples {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  void Add(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    points.push_back(p);
    normals.push_back(n);
  }
};

// Cell-centred grid on the parallelogram origin + [0,1]·a + [0,1]·b.
void SampleRect(const Eigen::Vector3f& origin, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                const Eigen::Vector3f& normal, float spacing, Samples* out) {
  const int na = std::max(1, static_cast<int>(std::ceil(a.norm() / spacing)));
  const int nb = std::max(1, static_cast<int>(std::ceil(b.norm() / spacing)));
  for (int i = 0; i < na; ++i) {
    for (int j = 0; j < nb; ++j) {
      const float fa = (static_cast<float>(i) + 0.5f) / static_cast<float>(na);
      const float fb = (static_cast<float>(j) + 0.5f) / static_cast<float>(nb);
      out->Add(origin + fa * a + fb * b, normal);
    }
  }
}

// Spacing that keeps `area` under max_points samples.
float PartSpacing(float area, const CompletionParams& params) {
  const float floor_spacing = std::max(params.surface_spacing_m, 1e-3f);
  const float budget = static_cast<float>(std::max(1, params.max_part_points));
  return std::max(floor_spacing, std::sqrt(std::max(area, 0.0f) / budget));
}

Eigen::Vector3f Lift(const Eigen::Vector2f& xy, float z) { return {xy.x(), xy.y(), z}; }

Eigen::Vector2f Perp(const Eigen::Vector2f& v) { return {-v.y(), v.x()}; }

// Direction with angle in [0, π): a line's orientation written one way only.
Eigen::Vector2f CanonicalAxis(Eigen::Vector2f v) {
  if (v.y() < 0.0f || (v.y() == 0.0f && v.x() < 0.0f)) v = -v;
  return v;
}

Eigen::Vector2f PcaAxis(std::span<const Eigen::Vector2f> xy) {
  if (xy.size() < 2) return Eigen::Vector2f::UnitX();
  Eigen::Vector2f mean = Eigen::Vector2f::Zero();
  for (const Eigen::Vector2f& p : xy) mean += p;
  mean /= static_cast<float>(xy.size());
  Eigen::Matrix2f cov = Eigen::Matrix2f::Zero();
  for (const Eigen::Vector2f& p : xy) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> eig(cov);
  const Eigen::Vector2f major = eig.eigenvectors().col(1);  // eigenvalues ascend
  if (!major.allFinite() || major.squaredNorm() < 1e-12f) return Eigen::Vector2f::UnitX();
  return CanonicalAxis(major.normalized());
}

// Footprint rectangle in (s, t) = (p·axis0, p·axis1) coordinates.
struct Rect {
  Eigen::Vector2f axis0 = Eigen::Vector2f::UnitX();
  float lo[2] = {0.0f, 0.0f};
  float hi[2] = {0.0f, 0.0f};
  Eigen::Vector2f Axis(int k) const { return k == 0 ? axis0 : Perp(axis0); }
  float Extent(int k) const { return hi[k] - lo[k]; }
  Eigen::Vector2f Centre() const {
    return 0.5f * (lo[0] + hi[0]) * Axis(0) + 0.5f * (lo[1] + hi[1]) * Axis(1);
  }
};

Rect RectAround(std::span<const Eigen::Vector2f> xy, const Eigen::Vector2f& axis) {
  Rect r;
  r.axis0 = axis;
  r.lo[0] = r.lo[1] = kInf;
  r.hi[0] = r.hi[1] = -kInf;
  for (const Eigen::Vector2f& p : xy) {
    for (int k = 0; k < 2; ++k) {
      const float c = p.dot(r.Axis(k));
      r.lo[k] = std::min(r.lo[k], c);
      r.hi[k] = std::max(r.hi[k], c);
    }
  }
  return r;
}

// The footprint rectangle, axis0 along its longer side.
Rect FitFootprint(std::span<const Eigen::Vector2f> xy, const std::vector<Eigen::Vector2f>& hull,
                  BoxFit fit) {
  Eigen::Vector2f axis = PcaAxis(xy);
  if (fit == BoxFit::kMinAreaRect && hull.size() >= 3) {
    float best_area = kInf;
    for (std::size_t i = 0; i < hull.size(); ++i) {
      const Eigen::Vector2f edge = hull[(i + 1) % hull.size()] - hull[i];
      if (edge.squaredNorm() < 1e-12f) continue;
      const Rect r = RectAround(hull, CanonicalAxis(edge.normalized()));
      const float area = r.Extent(0) * r.Extent(1);
      if (area < best_area) {
        best_area = area;
        axis = r.axis0;
      }
    }
  }
  Rect r = RectAround(xy, axis);
  if (r.Extent(1) > r.Extent(0)) r = RectAround(xy, CanonicalAxis(Perp(axis)));
  return r;
}

float FreeShare(const std::vector<Eigen::Vector3f>& points, const SpaceQuery& space) {
  if (points.empty()) return 0.0f;
  std::vector<std::uint8_t> state(points.size(), kUnobserved);
  space(points, state);
  const auto free = std::count(state.begin(), state.end(), std::uint8_t{kObservedFree});
  return static_cast<float>(free) / static_cast<float>(points.size());
}

// Grows each side of the footprint rectangle outward while the swept face is not observed free
// (see CompletionParams::box_grow). Axis 0 first, then axis 1 over the grown axis-0 extent.
void GrowBox(Rect* r, float floor_z, float top_z, const SpaceQuery& space,
             const CompletionParams& params) {
  const float step = std::max(params.box_grow_step_m, 1e-3f);
  const float height = top_z - floor_z;
  for (int k = 0; k < 2; ++k) {
    const int other = 1 - k;
    const float max_growth = params.box_max_growth * r->Extent(k);
    const float face_len = r->Extent(other);
    const float check_spacing =
        std::max(2.0f * params.surface_spacing_m, std::sqrt(face_len * height / 256.0f));
    for (int side = 0; side < 2; ++side) {
      const float sign = side == 0 ? -1.0f : 1.0f;
      float grown = 0.0f;
      // Steps of at most `step`, the last one landing on max_growth exactly.
      const int steps = static_cast<int>(std::ceil(max_growth / step - 1e-4f));
      for (int i = 1; i <= steps; ++i) {
        const float d = max_growth * static_cast<float>(i) / static_cast<float>(steps);
        const float s = side == 0 ? r->lo[k] - d : r->hi[k] + d;
        const Eigen::Vector2f origin = s * r->Axis(k) + r->lo[other] * r->Axis(other);
        Samples face;
        SampleRect(Lift(origin, floor_z), Lift(face_len * r->Axis(other), 0.0f),
                   Eigen::Vector3f(0.0f, 0.0f, height), Lift(sign * r->Axis(k), 0.0f),
                   check_spacing, &face);
        if (FreeShare(face.points, space) >= params.box_grow_max_free) break;
        grown = d;
      }
      if (side == 0) {
        r->lo[k] -= grown;
      } else {
        r->hi[k] += grown;
      }
    }
  }
}

// Four walls and the top of the floor-supported box; the bottom rests on the floor and can never
// be scanned, so it is not predicted.
void SampleBox(const Rect& r, float floor_z, float top_z, const CompletionParams& params,
               Samples* out) {
  const float h = top_z - floor_z;
  const float e0 = r.Extent(0), e1 = r.Extent(1);
  const float spacing = PartSpacing(2.0f * (e0 + e1) * h + e0 * e1, params);
  const Eigen::Vector3f up(0.0f, 0.0f, h);
  for (int k = 0; k < 2; ++k) {
    const int other = 1 - k;
    const Eigen::Vector3f along = Lift(r.Extent(other) * r.Axis(other), 0.0f);
    for (int side = 0; side < 2; ++side) {
      const float s = side == 0 ? r.lo[k] : r.hi[k];
      const float sign = side == 0 ? -1.0f : 1.0f;
      const Eigen::Vector2f origin = s * r.Axis(k) + r.lo[other] * r.Axis(other);
      SampleRect(Lift(origin, floor_z), along, up, Lift(sign * r.Axis(k), 0.0f), spacing, out);
    }
  }
  const Eigen::Vector2f corner = r.lo[0] * r.Axis(0) + r.lo[1] * r.Axis(1);
  SampleRect(Lift(corner, top_z), Lift(e0 * r.Axis(0), 0.0f), Lift(e1 * r.Axis(1), 0.0f),
             Eigen::Vector3f::UnitZ(), spacing, out);
}

float Cross(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return a.x() * b.y() - a.y() * b.x();
}

float PolygonArea(const std::vector<Eigen::Vector2f>& hull) {
  float area = 0.0f;
  for (std::size_t i = 0; i < hull.size(); ++i) area += Cross(hull[i], hull[(i + 1) % hull.size()]);
  return 0.5f * std::abs(area);
}

bool InsideConvex(const std::vector<Eigen::Vector2f>& hull, const Eigen::Vector2f& p) {
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f& a = hull[i];
    const Eigen::Vector2f& b = hull[(i + 1) % hull.size()];
    if (Cross(b - a, p - a) < 0.0f) return false;
  }
  return true;
}

// The footprint hull's walls and its top cap (again no bottom).
void SampleHull(const std::vector<Eigen::Vector2f>& hull, float floor_z, float top_z,
                const CompletionParams& params, Samples* out) {
  if (hull.size() < 3) return;
  const float h = top_z - floor_z;
  float perimeter = 0.0f;
  for (std::size_t i = 0; i < hull.size(); ++i)
    perimeter += (hull[(i + 1) % hull.size()] - hull[i]).norm();
  const float area = PolygonArea(hull);
  const float spacing = PartSpacing(perimeter * h + area, params);
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f edge = hull[(i + 1) % hull.size()] - hull[i];
    if (edge.squaredNorm() < 1e-12f) continue;
    const Eigen::Vector2f outward = -Perp(edge).normalized();  // counter-clockwise hull
    SampleRect(Lift(hull[i], floor_z), Lift(edge, 0.0f), Eigen::Vector3f(0.0f, 0.0f, h),
               Lift(outward, 0.0f), spacing, out);
  }
  Eigen::Vector2f lo = hull.front(), hi = hull.front();
  for (const Eigen::Vector2f& p : hull) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const int nx = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / spacing)));
  const int ny = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / spacing)));
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const Eigen::Vector2f p(lo.x() + (static_cast<float>(i) + 0.5f) * (hi.x() - lo.x()) / nx,
                              lo.y() + (static_cast<float>(j) + 0.5f) * (hi.y() - lo.y()) / ny);
      if (InsideConvex(hull, p)) out->Add(Lift(p, top_z), Eigen::Vector3f::UnitZ());
    }
  }
}

Eigen::Vector3f Reflect(const Eigen::Vector3f& v, const Eigen::Vector3f& normal) {
  return v - 2.0f * v.dot(normal) * normal;
}

struct MirrorOutcome {
  MirrorPlaneCheck check;
  std::vector<std::uint8_t> plausible;  // per point
  std::vector<Eigen::Vector3f> reflected;
};

// box (optional) counts reflections that leave the grown footprint rectangle.
MirrorOutcome EvaluateMirror(std::span<const Eigen::Vector3f> points, const KdTree& tree,
                             const Eigen::Vector2f& centre_xy, float angle_rad,
                             const SpaceQuery& space, const CompletionParams& params,
                             const Rect* box = nullptr) {
  MirrorOutcome out;
  out.check.angle_rad = angle_rad;
  if (points.empty()) return out;
  const Eigen::Vector3f n(std::cos(angle_rad), std::sin(angle_rad), 0.0f);
  const Eigen::Vector3f c = Lift(centre_xy, 0.0f);
  out.reflected.reserve(points.size());
  for (const Eigen::Vector3f& p : points) out.reflected.push_back(c + Reflect(p - c, n));
  std::vector<std::uint8_t> state(points.size(), kUnobserved);
  space(out.reflected, state);
  const float support2 = params.symmetry_support_m * params.symmetry_support_m;
  int plausible = 0, free = 0, fresh = 0;
  out.plausible.assign(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const bool near_observed = tree.NearestSquared(out.reflected[i]) <= support2;
    if (near_observed || state[i] != kObservedFree) {
      ++plausible;
      out.plausible[i] = 1;
      if (!near_observed) ++fresh;
    } else {
      ++free;
    }
    if (box != nullptr) {
      // A box-axis plane through the box centre maps the box onto itself exactly, so the margin
      // only absorbs rounding.
      constexpr float kBoxMargin = 0.01f;
      const Eigen::Vector2f xy = out.reflected[i].head<2>();
      for (int k = 0; k < 2; ++k) {
        const float along = xy.dot(box->Axis(k));
        if (along < box->lo[k] - kBoxMargin || along > box->hi[k] + kBoxMargin) {
          ++out.check.outside_box;
          break;
        }
      }
    }
  }
  const float n_points = static_cast<float>(points.size());
  out.check.plausible_share = static_cast<float>(plausible) / n_points;
  out.check.free_share = static_cast<float>(free) / n_points;
  out.check.new_points = fresh;
  out.check.accepted = out.check.plausible_share >= params.symmetry_min_plausible &&
                       out.check.free_share < params.symmetry_max_free;
  return out;
}

// Ranks planes by the unseen surface they explain. Reflections leaving the grown box count
// against it (a plane a few degrees off the true one explains as much but turns the object
// out of its box), and free-space contradictions ten times.
float MirrorRank(const MirrorPlaneCheck& c, int n_points) {
  constexpr float kFreePenalty = 10.0f;
  return static_cast<float>(c.new_points - c.outside_box) /
             static_cast<float>(std::max(1, n_points)) -
         kFreePenalty * c.free_share;
}

}  // namespace

std::vector<int> FarthestPointSample(std::span<const Eigen::Vector3f> points, int count,
                                     std::uint64_t seed) {
  const int n = static_cast<int>(points.size());
  std::vector<int> out;
  if (n == 0 || count <= 0) return out;
  if (count >= n) {
    out.resize(static_cast<std::size_t>(n));
    std::iota(out.begin(), out.end(), 0);
    return out;
  }
  SplitMix64 rng{seed};
  // Farthest-point sampling costs O(n · count); beyond 16 candidates per sample a seeded uniform
  // subset is thinned first (the spread barely changes, the cost stays bounded).
  std::vector<int> pool(static_cast<std::size_t>(n));
  std::iota(pool.begin(), pool.end(), 0);
  const int pool_limit = 16 * count;
  if (n > pool_limit) {
    for (int i = 0; i < pool_limit; ++i) {
      const int j = i + static_cast<int>(rng.Next() % static_cast<std::uint64_t>(n - i));
      std::swap(pool[static_cast<std::size_t>(i)], pool[static_cast<std::size_t>(j)]);
    }
    pool.resize(static_cast<std::size_t>(pool_limit));
    std::sort(pool.begin(), pool.end());
  }
  // The pool's coordinates in three contiguous arrays, so the distance update vectorises; the sum
  // runs in (p - c).squaredNorm()'s order, so the picks do not change. Distances are >= 0 (or
  // +inf), whose bit patterns order as int32, so the running maximum is an integer one, kept per
  // block of 64; the pick is the first point of the first block holding it (ties: lower index).
  const std::size_t m = pool.size();
  std::vector<float> xs(m), ys(m), zs(m);
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Vector3f& p = points[static_cast<std::size_t>(pool[i])];
    xs[i] = p.x();
    ys[i] = p.y();
    zs[i] = p.z();
  }
  constexpr std::size_t kBlock = 64;
  std::vector<float> dist(m, kInf);
  std::size_t current = static_cast<std::size_t>(rng.Next() % m);
  out.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    out.push_back(pool[current]);
    const float cx = xs[current], cy = ys[current], cz = zs[current];
    std::int32_t best = -1;
    std::size_t best_block = 0;
    for (std::size_t begin = 0; begin < m; begin += kBlock) {
      const std::size_t end = std::min(m, begin + kBlock);
      std::int32_t block_max = -1;
      for (std::size_t i = begin; i < end; ++i) {
        const float dx = xs[i] - cx, dy = ys[i] - cy, dz = zs[i] - cz;
        const float d = std::min(dist[i], dx * dx + (dy * dy + dz * dz));
        dist[i] = d;
        block_max = std::max(block_max, std::bit_cast<std::int32_t>(d));
      }
      if (block_max > best) {
        best = block_max;
        best_block = begin;
      }
    }
    std::size_t next = best_block;
    while (std::bit_cast<std::int32_t>(dist[next]) != best) ++next;
    current = next;
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<float> NearestDistances(std::span<const Eigen::Vector3f> reference,
                                    std::span<const Eigen::Vector3f> queries) {
  const KdTree tree(reference);
  std::vector<float> out(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i)
    out[i] = std::sqrt(tree.NearestSquared(queries[i]));
  return out;
}

std::vector<Eigen::Vector2f> ConvexHull2d(std::vector<Eigen::Vector2f> points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  std::vector<Eigen::Vector2f> hull(2 * points.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {  // lower chain
    while (k >= 2 && Cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0.0f) --k;
    hull[k++] = points[i];
  }
  for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && Cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0.0f) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  return hull;
}

MirrorPlaneCheck CheckMirrorPlane(std::span<const Eigen::Vector3f> points,
                                  const Eigen::Vector2f& centre_xy, float angle_rad,
                                  const SpaceQuery& space, const CompletionParams& params) {
  const KdTree tree(points);
  return EvaluateMirror(points, tree, centre_xy, angle_rad, space, params).check;
}

CompletionResult CompleteObject(std::span<const Eigen::Vector3f> points,
                                std::span<const Eigen::Vector3f> normals, float floor_z_m,
                                const SpaceQuery& space, const CompletionParams& params,
                                std::uint64_t seed) {
  CompletionResult result;
  if (points.empty()) return result;
  const bool have_normals = normals.size() == points.size();

  // P: N observed points, spread evenly over the surface.
  const std::vector<int> picked = FarthestPointSample(points, params.sample_count, seed);
  std::vector<Eigen::Vector3f> p_normals;
  result.observed.reserve(picked.size());
  for (const int i : picked) {
    result.observed.push_back(points[static_cast<std::size_t>(i)]);
    p_normals.push_back(have_normals ? normals[static_cast<std::size_t>(i)]
                                     : Eigen::Vector3f::Zero());
  }
  const std::vector<Eigen::Vector3f>& P = result.observed;
  const KdTree tree(P);

  float top_z = -kInf;
  for (const Eigen::Vector3f& p : points) top_z = std::max(top_z, p.z());
  top_z = std::max(top_z, floor_z_m + params.surface_spacing_m);

  std::vector<Eigen::Vector2f> footprint;
  footprint.reserve(P.size());
  for (const Eigen::Vector3f& p : P) footprint.push_back(p.head<2>());
  const std::vector<Eigen::Vector2f> hull = ConvexHull2d(footprint);
  Rect rect = FitFootprint(footprint, hull, params.box_fit);
  if (params.box_grow) GrowBox(&rect, floor_z_m, top_z, space, params);
  result.box_axis0 = rect.axis0;
  result.box_centre = Lift(rect.Centre(), 0.5f * (floor_z_m + top_z));
  result.box_half_extent =
      Eigen::Vector3f(rect.Extent(0), rect.Extent(1), top_z - floor_z_m) * 0.5f;

  Samples raw;
  if (params.use_box) {
    SampleBox(rect, floor_z_m, top_z, params, &raw);
    result.used_box = true;
  }

  // Mirror planes through the grown box centre; the angle grid starts at the box axis so both box
  // axes (the likeliest symmetry planes) are tried exactly.
  std::vector<Eigen::Vector2f> hull_input = footprint;
  if (params.use_symmetry && params.symmetry_angles > 0) {
    const float axis_angle = std::atan2(rect.axis0.y(), rect.axis0.x());
    MirrorOutcome best;
    float best_rank = -kInf;
    bool have = false;
    for (int k = 0; k < params.symmetry_angles; ++k) {
      const float a =
          axis_angle + kPi * static_cast<float>(k) / static_cast<float>(params.symmetry_angles);
      MirrorOutcome o = EvaluateMirror(P, tree, rect.Centre(), a, space, params, &rect);
      // Accepted planes first, then by rank; the first of equals wins (deterministic).
      const float rank = MirrorRank(o.check, static_cast<int>(P.size()));
      const bool better = !have || (o.check.accepted && !best.check.accepted) ||
                          (o.check.accepted == best.check.accepted && rank > best_rank);
      if (better) {
        best = std::move(o);
        best_rank = rank;
        have = true;
      }
    }
    result.symmetry = best.check;
    if (best.check.accepted) {
      result.used_symmetry = true;
      const Eigen::Vector3f n(std::cos(best.check.angle_rad), std::sin(best.check.angle_rad), 0.0f);
      for (std::size_t i = 0; i < P.size(); ++i) {
        if (!best.plausible[i]) continue;
        raw.Add(best.reflected[i], Reflect(p_normals[i], n));
        hull_input.push_back(best.reflected[i].head<2>());
      }
    }
  }

  if (params.use_hull) {
    const std::vector<Eigen::Vector2f> full_hull =
        result.used_symmetry ? ConvexHull2d(hull_input) : hull;
    const std::size_t before = raw.points.size();
    SampleHull(full_hull, floor_z_m, top_z, params, &raw);
    result.used_hull = raw.points.size() > before;
  }

  // Predicted points in observed free space are not part of the object.
  Samples kept;
  if (!raw.points.empty()) {
    std::vector<std::uint8_t> state(raw.points.size(), kUnobserved);
    space(raw.points, state);
    for (std::size_t i = 0; i < raw.points.size(); ++i) {
      if (state[i] == kObservedFree) {
        ++result.dropped_free;
        continue;
      }
      kept.Add(raw.points[i], raw.normals[i]);
    }
  }
  const std::vector<int> chosen =
      FarthestPointSample(kept.points, params.max_predicted, seed ^ 0x5A17C0DEull);
  for (const int i : chosen) {
    result.predicted.push_back(kept.points[static_cast<std::size_t>(i)]);
    result.normals.push_back(kept.normals[static_cast<std::size_t>(i)]);
  }

  // G eq. 1 and its normalisation.
  const std::size_t m = result.predicted.size();
  result.distance_m.resize(m);
  result.score.assign(m, 0.0f);
  int missing = 0;
  for (std::size_t i = 0; i < m; ++i) {
    result.distance_m[i] = std::sqrt(tree.NearestSquared(result.predicted[i]));
    result.max_distance_m = std::max(result.max_distance_m, result.distance_m[i]);
    if (result.distance_m[i] > params.missing_distance_m) ++missing;
  }
  if (m == 0) return result;
  double sum = 0.0;
  if (result.max_distance_m > 0.0f) {
    for (std::size_t i = 0; i < m; ++i) {
      result.score[i] = result.distance_m[i] / result.max_distance_m;
      sum += result.score[i];
    }
  }
  result.mean_score = static_cast<float>(sum / static_cast<double>(m));
  result.missing_share = static_cast<float>(missing) / static_cast<float>(m);
  result.incomplete =
      result.mean_score >= params.tau && result.max_distance_m >= params.min_max_distance_m;
  result.incompleteness = result.incomplete ? result.mean_score : 0.0f;
  return result;
}

}  // namespace voxplan::taskflow
