#pragma once
// Stable chunked storage of blocks: a slot's address never moves while the slot lives.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/block.h"

namespace voxplan {

class BlockPool {
 public:
  static constexpr uint32_t kChunkBlocks = 256;

  // Returns a slot holding a reset block.
  uint32_t Allocate();
  void Release(uint32_t slot);
  void Clear();

  TsdfBlock& operator[](uint32_t slot) { return chunks_[slot / kChunkBlocks][slot % kChunkBlocks]; }
  const TsdfBlock& operator[](uint32_t slot) const {
    return chunks_[slot / kChunkBlocks][slot % kChunkBlocks];
  }
  size_t live() const { return next_ - free_.size(); }
  size_t capacity_bytes() const { return chunks_.size() * chunk_bytes(); }
  static constexpr size_t chunk_bytes() { return kChunkBlocks * sizeof(TsdfBlock); }
  // True when the next Allocate() adds a chunk (no free slot, every chunk full).
  bool AllocateNeedsChunk() const {
    return free_.empty() && next_ / kChunkBlocks >= chunks_.size();
  }

 private:
  std::vector<std::unique_ptr<TsdfBlock[]>> chunks_;
  std::vector<uint32_t> free_;
  uint32_t next_ = 0;
};

}  // namespace voxplan
