#pragma once
// Map files (.vpmap): magic, format version, volume parameters, block count, (version 2) the
// world's up axis, then the blocks in sorted BlockIndex order, each index followed by its raw
// TsdfBlock bytes, and a 64-bit checksum of everything before it. Save writes a temp file then
// renames; Load never modifies anything. Version 1 files (no up axis) still load, as unknown up.
#include <cstdint>
#include <string>

#include "core/status.h"
#include "core/volume.h"
#include "io/world_up.h"

namespace voxplan {

inline constexpr uint32_t kMapFormatVersion = 2;        // what SaveMap writes
inline constexpr uint32_t kMapFormatOldestVersion = 1;  // the oldest LoadMap reads

// Whether `path` names a map file: the .vpmap extension.
bool IsMapPath(const std::string& path);

// `up`: the world's up axis the map records (`voxplan fuse` passes the dataset's).
Status SaveMap(const TsdfVolume& volume, const std::string& path, WorldUp up = WorldUp::kUnknown);
// `up`, when given, receives the recorded up axis (kUnknown for a version 1 file).
Result<TsdfVolume> LoadMap(const std::string& path, WorldUp* up = nullptr);

struct MapHeader {
  uint32_t version = 0;
  VolumeParams params;
  uint64_t num_blocks = 0;
  WorldUp up = WorldUp::kUnknown;  // version 1: unknown (read as +z)
};
Result<MapHeader> ReadMapHeader(const std::string& path);  // for `voxplan info`

}  // namespace voxplan
