#pragma once
// The structure of a ROS 1 bag (format 2.0), checked before rosbag_storage reads it:
// rosbag_storage trusts the file's lengths (it allocates a record header's stated length, parses
// headers past their end, and reads messages at an index entry's offset without looking at the
// chunk's size), so a corrupt bag could crash it or take the machine's memory. Every record's
// header and data must lie inside the file, every header must be a whole list of name=value
// fields, the index must point at records of the right kinds, and each index entry at a whole
// message record inside its chunk (decompressed here, bz2 and lz4 as rosbag does, to check it).
// No ROS headers: io/rosbag_file.cpp calls it from RosBagFile::Open.
#include <cstdint>
#include <string>

#include "core/status.h"

namespace voxplan {

// A chunk larger than this uncompressed is refused before its buffer is allocated (rosbag writes
// 768 KiB chunks, larger only by the one message that closes a chunk).
inline constexpr uint64_t kMaxBagChunkBytes = uint64_t(1) << 30;

// Ok, or CorruptData / Unsupported naming the file and the byte of the first fault. Refuses
// other versions than 2.0, encrypted bags and unindexed ones (a recording that did not finish:
// `rosbag reindex` repairs it).
Status CheckRosBagStructure(const std::string& path);

}  // namespace voxplan
