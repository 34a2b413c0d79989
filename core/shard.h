#pragma once
// Which process owns a block when a map is split over ranks (distributed/, `mpirun voxplan
// fuse`): a fixed hash of the block's chunk, the 8^3 blocks sharing index >> 3. Chunks, not
// single blocks, so that a rank's blocks are mostly each other's neighbours and the halo that
// meshing across shards needs stays small; still hashed, so a frame's blocks spread over all
// ranks. The function is part of the sharded map format (its manifest names it): changing it
// changes which shard holds a block.
#include <cstdint>

#include "core/index.h"

namespace voxplan {

inline constexpr int kShardChunkShift = 3;  // 8 blocks per chunk side
inline constexpr uint32_t kMaxShardRanks = 4096;
inline constexpr const char* kShardOwnerFunction = "splitmix64(block >> 3) mod ranks";

constexpr uint32_t BlockOwner(BlockIndex b, uint32_t ranks) {
  if (ranks <= 1) return 0;
  const auto c = [](int32_t v) { return uint64_t(uint32_t(v >> kShardChunkShift)) & 0x1fffff; };
  uint64_t k = c(b.x) | (c(b.y) << 21) | (c(b.z) << 42);
  k ^= k >> 30;  // splitmix64 finaliser
  k *= 0xbf58476d1ce4e5b9ull;
  k ^= k >> 27;
  k *= 0x94d049bb133111ebull;
  k ^= k >> 31;
  return uint32_t(k % ranks);
}

// This process's part of a split map: rank `rank` of `ranks` keeps the blocks BlockOwner gives
// it. The default, one rank, keeps everything.
struct ShardSpec {
  uint32_t rank = 0;
  uint32_t ranks = 1;
  constexpr bool Owns(BlockIndex b) const { return ranks <= 1 || BlockOwner(b, ranks) == rank; }
  constexpr bool whole() const { return ranks <= 1; }
};

}  // namespace voxplan
