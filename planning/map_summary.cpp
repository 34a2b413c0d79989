#include "planning/map_summary.h"

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <utility>

#include "core/block.h"

namespace voxplan {

ColumnRegion::ColumnRegion(const std::vector<Eigen::Vector2i>& columns, int z_begin, int z_end)
    : z_begin_(z_begin), z_end_(std::max(z_begin, z_end)) {
  std::map<std::pair<int32_t, int32_t>, uint64_t> masks;  // (by, bx) -> columns
  for (const Eigen::Vector2i& c : columns) {
    const int32_t bx = c.x() >> kBlockShift, by = c.y() >> kBlockShift;
    masks[{by, bx}] |= uint64_t(1) << ((c.x() & kBlockMask) + kBlockSide * (c.y() & kBlockMask));
  }
  size_t n = 0;
  for (const auto& [key, mask] : masks) {
    blocks_.push_back({key.second, key.first, mask});
    n += size_t(std::popcount(mask));
  }
  voxels_ = n * size_t(z_end_ - z_begin_);
}

size_t ColumnRegion::CountUnobserved(const PlanningMap& map) const {
  if (z_end_ <= z_begin_) return 0;
  const int bz0 = z_begin_ >> kBlockShift, bz1 = (z_end_ - 1) >> kBlockShift;
  size_t observed = 0;
  for (const BlockColumn& b : blocks_)
    for (int bz = bz0; bz <= bz1; ++bz) {
      const PlanningBlock* pb = map.FindBlock({b.bx, b.by, bz});
      if (!pb) continue;  // unallocated: all unobserved
      const int z0 = std::max(z_begin_ - bz * kBlockSide, 0);
      const int z1 = std::min(z_end_ - bz * kBlockSide, kBlockSide);
      for (int z = z0; z < z1; ++z)  // BlockMask word z holds the x-y slice at local z
        observed +=
            size_t(std::popcount((pb->free[size_t(z)] | pb->occupied[size_t(z)]) & b.columns));
    }
  return voxels_ - observed;
}

double MeanSurfaceUncertainty(const PlanningMap& map) {
  std::vector<uint32_t> by_weight(size_t(std::numeric_limits<uint16_t>::max()) + 1, 0);
  size_t n = 0;
  map.volume().ForEachBlock([&](BlockIndex b, const TsdfBlock& tb) {
    const PlanningBlock* pb = map.FindBlock(b);
    if (!pb) return;
    ForEachBit(pb->surface, [&](int i) {
      ++by_weight[tb.weight[i]];
      ++n;
    });
  });
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (size_t w = 0; w < by_weight.size(); ++w) {
    if (by_weight[w] == 0) continue;
    const float weight = DecodeWeight(uint16_t(w));
    sum += double(by_weight[w]) * (weight > 1.f ? double(1.0f / weight) : 1.0);
  }
  return sum / double(n);
}

}  // namespace voxplan
