#pragma once
// TsdfVolume stores and looks up blocks; algorithms live elsewhere as free functions.
#include <cstdint>
#include <vector>

#include "core/block_map.h"
#include "core/block_pool.h"
#include "core/status.h"

namespace voxplan {

struct VolumeParams {
  float voxel_size_m = 0.01f;
  float trunc_m = 0.04f;  // truncation distance of the signed distance
  // Memory budget of the volume (blocks, pool and hash table, as MemoryBytes() counts them);
  // AllocateWithinBudget refuses new blocks past it. 0: no budget.
  uint64_t max_memory_bytes = 0;

  // Voxel size and truncation within core/bounds.h's ranges (truncation in voxels), the budget
  // 0 or within its range; InvalidArgument naming the value and the range otherwise.
  Status Validate() const;
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
  // The same within the memory budget: a new block that would take MemoryBytesWith(one more)
  // past params().max_memory_bytes is not allocated (nullptr, counted in blocks_refused()).
  TsdfBlock* AllocateWithinBudget(BlockIndex b);
  size_t blocks_refused() const { return blocks_refused_; }
  bool EraseBlock(BlockIndex b);
  void Clear();

  size_t num_blocks() const { return map_.size(); }
  size_t num_voxels() const { return map_.size() * kBlockVoxels; }
  // Bytes of voxel payload per allocated voxel, and everything the volume holds: the pool's
  // chunks and the hash table's arrays.
  static constexpr double BytesPerVoxel() { return double(sizeof(TsdfBlock)) / kBlockVoxels; }
  size_t MemoryBytes() const;
  // What the volume would hold at its peak while allocating one more block: a new pool chunk
  // when the pool is full, and the hash table's old and new arrays while it grows.
  size_t MemoryBytesWithOneMore() const;

  std::vector<BlockIndex> SortedBlockIndices() const;
  template <typename F>  // f(BlockIndex, const TsdfBlock&), unordered
  void ForEachBlock(F&& f) const {
    map_.ForEach([&](BlockIndex b, uint32_t s) { f(b, pool_[s]); });
  }

 private:
  VolumeParams params_;
  BlockMap map_;
  BlockPool pool_;
  size_t blocks_refused_ = 0;
};

}  // namespace voxplan
