#include "core/block_pool.h"

#include <algorithm>

namespace voxplan {

void ResetBlock(TsdfBlock& block) {
  std::fill(std::begin(block.tsdf), std::end(block.tsdf), int16_t(kTsdfScale));
  std::fill(std::begin(block.weight), std::end(block.weight), uint16_t(0));
  std::fill(std::begin(block.r), std::end(block.r), uint8_t(0));
  std::fill(std::begin(block.g), std::end(block.g), uint8_t(0));
  std::fill(std::begin(block.b), std::end(block.b), uint8_t(0));
}

uint32_t BlockPool::Allocate() {
  uint32_t slot;
  if (!free_.empty()) {
    slot = free_.back();
    free_.pop_back();
  } else {
    slot = next_++;
    if (slot / kChunkBlocks >= chunks_.size())
      chunks_.push_back(std::make_unique_for_overwrite<TsdfBlock[]>(kChunkBlocks));
  }
  ResetBlock((*this)[slot]);
  return slot;
}

void BlockPool::Release(uint32_t slot) { free_.push_back(slot); }

void BlockPool::Clear() {
  chunks_.clear();
  free_.clear();
  next_ = 0;
}

}  // namespace voxplan
