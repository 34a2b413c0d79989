#include "core/volume.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/bounds.h"

namespace voxplan {

Status VolumeParams::Validate() const {
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("voxel size", voxel_size_m, bounds::kVoxelSizeMinM,
                                             bounds::kVoxelSizeMaxM, "m"));
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange("truncation", trunc_m / voxel_size_m,
                                             bounds::kTruncMinVoxels, bounds::kTruncMaxVoxels,
                                             "voxels"));
  if (max_memory_bytes != 0)
    return bounds::CheckRange("memory budget", double(max_memory_bytes),
                              double(bounds::kMemoryMinBytes), double(bounds::kMemoryMaxBytes),
                              "bytes");
  return Status::Ok();
}

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

TsdfBlock* TsdfVolume::AllocateWithinBudget(BlockIndex b) {
  if (TsdfBlock* found = FindBlock(b)) return found;
  if (params_.max_memory_bytes != 0 && MemoryBytesWithOneMore() > params_.max_memory_bytes) {
    ++blocks_refused_;
    return nullptr;
  }
  return &FindOrAllocate(b);
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
  blocks_refused_ = 0;
}

size_t TsdfVolume::MemoryBytes() const { return pool_.capacity_bytes() + map_.capacity_bytes(); }

size_t TsdfVolume::MemoryBytesWithOneMore() const {
  const size_t pool =
      pool_.capacity_bytes() + (pool_.AllocateNeedsChunk() ? pool_.chunk_bytes() : 0);
  return pool + map_.PeakBytesWith(map_.size() + 1);
}

std::vector<BlockIndex> TsdfVolume::SortedBlockIndices() const {
  std::vector<BlockIndex> out;
  out.reserve(map_.size());
  for (const auto& [b, s] : map_.Sorted()) out.push_back(b);
  return out;
}

}  // namespace voxplan
