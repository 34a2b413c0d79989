#include "planning/geodesic.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "core/parallel.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace voxplan {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// One grid move (dx, dy) of length `cost` cells; `vias` are the other cells its straight
// segment crosses, which must be traversable too (no corner cutting).
struct Move {
  int dx, dy;
  float cost;
  int num_vias;
  int via_dx[2], via_dy[2];
};

std::vector<Move> MovesFor(GridConnectivity connectivity) {
  std::vector<Move> moves = {{1, 0, 1.0f, 0, {}, {}},
                             {-1, 0, 1.0f, 0, {}, {}},
                             {0, 1, 1.0f, 0, {}, {}},
                             {0, -1, 1.0f, 0, {}, {}}};
  const float diag = std::sqrt(2.0f), knight = std::sqrt(5.0f);
  for (int sy : {-1, 1})
    for (int sx : {-1, 1}) moves.push_back({sx, sy, diag, 2, {sx, 0}, {0, sy}});
  if (connectivity == GridConnectivity::k16)
    for (int sy : {-1, 1})
      for (int sx : {-1, 1}) {
        // (2, 1) crosses (1, 0) and (1, 1); (1, 2) crosses (0, 1) and (1, 1).
        moves.push_back({2 * sx, sy, knight, 2, {sx, sx}, {0, sy}});
        moves.push_back({sx, 2 * sy, knight, 2, {0, sx}, {sy, sy}});
      }
  return moves;
}

// Felzenszwalb-Huttenlocher lower envelope of parabolas along one row: out[q] =
// min_p (q - p)^2 + f[p] over the sites p with f[p] finite. v, z are scratch (n and n + 1).
void EnvelopeRow(const int* dy, int far, int n, float* out, std::vector<int>& v,
                 std::vector<double>& z) {
  const auto f = [&](int p) { return double(dy[p]) * double(dy[p]); };
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (dy[q] >= far) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -std::numeric_limits<double>::infinity();
      z[1] = std::numeric_limits<double>::infinity();
      continue;
    }
    double s;
    while ((s = ((f(q) + double(q) * q) - (f(v[k]) + double(v[k]) * v[k])) / (2.0 * (q - v[k]))) <=
           z[k])
      --k;  // z[0] = -inf stops this
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  if (k < 0) {
    std::fill_n(out, n, kInf);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    out[q] = float(double(q - v[j]) * double(q - v[j]) + f(v[j]));
  }
}

}  // namespace

Image<float> SquaredDistanceTransform(const Image<uint8_t>& sites) {
  const int w = sites.width, h = sites.height;
  Image<float> out(w, h, kInf);
  if (w == 0 || h == 0) return out;
  // Pass 1: distance to the nearest site in the same column, by a down and an up sweep over
  // whole rows (memory order).
  const int far = h + 1;
  std::vector<int> dy(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y) {
    const uint8_t* s = &sites.data[size_t(y) * w];
    int* row = &dy[size_t(y) * w];
    const int* above = y > 0 ? row - w : nullptr;
    for (int x = 0; x < w; ++x) row[x] = s[x] ? 0 : (above ? std::min(above[x] + 1, far) : far);
  }
  for (int y = h - 2; y >= 0; --y) {
    int* row = &dy[size_t(y) * w];
    const int* below = row + w;
    for (int x = 0; x < w; ++x) row[x] = std::min(row[x], below[x] + 1);
  }
  // Pass 2: exact 1-D transform of the squared column distances along each row.
  ParallelFor(size_t(h), 16, [&](size_t begin, size_t end) {
    std::vector<int> v(static_cast<size_t>(w));
    std::vector<double> z(size_t(w) + 1);
    for (size_t y = begin; y < end; ++y) EnvelopeRow(&dy[y * w], far, w, &out.data[y * w], v, z);
  });
  return out;
}

Image<float> ComputeClearance(const FloorMap& map, bool unknown_is_obstacle) {
  const int w = map.width(), h = map.height();
  // With unknown as obstacle the world beyond the raster is too: one ring of sites around it.
  const int pad = unknown_is_obstacle ? 1 : 0;
  Image<uint8_t> sites(w + 2 * pad, h + 2 * pad, uint8_t(pad));
  for (int iy = 0; iy < h; ++iy)
    for (int ix = 0; ix < w; ++ix) {
      const FloorCell c = map.At(ix, iy);
      sites.at(ix + pad, iy + pad) =
          c == FloorCell::kObstacle || (unknown_is_obstacle && c == FloorCell::kUnknown);
    }
  const Image<float> d2 = SquaredDistanceTransform(sites);
  Image<float> clearance(w, h);
  const float cell = map.cell_size_m();
  for (int iy = 0; iy < h; ++iy)
    for (int ix = 0; ix < w; ++ix)
      clearance.at(ix, iy) = std::sqrt(d2.at(ix + pad, iy + pad)) * cell;
  return clearance;
}

Image<uint8_t> TraversableCells(const FloorMap& map, const GeodesicParams& params) {
  const Image<float> clearance = ComputeClearance(map, params.clearance_from_unknown);
  Image<uint8_t> traversable(map.width(), map.height());
  for (size_t i = 0; i < traversable.data.size(); ++i) {
    const FloorCell c = map.cells()[i];
    const bool standable = IsFree(c) || (params.unknown_traversable && c == FloorCell::kUnknown);
    traversable.data[i] = standable && clearance.data[i] >= params.robot_radius_m;
  }
  return traversable;
}

float DistanceField::At(int ix, int iy) const {
  return geometry.Contains(ix, iy) ? distance_m.at(ix, iy) : kInf;
}

namespace {

// A move's bit in a cell's move mask. The bits come in groups of four whose targets are four
// consecutive cells of one row (rows -2 .. +2, starting at x - 1, x - 2, x - 1, x - 2 and x - 1),
// then the (2, -1) and (2, 1) knights, so the SSE path below reads each group with one load.
constexpr int kMaskGroups = 6;
constexpr int kMaskBits = 4 * kMaskGroups;
int MaskBit(int dx, int dy) {
  switch (dy) {
    case -2:
      return dx + 1;
    case -1:
      return dx == 2 ? 20 : 4 + dx + 2;
    case 0:
      return 8 + dx + 1;
    case 1:
      return dx == 2 ? 21 : 12 + dx + 2;
    default:
      return 16 + dx + 1;
  }
}

// Per cell, the bit of every move (MaskBit) that stays on traversable cells (its target and
// every cell it crosses); 0 on cells that are not traversable. One mask serves every field over
// the same raster, and spares each Dijkstra the corner checks of every move.
std::vector<uint32_t> MoveMasks(const Image<uint8_t>& traversable, GridConnectivity connectivity) {
  const int w = traversable.width, h = traversable.height;
  // A copy padded with two closed cells on every side, so no move needs a bounds check.
  constexpr int kPad = 2;
  const int pw = w + 2 * kPad;
  std::vector<uint8_t> open(size_t(pw) * size_t(h + 2 * kPad), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) open[size_t(y + kPad) * pw + x + kPad] = traversable.at(x, y) != 0;
  std::vector<uint32_t> masks(size_t(w) * size_t(h), 0);
  for (const Move& m : MovesFor(connectivity)) {
    const ptrdiff_t to = ptrdiff_t(m.dy) * pw + m.dx;
    // A move without vias checks its own target twice.
    const ptrdiff_t via0 = m.num_vias ? ptrdiff_t(m.via_dy[0]) * pw + m.via_dx[0] : to;
    const ptrdiff_t via1 = m.num_vias ? ptrdiff_t(m.via_dy[1]) * pw + m.via_dx[1] : to;
    const int bit = MaskBit(m.dx, m.dy);
    for (int y = 0; y < h; ++y) {
      const uint8_t* c = &open[size_t(y + kPad) * pw + kPad];
      uint32_t* out = &masks[size_t(y) * w];
      for (int x = 0; x < w; ++x)
        out[x] |= uint32_t(c[x] & c[x + to] & c[x + via0] & c[x + via1]) << bit;
    }
  }
  return masks;
}

// Dijkstra over the moves `masks` allows. Distances are in cells while it runs. Every move
// costs at least one cell, so the cells whose distance lies in [k, k + 1) are final once the
// buckets below k are done and can be settled in any order (Dial's buckets, exact here): no
// heap. Each distance is the least of its neighbours' plus the move, whatever the order, so the
// field does not depend on how it was computed (nor on the SSE path). Sequential, so
// deterministic.
DistanceField FieldOverMoves(const std::vector<uint32_t>& masks, const Image<uint8_t>& traversable,
                             const FloorGeometry& geometry, Eigen::Vector2i source_cell,
                             GridConnectivity connectivity) {
  assert(traversable.width == geometry.width && traversable.height == geometry.height);
  assert(masks.size() == traversable.data.size());
  DistanceField field;
  field.geometry = geometry;
  field.connectivity = connectivity;
  field.distance_m = Image<float>(geometry.width, geometry.height, kInf);
  if (!geometry.Contains(source_cell.x(), source_cell.y()) ||
      !traversable.at(source_cell.x(), source_cell.y())) {
    field.source_cell = {-1, -1};
    return field;
  }
  field.source_cell = source_cell;
  const ptrdiff_t w = geometry.width;
  std::array<ptrdiff_t, kMaskBits> offset{};
  std::array<float, kMaskBits> cost;
  cost.fill(kInf);  // no move: never an improvement
  for (const Move& m : MovesFor(connectivity)) {
    offset[size_t(MaskBit(m.dx, m.dy))] = ptrdiff_t(m.dy) * w + m.dx;
    cost[size_t(MaskBit(m.dx, m.dy))] = m.cost;
  }
  // The longest move (sqrt 5 < 3 cells) lands at most 3 buckets ahead: 4 buckets in a ring.
  constexpr uint32_t kRing = 4;
  std::array<std::vector<uint32_t>, kRing> buckets;
  std::vector<uint8_t> settled(masks.size(), 0);
  float* dist = field.distance_m.data.data();
  auto improve = [&](uint32_t i, int bit, float nd) {
    const size_t j = size_t(ptrdiff_t(i) + offset[size_t(bit)]);
    dist[j] = nd;
    buckets[uint32_t(nd) % kRing].push_back(uint32_t(j));
  };
#if defined(__SSE2__)
  // Cells at least this far from both ends of the raster read every group in the array.
  const size_t margin = size_t(2 * w + 2);
  __m128 group_cost[kMaskGroups];
  for (int g = 0; g < kMaskGroups; ++g) group_cost[g] = _mm_loadu_ps(&cost[size_t(4 * g)]);
#endif
  const uint32_t start = uint32_t(geometry.Linear(source_cell.x(), source_cell.y()));
  dist[start] = 0.0f;
  buckets[0].push_back(start);
  size_t pending = 1;
  for (uint32_t k = 0; pending > 0; ++k) {
    std::vector<uint32_t>& bucket = buckets[k % kRing];
    for (size_t t = 0; t < bucket.size(); ++t) {
      const uint32_t i = bucket[t];
      if (settled[i]) continue;  // settled through an earlier entry
      settled[i] = 1;
      const float d = dist[i];
#if defined(__SSE2__)
      if (i >= margin && i + margin < masks.size()) {
        // Which of 16 neighbours improve is hard to predict: compare them four at a time.
        const float* p = dist + i;
        const __m128 dv = _mm_set1_ps(d);
        const __m128 old[kMaskGroups] = {
            _mm_loadu_ps(p - 2 * w - 1), _mm_loadu_ps(p - w - 2),
            _mm_loadu_ps(p - 1),         _mm_loadu_ps(p + w - 2),
            _mm_loadu_ps(p + 2 * w - 1), _mm_set_ps(0.f, 0.f, p[w + 2], p[-w + 2])};
        uint32_t better = 0;  // bits of the moves that shorten their target's distance
        for (int g = 0; g < kMaskGroups; ++g) {
          const __m128 nd = _mm_add_ps(dv, group_cost[g]);
          better |= uint32_t(_mm_movemask_ps(_mm_cmplt_ps(nd, old[g]))) << (4 * g);
        }
        better &= masks[i];
        for (; better != 0; better &= better - 1) {
          const int bit = std::countr_zero(better);
          improve(i, bit, d + cost[size_t(bit)]);
          ++pending;
        }
        continue;
      }
#endif
      for (uint32_t m = masks[i]; m != 0; m &= m - 1) {
        const int bit = std::countr_zero(m);
        const float nd = d + cost[size_t(bit)];
        if (nd < dist[size_t(ptrdiff_t(i) + offset[size_t(bit)])]) {
          improve(i, bit, nd);
          ++pending;
        }
      }
    }
    pending -= bucket.size();
    bucket.clear();
  }
  const float cell = geometry.cell_size_m;
  for (float& d : field.distance_m.data) d *= cell;
  return field;
}

}  // namespace

DistanceField GeodesicField(const Image<uint8_t>& traversable, const FloorGeometry& geometry,
                            Eigen::Vector2i source_cell, GridConnectivity connectivity) {
  return FieldOverMoves(MoveMasks(traversable, connectivity), traversable, geometry, source_cell,
                        connectivity);
}

std::optional<Eigen::Vector2i> SnapToTraversable(const Image<uint8_t>& traversable,
                                                 const FloorGeometry& geometry,
                                                 const Eigen::Vector2f& p_W, float snap_radius_m) {
  const Eigen::Vector2i own = geometry.CellOf(p_W);
  if (geometry.Contains(own.x(), own.y()) && traversable.at(own.x(), own.y())) return own;
  if (!(snap_radius_m > 0.0f)) return std::nullopt;
  const int r = int(std::ceil(snap_radius_m / geometry.cell_size_m)) + 1;
  std::optional<Eigen::Vector2i> best;
  float best_d2 = snap_radius_m * snap_radius_m;
  for (int iy = std::max(own.y() - r, 0); iy <= std::min(own.y() + r, geometry.height - 1); ++iy)
    for (int ix = std::max(own.x() - r, 0); ix <= std::min(own.x() + r, geometry.width - 1); ++ix) {
      if (!traversable.at(ix, iy)) continue;
      const float d2 = (geometry.CellCenter(ix, iy) - p_W).squaredNorm();
      if (d2 < best_d2 || (!best && d2 == best_d2)) {
        best_d2 = d2;
        best = Eigen::Vector2i(ix, iy);
      }
    }
  return best;
}

Result<std::vector<Eigen::Vector2f>> ExtractPath(const DistanceField& field,
                                                 const Eigen::Vector2f& target_W) {
  Eigen::Vector2i cur = field.geometry.CellOf(target_W);
  if (!std::isfinite(field.At(cur.x(), cur.y())))
    return NotFound("geodesic path: the target is unreachable from the source");
  const std::vector<Move> moves = MovesFor(field.connectivity);
  const float cell = field.geometry.cell_size_m;
  std::vector<Eigen::Vector2i> cells = {cur};
  // Each step strictly lowers the distance, so a path visits at most every cell once.
  const size_t max_steps = size_t(field.geometry.width) * size_t(field.geometry.height);
  while (cur != field.source_cell) {
    const float here = field.At(cur.x(), cur.y());
    float best = kInf;
    Eigen::Vector2i next = cur;
    for (const Move& m : moves) {
      const float there = field.At(cur.x() + m.dx, cur.y() + m.dy);
      if (!(there < here)) continue;
      // Cells of this component are finite exactly when traversable, so the vias must be too.
      bool clear = true;
      for (int v = 0; v < m.num_vias; ++v)
        clear &= std::isfinite(field.At(cur.x() + m.via_dx[v], cur.y() + m.via_dy[v]));
      const float through = there + m.cost * cell;
      if (clear && through < best) {
        best = through;
        next = Eigen::Vector2i(cur.x() + m.dx, cur.y() + m.dy);
      }
    }
    if (next == cur || cells.size() > max_steps)
      return Status(StatusCode::kInternal, "geodesic path: the field has no descent");
    cur = next;
    cells.push_back(cur);
  }
  std::vector<Eigen::Vector2f> path;
  path.reserve(cells.size());
  for (auto it = cells.rbegin(); it != cells.rend(); ++it)
    path.push_back(field.geometry.CellCenter(it->x(), it->y()));
  return path;
}

void GeodesicCache::Clear() {
  synced_ = false;
  fields_.clear();
  traversable_ = {};
  moves_ = {};
}

void GeodesicCache::Sync(const FloorMap& map, const GeodesicParams& params) {
  if (synced_ && revision_ == map.revision() && params_ == params && geometry_ == map.geometry())
    return;
  fields_.clear();
  synced_ = true;
  revision_ = map.revision();
  params_ = params;
  geometry_ = map.geometry();
  traversable_ = TraversableCells(map, params);
  moves_ = MoveMasks(traversable_, params.connectivity);
}

GeodesicCache::Snapped GeodesicCache::Snap(const Eigen::Vector2f& p_W) const {
  Snapped s;
  s.cell = SnapToTraversable(traversable_, geometry_, p_W, params_.snap_radius_m);
  if (s.cell && *s.cell != geometry_.CellOf(p_W))
    s.offset_m = (geometry_.CellCenter(s.cell->x(), s.cell->y()) - p_W).norm();
  return s;
}

std::shared_ptr<const DistanceField> GeodesicCache::Field(const FloorMap& map,
                                                          const Eigen::Vector2f& source_W,
                                                          const GeodesicParams& params) {
  Sync(map, params);
  const Snapped s = Snap(source_W);
  if (!s.cell)
    return std::make_shared<const DistanceField>(
        FieldOverMoves(moves_, traversable_, geometry_, {-1, -1}, params.connectivity));
  auto& slot = fields_[Key(*s.cell)];
  if (!slot) {
    slot = std::make_shared<const DistanceField>(
        FieldOverMoves(moves_, traversable_, geometry_, *s.cell, params.connectivity));
    ++fields_computed_;
  }
  return slot;
}

Result<std::vector<Eigen::Vector2f>> GeodesicCache::Path(const FloorMap& map,
                                                         const Eigen::Vector2f& source_W,
                                                         const Eigen::Vector2f& target_W,
                                                         const GeodesicParams& params) {
  const std::shared_ptr<const DistanceField> field = Field(map, source_W, params);
  const Snapped target = Snap(target_W);
  if (!field->has_source() || !target.cell)
    return NotFound("geodesic path: the source or the target is not on a traversable cell");
  return ExtractPath(*field, geometry_.CellCenter(target.cell->x(), target.cell->y()));
}

void GeodesicCache::Prefetch(const FloorMap& map, std::span<const Eigen::Vector2f> sources_W,
                             const GeodesicParams& params) {
  Sync(map, params);
  std::vector<Eigen::Vector2i> missing;
  for (const Eigen::Vector2f& p_W : sources_W) {
    const Snapped s = Snap(p_W);
    if (s.cell && !fields_.count(Key(*s.cell))) missing.push_back(*s.cell);
  }
  std::sort(missing.begin(), missing.end(),
            [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) { return Key(a) < Key(b); });
  missing.erase(std::unique(missing.begin(), missing.end()), missing.end());
  // One field per task: each is a sequential Dijkstra, so the results do not depend on threads.
  std::vector<std::shared_ptr<const DistanceField>> computed(missing.size());
  ParallelFor(missing.size(), 1, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k)
      computed[k] = std::make_shared<const DistanceField>(
          FieldOverMoves(moves_, traversable_, geometry_, missing[k], params.connectivity));
  });
  for (size_t k = 0; k < missing.size(); ++k) fields_[Key(missing[k])] = computed[k];
  fields_computed_ += missing.size();
}

Eigen::MatrixXf GeodesicCache::DistanceMatrix(const FloorMap& map,
                                              std::span<const Eigen::Vector2f> points_W,
                                              const GeodesicParams& params) {
  Prefetch(map, points_W, params);
  const size_t n = points_W.size();
  std::vector<Snapped> snapped(n);
  for (size_t i = 0; i < n; ++i) snapped[i] = Snap(points_W[i]);

  Eigen::MatrixXf distances = Eigen::MatrixXf::Constant(Eigen::Index(n), Eigen::Index(n), kInf);
  for (size_t i = 0; i < n; ++i) {
    distances(Eigen::Index(i), Eigen::Index(i)) = 0.0f;
    if (!snapped[i].cell) continue;
    const DistanceField& field = *fields_.at(Key(*snapped[i].cell));
    for (size_t j = 0; j < n; ++j) {
      if (j == i || !snapped[j].cell) continue;
      const Eigen::Vector2i c = *snapped[j].cell;
      distances(Eigen::Index(i), Eigen::Index(j)) =
          field.distance_m.at(c.x(), c.y()) + snapped[i].offset_m + snapped[j].offset_m;
    }
  }
  return distances;
}

}  // namespace voxplan
