#pragma once
// A writer of ScanNet .sens files (SensorData version 4) for the tests, and a small scan made
// with it: a wall 2 m in front of a camera stepping sideways, zlib depth in millimetres, JPEG
// colour at twice the depth size, one frame with ScanNet's lost-tracking pose (-inf).
#include <zlib.h>

#include <Eigen/Core>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "io/image_io.h"
#include "io/sens_file.h"
#include "tests/support/test_support.h"

namespace voxplan::test {

struct SensTestFrame {
  Eigen::Matrix4f camera_to_world = Eigen::Matrix4f::Identity();
  uint64_t timestamp_us = 0;
  std::string color_bytes, depth_bytes;  // compressed as the header says
};

inline void PutU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
inline void PutU64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
inline void PutF32(std::string& out, float v) { PutU32(out, std::bit_cast<uint32_t>(v)); }
inline void PutMatrix(std::string& out, const Eigen::Matrix4f& m) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) PutF32(out, m(r, c));  // row-major, as mLib writes it
}

// The bytes of a .sens file: header, frame count, frames (no IMU frames).
inline std::string EncodeSens(const SensHeader& h, const std::vector<SensTestFrame>& frames,
                              uint32_t version = 4) {
  std::string out;
  PutU32(out, version);
  PutU64(out, h.sensor_name.size());
  out += h.sensor_name;
  PutMatrix(out, h.color_intrinsic);
  PutMatrix(out, h.color_extrinsic);
  PutMatrix(out, h.depth_intrinsic);
  PutMatrix(out, h.depth_extrinsic);
  PutU32(out, uint32_t(h.color_compression));
  PutU32(out, uint32_t(h.depth_compression));
  PutU32(out, uint32_t(h.color_width));
  PutU32(out, uint32_t(h.color_height));
  PutU32(out, uint32_t(h.depth_width));
  PutU32(out, uint32_t(h.depth_height));
  PutF32(out, h.depth_shift);
  PutU64(out, frames.size());
  for (const SensTestFrame& f : frames) {
    PutMatrix(out, f.camera_to_world);
    PutU64(out, f.timestamp_us);  // colour
    PutU64(out, f.timestamp_us);  // depth
    PutU64(out, f.color_bytes.size());
    PutU64(out, f.depth_bytes.size());
    out += f.color_bytes;
    out += f.depth_bytes;
  }
  return out;
}

// Depth (metres) as little-endian uint16 units at `shift` per metre, zlib-compressed.
inline std::string ZlibDepth(const DepthImage& depth, float shift) {
  std::string raw;
  for (float d : depth.data) {
    const unsigned v = d > 0.f ? unsigned(d * shift + 0.5f) : 0u;
    raw.push_back(char(v & 0xff));
    raw.push_back(char(v >> 8));
  }
  uLongf size = compressBound(uLong(raw.size()));
  std::string out(size, '\0');
  compress2(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
            uLong(raw.size()), 6);
  out.resize(size);
  return out;
}

inline Eigen::Matrix4f Intrinsic(float fx, float fy, float cx, float cy) {
  Eigen::Matrix4f k = Eigen::Matrix4f::Identity();
  k(0, 0) = fx, k(1, 1) = fy, k(0, 2) = cx, k(1, 2) = cy;
  return k;
}

// A smooth colour pattern (JPEG keeps it within a few levels): red grows with u, green with v.
inline ColorImage GradientColor(int width, int height) {
  ColorImage c(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
      c.at(u, v) = PackRgb(uint8_t(u * 255 / (width - 1)), uint8_t(v * 255 / (height - 1)), 128);
  return c;
}

// The small scan: 32 x 24 depth (fx 24, cx 15.5), 64 x 48 JPEG colour of the same view
// (fx 48, cx 31.5: a resize), depth shift 1000, frames 5 cm apart along x at 30 Hz in
// microseconds, looking at the wall z = 2; frame `lost` (if below `frames`) has the -inf pose.
struct SensScan {
  SensHeader header;
  std::vector<SensTestFrame> frames;
  PinholeCamera depth_camera;
};

inline SensScan MakeWallScan(int frames = 4, int lost = 2) {
  SensScan s;
  SensHeader& h = s.header;
  h.sensor_name = "StructureSensor";
  h.depth_width = 32, h.depth_height = 24;
  h.color_width = 64, h.color_height = 48;
  h.depth_intrinsic = Intrinsic(24.f, 24.f, 15.5f, 11.5f);
  h.color_intrinsic = Intrinsic(48.f, 48.f, 31.5f, 23.5f);
  h.color_extrinsic = h.depth_extrinsic = Eigen::Matrix4f::Identity();
  h.color_compression = SensColorCompression::kJpeg;
  h.depth_compression = SensDepthCompression::kZlibUshort;
  h.depth_shift = 1000.f;
  s.depth_camera = PinholeCamera{32, 24, 24.f, 24.f, 15.5f, 11.5f};
  const std::string jpeg = EncodeJpeg(GradientColor(64, 48), 95).value();
  const Plane wall{Eigen::Vector3f(0, 0, -1), -2.f};
  for (int i = 0; i < frames; ++i) {
    SensTestFrame f;
    f.camera_to_world(0, 3) = 0.05f * float(i);
    Pose3f T_W_C;
    T_W_C.matrix() = f.camera_to_world;
    f.timestamp_us = 1000000 + uint64_t(i) * 33333;
    f.depth_bytes = ZlibDepth(RenderDepth(wall, s.depth_camera, T_W_C), h.depth_shift);
    f.color_bytes = jpeg;
    if (i == lost) f.camera_to_world.setConstant(-std::numeric_limits<float>::infinity());
    s.frames.push_back(std::move(f));
  }
  return s;
}

inline std::string ReadFileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

}  // namespace voxplan::test
