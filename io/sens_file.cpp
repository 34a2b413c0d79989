#include "io/sens_file.h"

#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "core/bounds.h"
#include "core/pose.h"
#include "io/image_io.h"
#include "io/text_file.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kSensVersion = 4;
constexpr uint64_t kMaxSensorNameBytes = 4096;
// A frame's record before its images: a 4x4 float pose and four uint64 (timestamps, sizes).
constexpr uint64_t kFrameRecordBytes = 16 * 4 + 4 * 8;
// Deflate inflates at most 1032-fold (a 258-byte match per 2 bits), plus zlib's header: a depth
// stream too short to fill the header's image is refused before its buffer is allocated.
constexpr uint64_t kZlibMaxRatio = 1032, kZlibSlackBytes = 64;

// Little-endian reads over a file of known size; every read is checked against what is left,
// so a size field can never move the reader past the end or allocate more than the file holds.
class SensReader {
 public:
  SensReader(std::ifstream& in, std::string path, uint64_t size)
      : in_(in), path_(std::move(path)), size_(size) {}
  uint64_t left() const { return size_ - pos_; }
  uint64_t pos() const { return pos_; }
  std::string where() const { return context_.empty() ? path_ : path_ + ": " + context_; }
  void set_context(std::string context) { context_ = std::move(context); }

  Status Bytes(void* out, uint64_t n, const char* what) {
    if (n > left())
      return CorruptData(where() + ": truncated: " + what + " needs " + std::to_string(n) +
                         " bytes at byte " + std::to_string(pos_) + ", " + std::to_string(left()) +
                         " left");
    if (n > 0 && !in_.read(static_cast<char*>(out), std::streamsize(n)))
      return IoError(where() + ": read failed at byte " + std::to_string(pos_));
    pos_ += n;
    return Status::Ok();
  }
  Status Skip(uint64_t n, const char* what) {
    if (n > left())
      return CorruptData(where() + ": " + what + " of " + std::to_string(n) +
                         " bytes runs past the end of the file (at byte " + std::to_string(pos_) +
                         ", " + std::to_string(left()) + " left)");
    pos_ += n;
    in_.seekg(std::streamoff(pos_));
    if (!in_) return IoError(where() + ": seek failed to byte " + std::to_string(pos_));
    return Status::Ok();
  }
  Result<uint64_t> U64(const char* what) {
    unsigned char b[8];
    VOXPLAN_RETURN_IF_ERROR(Bytes(b, 8, what));
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | b[i];
    return v;
  }
  Result<uint32_t> U32(const char* what) {
    unsigned char b[4];
    VOXPLAN_RETURN_IF_ERROR(Bytes(b, 4, what));
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
  }
  Result<float> F32(const char* what) {
    Result<uint32_t> bits = U32(what);
    if (!bits.ok()) return bits.status();
    return std::bit_cast<float>(*bits);
  }
  Result<Eigen::Matrix4f> Matrix(const char* what) {
    Eigen::Matrix4f m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        Result<float> v = F32(what);
        if (!v.ok()) return v.status();
        m(r, c) = *v;
      }
    return m;
  }

 private:
  std::ifstream& in_;
  std::string path_;
  uint64_t size_ = 0, pos_ = 0;
  std::string context_;
};

Status CheckIntrinsic(const Eigen::Matrix4f& k, const std::string& path, const char* which) {
  const float fx = k(0, 0), fy = k(1, 1);
  if (!(fx > 0.f) || !(fy > 0.f) || !std::isfinite(fx) || !std::isfinite(fy) ||
      !std::isfinite(k(0, 2)) || !std::isfinite(k(1, 2)))
    return CorruptData(path + ": " + which + " intrinsics (fx " + NumberText(fx) + ", fy " +
                       NumberText(fy) + ", cx " + NumberText(k(0, 2)) + ", cy " +
                       NumberText(k(1, 2)) + ") must be finite with positive focal lengths");
  return Status::Ok();
}

Status CheckExtrinsic(const Eigen::Matrix4f& m, const std::string& path, const char* which) {
  if (Status s = ValidatePoseMatrix(m.cast<double>()); !s.ok())
    return CorruptData(path + ": " + which + " extrinsics: " + s.message());
  return Status::Ok();
}

Result<SensHeader> ReadHeader(SensReader& r, const std::string& path) {
  SensHeader h;
  Result<uint32_t> version = r.U32("version");
  if (!version.ok()) return version.status();
  if (*version != kSensVersion)
    return Unsupported(path + ": SensorData version " + std::to_string(*version) +
                       ", only version 4 (ScanNet) is read");
  Result<uint64_t> name_bytes = r.U64("sensor name length");
  if (!name_bytes.ok()) return name_bytes.status();
  if (*name_bytes > kMaxSensorNameBytes)
    return CorruptData(path + ": sensor name of " + std::to_string(*name_bytes) +
                       " bytes (at most " + std::to_string(kMaxSensorNameBytes) + ")");
  h.sensor_name.resize(size_t(*name_bytes));
  VOXPLAN_RETURN_IF_ERROR(r.Bytes(h.sensor_name.data(), *name_bytes, "sensor name"));
  Eigen::Matrix4f* matrices[] = {&h.color_intrinsic, &h.color_extrinsic, &h.depth_intrinsic,
                                 &h.depth_extrinsic};
  for (Eigen::Matrix4f* m : matrices) {
    Result<Eigen::Matrix4f> read = r.Matrix("calibration matrix");
    if (!read.ok()) return read.status();
    *m = *read;
  }
  Result<uint32_t> color_type = r.U32("colour compression");
  Result<uint32_t> depth_type = r.U32("depth compression");
  if (!color_type.ok()) return color_type.status();
  if (!depth_type.ok()) return depth_type.status();
  const int32_t ct = std::bit_cast<int32_t>(*color_type), dt = std::bit_cast<int32_t>(*depth_type);
  if (ct < 0 || ct > 2)
    return Unsupported(path + ": colour compression " + std::to_string(ct) +
                       " (known: 0 raw, 1 PNG, 2 JPEG)");
  if (dt == int32_t(SensDepthCompression::kOcciUshort))
    return Unsupported(path +
                       ": depth compression 2 (occi_ushort) is not supported; ScanNet's "
                       "files use 1 (zlib_ushort)");
  if (dt < 0 || dt > 1)
    return Unsupported(path + ": depth compression " + std::to_string(dt) +
                       " (known: 0 raw_ushort, 1 zlib_ushort)");
  h.color_compression = SensColorCompression(ct);
  h.depth_compression = SensDepthCompression(dt);
  uint32_t sides[4];
  const char* side_names[4] = {"colour width", "colour height", "depth width", "depth height"};
  for (int i = 0; i < 4; ++i) {
    Result<uint32_t> v = r.U32(side_names[i]);
    if (!v.ok()) return v.status();
    sides[i] = *v;
  }
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize(path + ": depth image", sides[2], sides[3]));
  h.depth_width = int(sides[2]);
  h.depth_height = int(sides[3]);
  // A file without colour may state a zero colour size; any other is checked like depth's.
  if (sides[0] != 0 || sides[1] != 0) {
    VOXPLAN_RETURN_IF_ERROR(bounds::CheckImageSize(path + ": colour image", sides[0], sides[1]));
    h.color_width = int(sides[0]);
    h.color_height = int(sides[1]);
  }
  Result<float> shift = r.F32("depth shift");
  if (!shift.ok()) return shift.status();
  VOXPLAN_RETURN_IF_ERROR(bounds::CheckRange(path + ": depth shift", *shift, bounds::kDepthScaleMin,
                                             bounds::kDepthScaleMax, "units per metre"));
  h.depth_shift = *shift;
  VOXPLAN_RETURN_IF_ERROR(CheckIntrinsic(h.depth_intrinsic, path, "depth"));
  VOXPLAN_RETURN_IF_ERROR(CheckExtrinsic(h.depth_extrinsic, path, "depth"));
  if (h.color_width > 0) {
    VOXPLAN_RETURN_IF_ERROR(CheckIntrinsic(h.color_intrinsic, path, "colour"));
    VOXPLAN_RETURN_IF_ERROR(CheckExtrinsic(h.color_extrinsic, path, "colour"));
  }
  return h;
}

uint64_t RawColorBytes(const SensHeader& h) {
  return uint64_t(h.color_width) * uint64_t(h.color_height) * 3;
}
uint64_t RawDepthBytes(const SensHeader& h) {
  return uint64_t(h.depth_width) * uint64_t(h.depth_height) * 2;
}

// The compressed size a frame may state: raw sizes exactly, compressed ones within the slack.
Status CheckImageBytes(uint64_t bytes, uint64_t raw, bool is_raw, const std::string& where,
                       const char* what) {
  if (is_raw && bytes != raw)
    return CorruptData(where + ": raw " + what + " of " + std::to_string(bytes) +
                       " bytes, the header's size needs " + std::to_string(raw));
  if (!is_raw && bytes > 2 * raw + kSensCompressedSlackBytes)
    return CorruptData(where + ": compressed " + what + " of " + std::to_string(bytes) +
                       " bytes, more than twice the raw " + std::to_string(raw));
  return Status::Ok();
}

// The bytes at [offset, offset + n) of the file, opened afresh (so loads may run in parallel).
Result<std::string> ReadRange(const SensIndex& index, uint64_t offset, uint64_t n,
                              const std::string& where) {
  std::ifstream in(index.path, std::ios::binary);
  if (!in) return IoError(index.path + ": cannot open");
  std::error_code ec;
  const uintmax_t size = fs::file_size(index.path, ec);
  if (ec || size != index.file_bytes)
    return IoError(index.path + ": changed size since it was opened (" + std::to_string(size) +
                   " bytes, was " + std::to_string(index.file_bytes) + ")");
  std::string bytes(size_t(n), '\0');
  in.seekg(std::streamoff(offset));
  if (!in || (n > 0 && !in.read(bytes.data(), std::streamsize(n))))
    return IoError(where + ": read failed at byte " + std::to_string(offset));
  return bytes;
}

}  // namespace

std::string SensFrameName(const SensIndex& index, size_t i) {
  return index.path + ": frame " + std::to_string(i);
}

Result<SensIndex> ReadSensIndex(const std::string& path) {
  SensIndex index;
  index.path = path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return NotFound(path + ": .sens file not found");
  index.file_bytes = fs::file_size(path, ec);
  if (ec) return IoError(path + ": cannot stat (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) return IoError(path + ": cannot open");
  SensReader r(in, path, index.file_bytes);
  Result<SensHeader> header = ReadHeader(r, path);
  if (!header.ok()) return header.status();
  index.header = std::move(header).value();
  const SensHeader& h = index.header;

  Result<uint64_t> frames = r.U64("frame count");
  if (!frames.ok()) return frames.status();
  // Each frame takes at least its record: a count the file cannot hold is refused before any
  // memory is reserved for it.
  if (*frames > r.left() / kFrameRecordBytes || *frames > uint64_t(bounds::kFramesMax))
    return CorruptData(path + ": states " + std::to_string(*frames) + " frames, but " +
                       std::to_string(r.left()) + " bytes are left (" +
                       std::to_string(kFrameRecordBytes) + " per frame at least)");
  if (*frames == 0) return CorruptData(path + ": holds no frames");
  index.frames.reserve(size_t(*frames));
  const bool raw_color = h.color_compression == SensColorCompression::kRaw;
  const bool raw_depth = h.depth_compression == SensDepthCompression::kRawUshort;
  for (uint64_t i = 0; i < *frames; ++i) {
    const std::string where = SensFrameName(index, size_t(i));
    r.set_context("frame " + std::to_string(i));
    SensFrameRecord f;
    Result<Eigen::Matrix4f> pose = r.Matrix("camera-to-world pose");
    if (!pose.ok()) return pose.status();
    f.camera_to_world = *pose;
    Result<uint64_t> tc = r.U64("colour timestamp"), td = r.U64("depth timestamp");
    if (!tc.ok()) return tc.status();
    if (!td.ok()) return td.status();
    Result<uint64_t> cb = r.U64("colour size"), db = r.U64("depth size");
    if (!cb.ok()) return cb.status();
    if (!db.ok()) return db.status();
    f.color_timestamp_us = *tc;
    f.depth_timestamp_us = *td;
    f.color_bytes = *cb;
    f.depth_bytes = *db;
    if (f.depth_bytes == 0) return CorruptData(where + ": no depth bytes");
    VOXPLAN_RETURN_IF_ERROR(
        CheckImageBytes(f.depth_bytes, RawDepthBytes(h), raw_depth, where, "depth"));
    if (!raw_depth && f.depth_bytes * kZlibMaxRatio + kZlibSlackBytes < RawDepthBytes(h))
      return CorruptData(where + ": zlib depth of " + std::to_string(f.depth_bytes) +
                         " bytes cannot inflate to the header's " + std::to_string(h.depth_width) +
                         "x" + std::to_string(h.depth_height) + " (" +
                         std::to_string(RawDepthBytes(h)) + " bytes)");
    if (h.color_width == 0 && f.color_bytes > 0)
      return CorruptData(where + ": " + std::to_string(f.color_bytes) +
                         " colour bytes, but the header states no colour image size");
    if (f.color_bytes > 0)
      VOXPLAN_RETURN_IF_ERROR(
          CheckImageBytes(f.color_bytes, RawColorBytes(h), raw_color, where, "colour"));
    f.color_offset = r.pos();
    VOXPLAN_RETURN_IF_ERROR(r.Skip(f.color_bytes, "colour image"));
    f.depth_offset = r.pos();
    VOXPLAN_RETURN_IF_ERROR(r.Skip(f.depth_bytes, "depth image"));
    index.frames.push_back(f);
  }
  return index;
}

Result<DepthImage> ReadSensDepth(const SensIndex& index, size_t i, double depth_scale) {
  if (i >= index.frames.size())
    return InvalidArgument(index.path + ": frame " + std::to_string(i) + " out of range (" +
                           std::to_string(index.frames.size()) + " frames)");
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale))
    return InvalidArgument(index.path + ": depth scale must be positive and finite, got " +
                           NumberText(depth_scale));
  const SensHeader& h = index.header;
  const SensFrameRecord& f = index.frames[i];
  const std::string where = SensFrameName(index, i);
  Result<std::string> bytes = ReadRange(index, f.depth_offset, f.depth_bytes, where);
  if (!bytes.ok()) return bytes.status();
  const uint64_t raw_bytes = RawDepthBytes(h);
  std::string raw;
  if (h.depth_compression == SensDepthCompression::kRawUshort) {
    raw = std::move(bytes).value();
  } else {
    // uncompress() writes at most raw_bytes: a stream that inflates to more is refused, not read.
    raw.resize(size_t(raw_bytes));
    uLongf out_bytes = uLongf(raw_bytes);
    const int z = uncompress(reinterpret_cast<Bytef*>(raw.data()), &out_bytes,
                             reinterpret_cast<const Bytef*>(bytes->data()), uLong(bytes->size()));
    if (z == Z_BUF_ERROR && out_bytes == raw_bytes)
      return CorruptData(where + ": zlib depth inflates to more than the header's " +
                         std::to_string(h.depth_width) + "x" + std::to_string(h.depth_height));
    if (z != Z_OK)
      return CorruptData(where + ": corrupt zlib depth (" + (zError(z) ? zError(z) : "error") +
                         ")");
    if (out_bytes != raw_bytes)
      return CorruptData(where + ": zlib depth inflates to " + std::to_string(out_bytes) +
                         " bytes, the header's " + std::to_string(h.depth_width) + "x" +
                         std::to_string(h.depth_height) + " needs " + std::to_string(raw_bytes));
  }
  DepthImage depth(h.depth_width, h.depth_height);
  const double inv_scale = 1.0 / depth_scale;
  const auto* p = reinterpret_cast<const unsigned char*>(raw.data());
  for (size_t k = 0; k < depth.data.size(); ++k) {
    const unsigned v = unsigned(p[2 * k]) | unsigned(p[2 * k + 1]) << 8;  // little-endian
    depth.data[k] = float(double(v) * inv_scale);                         // 0 stays 0: invalid
  }
  return depth;
}

Result<ColorImage> ReadSensColor(const SensIndex& index, size_t i) {
  if (i >= index.frames.size())
    return InvalidArgument(index.path + ": frame " + std::to_string(i) + " out of range (" +
                           std::to_string(index.frames.size()) + " frames)");
  const SensHeader& h = index.header;
  const SensFrameRecord& f = index.frames[i];
  const std::string where = SensFrameName(index, i);
  if (f.color_bytes == 0) return CorruptData(where + ": no colour bytes");
  Result<std::string> bytes = ReadRange(index, f.color_offset, f.color_bytes, where);
  if (!bytes.ok()) return bytes.status();
  if (h.color_compression == SensColorCompression::kRaw) {
    ColorImage color(h.color_width, h.color_height);
    const auto* p = reinterpret_cast<const unsigned char*>(bytes->data());
    for (size_t k = 0; k < color.data.size(); ++k)
      color.data[k] = PackRgb(p[3 * k], p[3 * k + 1], p[3 * k + 2]);
    return color;
  }
  Result<ColorImage> color = DecodeColorImage(bytes->data(), bytes->size(), where + " colour");
  if (!color.ok()) return color.status();
  if (color->width != h.color_width || color->height != h.color_height)
    return CorruptData(where + ": colour decodes to " + std::to_string(color->width) + "x" +
                       std::to_string(color->height) + ", the header states " +
                       std::to_string(h.color_width) + "x" + std::to_string(h.color_height));
  return color;
}

}  // namespace voxplan
