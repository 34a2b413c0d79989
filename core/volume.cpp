#include "core/volume.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace voxplan {

TsdfVolume::TsdfVolume(VolumeParams params) : params_(params) {
  if (!(std::isfinite(params.voxel_size_m) && params.voxel_size_m > 0.0f))
    throw std::invalid_argument("voxel size must be positive, got " +
                                std::to_string(params.voxel_size_m));
  if (!(std::isfinite(params.trunc_m) && params.trunc_m >= params.voxel_size_m))
    throw std::invalid_argument("truncation must be at least one voxel, got " +
                                std::to_string(params.trunc_m) + " m");
}

TsdfBlock& TsdfVolume::FindOrAllocate(BlockIndex b, bool* created) {
  const uint32_t found = map_.Find(b);
  if (created) *created = found == BlockMap::kNoSlot;
  if (found != BlockMap::kNoSlot) return pool_[found];
  const uint32_t slot = pool_.Allocate();
  map_.Insert(b, slot);
  return pool_[slot];
}

bool TsdfVolume::EraseBlock(BlockIndex b) {
  const uint32_t s = map_.Find(b);
  if (s == BlockMap::kNoSlot) return false;
  map_.Erase(b);
  pool_.Release(s);
  return true;
}

void TsdfVolume::Clear() {
  map_.Clear();
  pool_.Clear();
}

size_t TsdfVolume::MemoryBytes() const {
  return pool_.capacity_bytes() + map_.size() * 2 * (sizeof(uint64_t) + sizeof(uint32_t));
}

std::vector<BlockIndex> TsdfVolume::SortedBlockIndices() const {
  std::vector<BlockIndex> out;
  out.reserve(map_.size());
  for (const auto& [b, s] : map_.Sorted()) out.push_back(b);
  return out;
}

}  // namespace voxplan
