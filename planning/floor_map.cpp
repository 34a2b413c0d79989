#include "planning/floor_map.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/parallel.h"
#include "core/volume.h"

namespace voxplan {
namespace {

constexpr int kColumnsPerBlock = kBlockSide * kBlockSide;
// Voxel centres this close to a band edge (in voxels) count as inside, so a band edge placed
// on a centre does not hinge on float rounding.
constexpr double kBandEdgeSlackVox = 1e-4;

uint64_t NextRevision() {
  static std::atomic<uint64_t> last{0};
  return last.fetch_add(1, std::memory_order_relaxed) + 1;
}

}  // namespace

FloorMap::FloorMap(float voxel_size_m, const FloorMapParams& params)
    : voxel_size_m_(voxel_size_m), params_(params) {
  if (!(std::isfinite(voxel_size_m) && voxel_size_m > 0.0f))
    throw std::invalid_argument("floor map: voxel size must be positive");
  const int k = params.cell_voxels;
  if (k <= 0 || kBlockSide % k != 0)
    throw std::invalid_argument("floor map: cell_voxels must divide " + std::to_string(kBlockSide) +
                                ", got " + std::to_string(k));
  if (!(params.min_free_fraction > 0.0f && params.min_free_fraction <= 1.0f))
    throw std::invalid_argument("floor map: min_free_fraction must lie in (0, 1]");
  // Voxel g has its centre at (g + 0.5) * voxel_size_m.
  const double lo = double(params.floor_z_m + params.band_min_m) / voxel_size_m - 0.5;
  const double hi = double(params.floor_z_m + params.band_max_m) / voxel_size_m - 0.5;
  if (!(std::isfinite(lo) && std::isfinite(hi)))
    throw std::invalid_argument("floor map: band limits must be finite");
  band_z0_ = int(std::ceil(lo - kBandEdgeSlackVox));
  band_z1_ = int(std::floor(hi + kBandEdgeSlackVox));
  if (band_z1_ < band_z0_)
    throw std::invalid_argument("floor map: the height band holds no voxel centre");
  const double band_voxels = double(k) * k * (band_z1_ - band_z0_ + 1);
  required_free_ =
      std::max(1, int(std::ceil(params.min_free_fraction * band_voxels - kBandEdgeSlackVox)));
  geometry_.cell_size_m = voxel_size_m * float(k);
}

size_t FloorMap::Count(FloorCell c) const {
  return size_t(std::count(cells_.begin(), cells_.end(), c));
}

Status FloorMap::Update(const TsdfVolume& volume, std::span<const BlockIndex> touched_blocks) {
  if (std::abs(volume.voxel_size_m() - voxel_size_m_) > 1e-6f * voxel_size_m_)
    return InvalidArgument("floor map: volume voxel size " + std::to_string(volume.voxel_size_m()) +
                           " m differs from the map's " + std::to_string(voxel_size_m_) + " m");
  const int bz0 = band_z0_ >> kBlockShift, bz1 = band_z1_ >> kBlockShift;
  std::vector<Eigen::Vector2i> columns;  // block columns (bx, by) that reach into the band
  columns.reserve(touched_blocks.size());
  for (const BlockIndex& b : touched_blocks)
    if (b.z >= bz0 && b.z <= bz1) columns.emplace_back(b.x, b.y);
  const auto row_major = [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) {
    return a.y() != b.y() ? a.y() < b.y() : a.x() < b.x();
  };
  std::sort(columns.begin(), columns.end(), row_major);
  columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
  if (columns.empty()) return Status::Ok();

  bool changed = GrowToCover(columns);
  const float trunc_vox = volume.trunc_m() / volume.voxel_size_m();
  // Block columns own disjoint cells, so the tasks never share a write.
  std::vector<uint8_t> column_changed(columns.size(), 0);
  ParallelFor(columns.size(), 4, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      column_changed[i] = ProjectBlockColumn(volume, columns[i], trunc_vox);
  });
  for (uint8_t c : column_changed) changed |= c != 0;
  changed |= UpdateFrontier(columns);
  if (changed) revision_ = NextRevision();
  return Status::Ok();
}

Status FloorMap::Rebuild(const TsdfVolume& volume) {
  geometry_ = FloorGeometry{.cell_size_m = geometry_.cell_size_m};
  cells_.clear();
  const std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
  VOXPLAN_RETURN_IF_ERROR(Update(volume, blocks));
  ApplyMarks({marked_.begin(), marked_.end()});  // also those in columns without blocks
  revision_ = NextRevision();  // the extent may have shrunk, which Update never reports
  return Status::Ok();
}

bool FloorMap::MarkObstacles(std::span<const Eigen::Vector2f> points_W) {
  std::vector<std::pair<int, int>> added;
  for (const Eigen::Vector2f& p : points_W) {
    if (!p.allFinite()) continue;
    const std::pair<int, int> c = GlobalCell(p);
    if (marked_.insert(c).second) added.push_back(c);
  }
  if (added.empty()) return false;
  const bool changed = ApplyMarks(added);
  if (changed) revision_ = NextRevision();
  return changed;
}

std::pair<int, int> FloorMap::GlobalCell(const Eigen::Vector2f& p_W) const {
  return {FloorToInt(p_W.x() / geometry_.cell_size_m), FloorToInt(p_W.y() / geometry_.cell_size_m)};
}

std::vector<Eigen::Vector2f> FloorMap::MarkContacts(std::span<const Eigen::Vector2f> contacts_W) {
  constexpr int kSeenCells = 2;
  const float cell_m = geometry_.cell_size_m;
  std::vector<Eigen::Vector2f> mark;
  for (const Eigen::Vector2f& p : contacts_W) {
    if (!p.allFinite()) continue;
    bool beside_seen = false;
    for (int dy = -kSeenCells; dy <= kSeenCells && !beside_seen; ++dy)
      for (int dx = -kSeenCells; dx <= kSeenCells && !beside_seen; ++dx) {
        const Eigen::Vector2f q = p + cell_m * Eigen::Vector2f(float(dx), float(dy));
        beside_seen = AtPoint(q) == FloorCell::kObstacle && !marked_.count(GlobalCell(q));
      }
    if (!beside_seen || !contacts_beside_seen_.insert(GlobalCell(p)).second) mark.push_back(p);
  }
  if (mark.empty() || !MarkObstacles(mark)) return {};
  return mark;
}

bool FloorMap::ApplyMarks(const std::vector<std::pair<int, int>>& cells) {
  if (cells.empty()) return false;
  const int cpb = kBlockSide / params_.cell_voxels;
  const auto floor_div = [cpb](int v) { return v >= 0 ? v / cpb : -((-v + cpb - 1) / cpb); };
  std::vector<Eigen::Vector2i> columns;
  for (const auto& [x, y] : cells) columns.emplace_back(floor_div(x), floor_div(y));
  std::sort(columns.begin(), columns.end(), [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) {
    return a.y() != b.y() ? a.y() < b.y() : a.x() < b.x();
  });
  columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
  bool changed = GrowToCover(columns);
  for (const auto& [x, y] : cells) {
    FloorCell& cell =
        cells_[geometry_.Linear(x - geometry_.origin_cell.x(), y - geometry_.origin_cell.y())];
    changed |= cell != FloorCell::kObstacle;
    cell = FloorCell::kObstacle;
  }
  return UpdateFrontier(columns) || changed;
}

bool FloorMap::GrowToCover(const std::vector<Eigen::Vector2i>& block_columns) {
  const int cpb = kBlockSide / params_.cell_voxels;
  Eigen::Vector2i lo = block_columns.front() * cpb, hi = lo;
  for (const Eigen::Vector2i& c : block_columns) {
    lo = lo.cwiseMin(c * cpb);
    hi = hi.cwiseMax(c * cpb + Eigen::Vector2i::Constant(cpb - 1));
  }
  const FloorGeometry old = geometry_;
  if (old.width > 0) {
    lo = lo.cwiseMin(old.origin_cell);
    hi = hi.cwiseMax(old.origin_cell + Eigen::Vector2i(old.width - 1, old.height - 1));
  }
  FloorGeometry grown = old;
  grown.origin_cell = lo;
  grown.width = hi.x() - lo.x() + 1;
  grown.height = hi.y() - lo.y() + 1;
  if (grown == old) return false;
  std::vector<FloorCell> cells(size_t(grown.width) * size_t(grown.height), FloorCell::kUnknown);
  const Eigen::Vector2i shift = old.origin_cell - grown.origin_cell;
  for (int iy = 0; iy < old.height; ++iy)
    std::copy_n(cells_.begin() + ptrdiff_t(old.Linear(0, iy)), old.width,
                cells.begin() + ptrdiff_t(grown.Linear(shift.x(), iy + shift.y())));
  cells_ = std::move(cells);
  geometry_ = grown;
  return true;
}

bool FloorMap::ProjectBlockColumn(const TsdfVolume& volume, Eigen::Vector2i block_column,
                                  float trunc_vox) {
  // Per voxel column of the block column (index x + 8 y): observed-free count and occupancy.
  // Both 16-bit so the loop over a layer vectorises.
  std::array<uint16_t, kColumnsPerBlock> free_count{};
  std::array<uint16_t, kColumnsPerBlock> occupied{};
  const VoxelStateParams state_params = params_.voxel_state;
  const int bz0 = band_z0_ >> kBlockShift, bz1 = band_z1_ >> kBlockShift;
  for (int bz = bz0; bz <= bz1; ++bz) {
    const TsdfBlock* block = volume.FindBlock({block_column.x(), block_column.y(), bz});
    if (block == nullptr) continue;  // unallocated: unobserved
    const int lz0 = std::max(band_z0_ - bz * kBlockSide, 0);
    const int lz1 = std::min(band_z1_ - bz * kBlockSide, kBlockSide - 1);
    for (int lz = lz0; lz <= lz1; ++lz) {
      const int base = LinearIndex(0, 0, lz);
      for (int c = 0; c < kColumnsPerBlock; ++c) {
        const VoxelState s =
            ClassifyVoxel(block->tsdf[base + c], block->weight[base + c], trunc_vox, state_params);
        free_count[c] += s == VoxelState::kFree;
        occupied[c] += s == VoxelState::kOccupied;
      }
    }
  }
  const int k = params_.cell_voxels, cpb = kBlockSide / k;
  const Eigen::Vector2i first = block_column * cpb - geometry_.origin_cell;
  bool changed = false;
  for (int cy = 0; cy < cpb; ++cy)
    for (int cx = 0; cx < cpb; ++cx) {
      int free = 0;
      bool occ = false;
      for (int vy = cy * k; vy < (cy + 1) * k; ++vy)
        for (int vx = cx * k; vx < (cx + 1) * k; ++vx) {
          free += free_count[vx + kBlockSide * vy];
          occ |= occupied[vx + kBlockSide * vy] != 0;
        }
      const Eigen::Vector2i global = block_column * cpb + Eigen::Vector2i(cx, cy);
      const bool marked = !marked_.empty() && marked_.count({global.x(), global.y()}) != 0;
      const FloorCell cell = occ || marked            ? FloorCell::kObstacle
                             : free >= required_free_ ? FloorCell::kFree
                                                      : FloorCell::kUnknown;
      FloorCell& stored = cells_[geometry_.Linear(first.x() + cx, first.y() + cy)];
      // Frontier is settled afterwards, once the neighbours are known.
      const FloorCell old = stored == FloorCell::kFrontier ? FloorCell::kFree : stored;
      if (old != cell) {
        stored = cell;
        changed = true;
      }
    }
  return changed;
}

bool FloorMap::UpdateFrontier(const std::vector<Eigen::Vector2i>& block_columns) {
  // A cell's frontier flag depends on its 8 neighbours, so the ring around each recomputed
  // block column is revisited too. Sequential: the rings overlap and the work is small.
  const int cpb = kBlockSide / params_.cell_voxels;
  bool changed = false;
  for (const Eigen::Vector2i& bc : block_columns) {
    const Eigen::Vector2i first = bc * cpb - geometry_.origin_cell;
    const int x0 = std::max(first.x() - 1, 0), x1 = std::min(first.x() + cpb, width() - 1);
    const int y0 = std::max(first.y() - 1, 0), y1 = std::min(first.y() + cpb, height() - 1);
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix) {
        FloorCell& cell = cells_[geometry_.Linear(ix, iy)];
        if (!IsFree(cell)) continue;
        bool next_to_unknown = false;
        for (int dy = -1; dy <= 1 && !next_to_unknown; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (At(ix + dx, iy + dy) == FloorCell::kUnknown) {
              next_to_unknown = true;
              break;
            }
        const FloorCell want = next_to_unknown ? FloorCell::kFrontier : FloorCell::kFree;
        if (cell != want) {
          cell = want;
          changed = true;
        }
      }
  }
  return changed;
}

FloorMap ProjectFloor(const TsdfVolume& volume, const FloorMapParams& params) {
  FloorMap map(volume.voxel_size_m(), params);
  const Status status = map.Rebuild(volume);  // cannot fail: the voxel sizes agree
  assert(status.ok());
  (void)status;
  return map;
}

Image<uint8_t> FloorImage(const FloorMap& map) {
  Image<uint8_t> image(map.width(), map.height());
  for (size_t i = 0; i < image.data.size(); ++i) {
    switch (map.cells()[i]) {
      case FloorCell::kUnknown:
        image.data[i] = kFloorPixelUnknown;
        break;
      case FloorCell::kFree:
        image.data[i] = kFloorPixelFree;
        break;
      case FloorCell::kFrontier:
        image.data[i] = kFloorPixelFrontier;
        break;
      case FloorCell::kObstacle:
        image.data[i] = kFloorPixelObstacle;
        break;
    }
  }
  return image;
}

}  // namespace voxplan
