#pragma once
// The ranges every numeric parameter is held to: the libraries' Validate() functions and the
// command line's validators read the same constants, so a value means the same everywhere.
// Each range is wide enough for any real use and narrow enough that no value in it can make
// a run spin or grow memory without bound (the memory budget bounds the rest).
#include <cstdint>
#include <string>

#include "core/camera.h"
#include "core/status.h"

namespace voxplan::bounds {

// Voxel edge: below 1 mm a frame's truncation band is tens of millions of voxels.
inline constexpr double kVoxelSizeMinM = 0.001, kVoxelSizeMaxM = 1.0;
// Truncation in voxels: a pixel's band walk stays within 2 * 64 / 8 = 16 blocks.
inline constexpr double kTruncMinVoxels = 1.0, kTruncMaxVoxels = 64.0;
// Depth ranges (min and max) lie within this, metres.
inline constexpr double kDepthMaxM = 100.0;
// Image and render sizes: per side, and in all (2^26 = 8192 x 8192).
inline constexpr int kImageSideMax = 16384;
inline constexpr int64_t kImagePixelsMax = int64_t(1) << 26;
// |fx| / width and |fy| / height: 0.1 is a 157 degree field of view, 100 is 0.6 degrees.
inline constexpr double kFocalMinPerSide = 0.1, kFocalMaxPerSide = 100.0;
inline constexpr int kThreadsMax = 1024;  // worker threads (0: all hardware threads)
inline constexpr double kDepthScaleMin = 0.01, kDepthScaleMax = 1e6;  // depth units per metre
inline constexpr int64_t kFramesMax = int64_t(1) << 30;  // frame counts, starts and strides
// A memory budget: at least 1 MiB (one pool chunk), at most 1 PiB.
inline constexpr uint64_t kMemoryMinBytes = uint64_t(1) << 20;
inline constexpr uint64_t kMemoryMaxBytes = uint64_t(1) << 50;

// "<name> must be in [lo, hi] <unit>, got <value>" unless lo <= value <= hi (NaN never is).
Status CheckRange(const std::string& name, double value, double lo, double hi,
                  const std::string& unit = "");
// The range as it is written in messages: "[0.001, 1] m".
std::string RangeText(double lo, double hi, const std::string& unit = "");
// width x height within kImageSideMax per side and kImagePixelsMax in all.
Status CheckImageSize(const std::string& name, int64_t width, int64_t height);
// Intrinsics against the image size: |fx|, |fy| within kFocal*PerSide of the side (fy may be
// negative, as ICL-NUIM's is), cx in [0, width], cy in [0, height], everything finite.
Status CheckIntrinsics(const PinholeCamera& camera);

}  // namespace voxplan::bounds
