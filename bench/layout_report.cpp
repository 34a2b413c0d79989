// Layout report: the sizes of the stored types and the bytes each voxel costs. A change here
// changes memory use and map files, so it is printed, not hidden.
#include <cstdio>

#include "core/block.h"
#include "core/block_pool.h"
#include "core/volume.h"

int main() {
  using namespace voxplan;
  std::printf("%-34s %8s\n", "type", "bytes");
  std::printf("%-34s %8zu\n", "TsdfBlock (8^3 voxels)", sizeof(TsdfBlock));
  std::printf("%-34s %8zu\n", "  tsdf   int16 x 512", sizeof(TsdfBlock::tsdf));
  std::printf("%-34s %8zu\n", "  weight uint16 x 512", sizeof(TsdfBlock::weight));
  std::printf("%-34s %8zu\n", "  r, g, b uint8 x 512 each", 3 * sizeof(TsdfBlock::r));
  std::printf("%-34s %8zu\n", "BlockIndex", sizeof(BlockIndex));
  std::printf("%-34s %8zu\n", "hash slot (packed key + slot)", sizeof(uint64_t) + sizeof(uint32_t));
  std::printf("%-34s %8zu\n", "pool chunk (blocks)", size_t(BlockPool::kChunkBlocks));
  // The map keeps load factor <= 1/2: at most 2 hash slots per block, 24 bytes over 512 voxels.
  const double hash_per_voxel = 2.0 * (sizeof(uint64_t) + sizeof(uint32_t)) / kBlockVoxels;
  std::printf(
      "{\"block_bytes\":%zu,\"voxel_payload_bytes\":%.3f,\"hash_bytes_per_voxel_max\":%.4f,"
      "\"bytes_per_voxel_max\":%.4f}\n",
      sizeof(TsdfBlock), TsdfVolume::BytesPerVoxel(), hash_per_voxel,
      TsdfVolume::BytesPerVoxel() + hash_per_voxel);
}
