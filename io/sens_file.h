#pragma once
// ScanNet's .sens files (the SensorData layout of ScanNet's SensReader, version 4): a header
// (sensor name, colour and depth intrinsics and extrinsics, compression, image sizes, depth
// shift), then per frame its camera-to-world pose, timestamps and compressed colour and depth.
// ReadSensIndex walks the headers only; each frame's images are read and decoded on demand.
// Every size read from the file is bounded (by the file's size and by core/bounds.h) before it
// is used; errors name the file and, past the header, the frame.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

// The compression codes of the format (ScanNet: JPEG colour, zlib depth).
enum class SensColorCompression : int32_t { kRaw = 0, kPng = 1, kJpeg = 2 };
enum class SensDepthCompression : int32_t { kRawUshort = 0, kZlibUshort = 1, kOcciUshort = 2 };

struct SensHeader {
  std::string sensor_name;
  // 4x4, row-major in the file. Intrinsics: fx, fy on the diagonal, cx, cy in the last column.
  // An extrinsic maps its camera into a common frame; ScanNet's colour one is the identity and
  // its depth one the depth-to-colour transform (both identity once registered).
  Eigen::Matrix4f color_intrinsic, color_extrinsic, depth_intrinsic, depth_extrinsic;
  SensColorCompression color_compression = SensColorCompression::kJpeg;
  SensDepthCompression depth_compression = SensDepthCompression::kZlibUshort;
  int color_width = 0, color_height = 0, depth_width = 0, depth_height = 0;
  float depth_shift = 1000.f;  // depth units per metre
};

struct SensFrameRecord {
  Eigen::Matrix4f camera_to_world;  // ScanNet writes -inf where its tracking was lost
  uint64_t color_timestamp_us = 0, depth_timestamp_us = 0;
  uint64_t color_offset = 0, color_bytes = 0;  // where the compressed images lie in the file
  uint64_t depth_offset = 0, depth_bytes = 0;
};

struct SensIndex {
  std::string path;
  uint64_t file_bytes = 0;
  SensHeader header;
  std::vector<SensFrameRecord> frames;
};

// A compressed image may hold at most twice its raw bytes plus this (JPEG headers of tiny
// images): a corrupt size field cannot ask for more memory than the frame could need.
inline constexpr uint64_t kSensCompressedSlackBytes = uint64_t(1) << 20;

// Reads and checks the header and every frame's record (not the images). Refuses another
// version than 4, unknown or unsupported compression (occi depth), image sizes outside
// core/bounds.h, a depth shift outside its range, non-rigid extrinsics, and any size that runs
// past the end of the file. Bytes after the last frame (ScanNet's IMU frames) are not read.
Result<SensIndex> ReadSensIndex(const std::string& path);

// Frame i's depth in metres (value / depth_scale; 0 stays 0) and its colour (PNG, JPEG or raw
// RGB), each checked against the header's size. Thread-safe: each call opens the file.
Result<DepthImage> ReadSensDepth(const SensIndex& index, size_t i, double depth_scale);
Result<ColorImage> ReadSensColor(const SensIndex& index, size_t i);

// "<file>: frame <i>", the name errors and frame paths use.
std::string SensFrameName(const SensIndex& index, size_t i);

}  // namespace voxplan
