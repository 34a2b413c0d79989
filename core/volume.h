#pragma once
// TsdfVolume stores and looks up blocks; algorithms live elsewhere as free functions.
#include <cstdint>
#include <vector>

#include "core/block_map.h"
#include "core/block_pool.h"

namespace voxplan {

struct VolumeParams {
  float voxel_size_m = 0.01f;
  float trunc_m = 0.04f;  // truncation distance of the signed distance
};

class TsdfVolume {
 public:
  // Throws std::invalid_argument unless 0 < voxel_size_m and voxel_size_m <= trunc_m.
  explicit TsdfVolume(VolumeParams params);

  const VolumeParams& params() const { return params_; }
  float voxel_size_m() const { return params_.voxel_size_m; }
  float trunc_m() const { return params_.trunc_m; }
  float block_size_m() const { return params_.voxel_size_m * kBlockSide; }

  const TsdfBlock* FindBlock(BlockIndex b) const {
    const uint32_t s = map_.Find(b);
    return s == BlockMap::kNoSlot ? nullptr : &pool_[s];
  }
  TsdfBlock* FindBlock(BlockIndex b) {
    const uint32_t s = map_.Find(b);
    return s == BlockMap::kNoSlot ? nullptr : &pool_[s];
  }
  // Not thread-safe; block addresses stay valid until the block is erased.
  TsdfBlock& FindOrAllocate(BlockIndex b, bool* created = nullptr);
  bool EraseBlock(BlockIndex b);
  void Clear();

  size_t num_blocks() const { return map_.size(); }
  size_t num_voxels() const { return map_.size() * kBlockVoxels; }
  // Bytes of voxel payload per allocated voxel, and everything the volume holds.
  static constexpr double BytesPerVoxel() { return double(sizeof(TsdfBlock)) / kBlockVoxels; }
  size_t MemoryBytes() const;

  std::vector<BlockIndex> SortedBlockIndices() const;
  template <typename F>  // f(BlockIndex, const TsdfBlock&), unordered
  void ForEachBlock(F&& f) const {
    map_.ForEach([&](BlockIndex b, uint32_t s) { f(b, pool_[s]); });
  }

 private:
  VolumeParams params_;
  BlockMap map_;
  BlockPool pool_;
};

}  // namespace voxplan
