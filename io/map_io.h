#pragma once
// Map files (.vpmap): magic, format version, volume parameters, block count, then the blocks in
// sorted BlockIndex order, each index followed by its raw TsdfBlock bytes, and a 64-bit checksum
// of everything before it. Save writes a temp file then renames; Load never modifies anything.
#include <cstdint>
#include <string>

#include "core/status.h"
#include "core/volume.h"

namespace voxplan {

inline constexpr uint32_t kMapFormatVersion = 1;

// Whether `path` names a map file: the .vpmap extension.
bool IsMapPath(const std::string& path);

Status SaveMap(const TsdfVolume& volume, const std::string& path);
Result<TsdfVolume> LoadMap(const std::string& path);

struct MapHeader {
  uint32_t version = 0;
  VolumeParams params;
  uint64_t num_blocks = 0;
};
Result<MapHeader> ReadMapHeader(const std::string& path);  // for `voxplan info`

}  // namespace voxplan
