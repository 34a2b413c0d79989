#include "io/image_io.h"

#include <jpeglib.h>
#include <png.h>

#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <vector>

#include "io/file_util.h"
#include "io/png_fast.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

// Larger than any depth camera; refusing bigger headers keeps a corrupt file from asking for
// gigabytes.
constexpr int kMaxImageSide = 16384;

// Owns a FILE*; closing on every path keeps the setjmp code free of cleanup branches.
struct FileCloser {
  FILE* file = nullptr;
  FileCloser() = default;
  FileCloser(const FileCloser&) = delete;
  FileCloser& operator=(const FileCloser&) = delete;
  ~FileCloser() { Close(); }
  void Close() {
    if (file) std::fclose(file);
    file = nullptr;
  }
};

Result<FILE*> OpenForRead(const std::string& path, FileCloser& closer) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound(path + ": file not found");
  if (fs::is_directory(path, ec)) return InvalidArgument(path + ": is a folder, not an image");
  closer.file = std::fopen(path.c_str(), "rb");
  if (!closer.file) return IoError(path + ": cannot open (" + std::strerror(errno) + ")");
  return closer.file;
}

enum class ImageKind { kPng, kJpeg, kOther };

// Sniffs the magic bytes and rewinds, so a .png that is really a JPEG still decodes.
Result<ImageKind> SniffKind(const std::string& path, FILE* file) {
  unsigned char magic[8] = {};
  const size_t n = std::fread(magic, 1, sizeof(magic), file);
  std::rewind(file);
  if (n == 0) return CorruptData(path + ": empty file");
  if (n == 8 && png_sig_cmp(magic, 0, 8) == 0) return ImageKind::kPng;
  if (n >= 3 && magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF) return ImageKind::kJpeg;
  return ImageKind::kOther;
}

// ---------------------------------------------------------------------------------------------
// libpng. The error callback longjmps back into RunPngRead / RunPngWrite; those functions hold no
// objects with destructors, and all buffers they fill live in the caller, so nothing leaks.

struct PngJob {
  std::jmp_buf jmp;
  char message[256] = {};
  FILE* file = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
};

void PngError(png_structp png, png_const_charp msg) {
  auto* job = static_cast<PngJob*>(png_get_error_ptr(png));
  std::snprintf(job->message, sizeof(job->message), "%s", msg ? msg : "unknown libpng error");
  std::longjmp(job->jmp, 1);
}
// Warnings (e.g. odd ancillary chunks) are not worth failing on, and the library never prints.
void PngWarning(png_structp, png_const_charp) {}

enum class PngMode { kHeader, kDepth, kColor };

struct PngPixels {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0, channels = 0;  // after transforms for kColor
  std::vector<png_byte> bytes;
  std::vector<png_bytep> rows;
  bool wrong_kind = false;  // kDepth: not 16-bit single-channel
};

// Returns false on a libpng error (message in job.message) or wrong_kind.
bool RunPngRead(PngJob& job, PngMode mode, PngPixels& out) {
  job.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &job, PngError, PngWarning);
  if (!job.png) {
    std::snprintf(job.message, sizeof(job.message), "cannot create libpng reader");
    return false;
  }
  job.info = png_create_info_struct(job.png);
  if (!job.info) {
    std::snprintf(job.message, sizeof(job.message), "cannot create libpng info");
    return false;
  }
  if (setjmp(job.jmp)) return false;
  png_init_io(job.png, job.file);
  png_set_user_limits(job.png, kMaxImageSide, kMaxImageSide);
  png_read_info(job.png, job.info);
  int interlace = 0;
  png_get_IHDR(job.png, job.info, &out.width, &out.height, &out.bit_depth, &out.color_type,
               &interlace, nullptr, nullptr);
  out.channels = png_get_channels(job.png, job.info);
  if (mode == PngMode::kHeader) return true;
  if (mode == PngMode::kDepth) {
    if (out.color_type != PNG_COLOR_TYPE_GRAY || out.bit_depth != 16) {
      out.wrong_kind = true;
      return false;
    }
  } else {
    if (out.color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(job.png);
    if (out.color_type == PNG_COLOR_TYPE_GRAY && out.bit_depth < 8)
      png_set_expand_gray_1_2_4_to_8(job.png);
    if (out.bit_depth == 16) png_set_strip_16(job.png);
    png_set_strip_alpha(job.png);
  }
  png_set_interlace_handling(job.png);
  png_read_update_info(job.png, job.info);
  out.channels = png_get_channels(job.png, job.info);
  const size_t row_bytes = png_get_rowbytes(job.png, job.info);
  out.bytes.resize(row_bytes * out.height);
  out.rows.resize(out.height);
  for (png_uint_32 y = 0; y < out.height; ++y) out.rows[y] = out.bytes.data() + y * row_bytes;
  png_read_image(job.png, out.rows.data());
  png_read_end(job.png, nullptr);
  return true;
}

struct PngReadGuard {
  PngJob& job;
  ~PngReadGuard() {
    if (job.png) png_destroy_read_struct(&job.png, job.info ? &job.info : nullptr, nullptr);
  }
};

Status DecodePngFile(const std::string& path, FILE* file, PngMode mode, PngPixels& out) {
  auto kind = SniffKind(path, file);
  if (!kind.ok()) return kind.status();
  if (*kind != ImageKind::kPng) return CorruptData(path + ": not a PNG file");
  PngJob job;
  job.file = file;
  PngReadGuard guard{job};
  if (!RunPngRead(job, mode, out)) {
    if (out.wrong_kind) return Status();  // caller words the message
    return CorruptData(path + ": corrupt or truncated PNG (" + job.message + ")");
  }
  return Status::Ok();
}

Status DecodePng(const std::string& path, PngMode mode, PngPixels& out) {
  FileCloser closer;
  auto file = OpenForRead(path, closer);
  if (!file.ok()) return file.status();
  return DecodePngFile(path, *file, mode, out);
}

std::string DescribePng(const PngPixels& p) {
  std::string kind;
  switch (p.color_type) {
    case PNG_COLOR_TYPE_GRAY:
      kind = "gray";
      break;
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      kind = "gray+alpha";
      break;
    case PNG_COLOR_TYPE_RGB:
      kind = "RGB";
      break;
    case PNG_COLOR_TYPE_RGB_ALPHA:
      kind = "RGBA";
      break;
    case PNG_COLOR_TYPE_PALETTE:
      kind = "palette";
      break;
    default:
      kind = "unknown colour type";
  }
  return std::to_string(p.bit_depth) + "-bit " + kind;
}

// ---------------------------------------------------------------------------------------------
// libjpeg: error_exit longjmps instead of exit(); messages are captured, never printed.

struct JpegErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jmp;
  char message[JMSG_LENGTH_MAX] = {};
};

void JpegErrorExit(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<JpegErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  std::longjmp(err->jmp, 1);
}
void JpegOutputMessage(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<JpegErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
}

struct JpegJob {
  jpeg_decompress_struct cinfo;
  JpegErrorManager err;
  bool created = false;
  FILE* file = nullptr;
};

// Decodes into `image` (the caller's, so no object with a destructor lives here across a
// longjmp). libjpeg-turbo writes RGBX rows straight into the image (its X byte is 0xFF and is
// cleared after), saving the copy out of packed RGB: 7-Scenes colour 1.3 -> 1.1 ms a frame.
bool RunJpegRead(JpegJob& job, ColorImage& image, std::vector<unsigned char>& pixels) {
  job.cinfo.err = jpeg_std_error(&job.err.pub);
  job.err.pub.error_exit = JpegErrorExit;
  job.err.pub.output_message = JpegOutputMessage;
  if (setjmp(job.err.jmp)) return false;
  jpeg_create_decompress(&job.cinfo);
  job.created = true;
  jpeg_stdio_src(&job.cinfo, job.file);
  jpeg_read_header(&job.cinfo, TRUE);
  if (job.cinfo.image_width > kMaxImageSide || job.cinfo.image_height > kMaxImageSide) {
    std::snprintf(job.err.message, sizeof(job.err.message), "image larger than %d pixels a side",
                  kMaxImageSide);
    return false;
  }
#ifdef JCS_EXTENSIONS
  job.cinfo.out_color_space = JCS_EXT_RGBX;
#else
  job.cinfo.out_color_space = JCS_RGB;
#endif
  jpeg_start_decompress(&job.cinfo);
  image = ColorImage(int(job.cinfo.output_width), int(job.cinfo.output_height));
  const size_t width = job.cinfo.output_width;
#ifdef JCS_EXTENSIONS
  while (job.cinfo.output_scanline < job.cinfo.output_height) {
    JSAMPROW row =
        reinterpret_cast<JSAMPROW>(image.data.data() + size_t(job.cinfo.output_scanline) * width);
    jpeg_read_scanlines(&job.cinfo, &row, 1);
  }
#else
  const size_t stride = width * size_t(job.cinfo.output_components);
  pixels.resize(stride * job.cinfo.output_height);
  while (job.cinfo.output_scanline < job.cinfo.output_height) {
    JSAMPROW row = pixels.data() + size_t(job.cinfo.output_scanline) * stride;
    jpeg_read_scanlines(&job.cinfo, &row, 1);
  }
#endif
  jpeg_finish_decompress(&job.cinfo);
  return true;
}

Result<ColorImage> DecodeJpeg(const std::string& path, FILE* file) {
  JpegJob job;
  job.file = file;
  ColorImage image;
  std::vector<unsigned char> pixels;  // packed RGB, without libjpeg-turbo's extensions
  const bool ok = RunJpegRead(job, image, pixels);
  // libjpeg "recovers" from a truncated file with a warning and grey rows; refuse that too.
  const bool warned = job.err.pub.num_warnings > 0;
  if (job.created) jpeg_destroy_decompress(&job.cinfo);
  if (!ok) return CorruptData(path + ": corrupt or truncated JPEG (" + job.err.message + ")");
  if (warned) return CorruptData(path + ": corrupt or truncated JPEG (" + job.err.message + ")");
#ifdef JCS_EXTENSIONS
  for (uint32_t& c : image.data) c &= 0x00ffffffu;  // PackRgb's X byte is 0
#else
  for (size_t i = 0; i < image.data.size(); ++i)
    image.data[i] = PackRgb(pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]);
#endif
  return image;
}

// Encoding into memory (jpeg_mem_dest), with the same longjmp error handling.
struct JpegEncodeJob {
  jpeg_compress_struct cinfo;
  JpegErrorManager err;
  bool created = false;
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
};

bool RunJpegWrite(JpegEncodeJob& job, const unsigned char* rgb, int width, int height,
                  int quality) {
  job.cinfo.err = jpeg_std_error(&job.err.pub);
  job.err.pub.error_exit = JpegErrorExit;
  job.err.pub.output_message = JpegOutputMessage;
  if (setjmp(job.err.jmp)) return false;
  jpeg_create_compress(&job.cinfo);
  job.created = true;
  jpeg_mem_dest(&job.cinfo, &job.buffer, &job.size);
  job.cinfo.image_width = JDIMENSION(width);
  job.cinfo.image_height = JDIMENSION(height);
  job.cinfo.input_components = 3;
  job.cinfo.in_color_space = JCS_RGB;
  jpeg_set_defaults(&job.cinfo);
  jpeg_set_quality(&job.cinfo, quality, TRUE);
  jpeg_start_compress(&job.cinfo, TRUE);
  const size_t stride = size_t(width) * 3;
  while (job.cinfo.next_scanline < job.cinfo.image_height) {
    JSAMPROW row = const_cast<unsigned char*>(rgb) + size_t(job.cinfo.next_scanline) * stride;
    jpeg_write_scanlines(&job.cinfo, &row, 1);
  }
  jpeg_finish_compress(&job.cinfo);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Writing.

struct PngWriteGuard {
  PngJob& job;
  ~PngWriteGuard() {
    if (job.png) png_destroy_write_struct(&job.png, job.info ? &job.info : nullptr);
  }
};

bool RunPngWrite(PngJob& job, int width, int height, int color_type, int bit_depth,
                 std::vector<png_bytep>& rows) {
  job.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &job, PngError, PngWarning);
  if (!job.png) {
    std::snprintf(job.message, sizeof(job.message), "cannot create libpng writer");
    return false;
  }
  job.info = png_create_info_struct(job.png);
  if (!job.info) {
    std::snprintf(job.message, sizeof(job.message), "cannot create libpng info");
    return false;
  }
  if (setjmp(job.jmp)) return false;
  png_init_io(job.png, job.file);
  // Level 3 writes several times faster than the default 6 for a few percent more bytes.
  png_set_compression_level(job.png, 3);
  png_set_IHDR(job.png, job.info, png_uint_32(width), png_uint_32(height), bit_depth, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(job.png, job.info);
  png_write_image(job.png, rows.data());
  png_write_end(job.png, nullptr);
  return true;
}

// `bytes` holds big-endian (PNG order) samples.
Status WritePngFile(const std::string& path, int width, int height, int channels, int bit_depth,
                    std::vector<png_byte>& bytes) {
  static constexpr int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                        PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  const size_t row_bytes = size_t(width) * size_t(channels) * size_t(bit_depth / 8);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) rows[size_t(y)] = bytes.data() + size_t(y) * row_bytes;

  FileCloser closer;
  closer.file = std::fopen(path.c_str(), "wb");
  if (!closer.file) return IoError(path + ": cannot create (" + std::strerror(errno) + ")");
  PngJob job;
  job.file = closer.file;
  PngWriteGuard guard{job};
  if (!RunPngWrite(job, width, height, kColorTypes[channels - 1], bit_depth, rows))
    return IoError(path + ": PNG write failed (" + job.message + ")");
  FILE* f = closer.file;
  closer.file = nullptr;
  const bool flushed = std::fflush(f) == 0;
  const bool closed = std::fclose(f) == 0;
  if (!flushed || !closed) return IoError(path + ": write failed (" + std::strerror(errno) + ")");
  return Status::Ok();
}

// Written to a temporary file beside `path`, then renamed, so readers never see half a PNG.
Status WritePngBytes(const std::string& path, int width, int height, int channels, int bit_depth,
                     std::vector<png_byte>& bytes) {
  return WriteAtomically(path, [&](const std::string& tmp) {
    return WritePngFile(tmp, width, height, channels, bit_depth, bytes);
  });
}

Status CheckSize(const std::string& path, int width, int height) {
  if (width <= 0 || height <= 0)
    return InvalidArgument(path + ": cannot write an empty image (" + std::to_string(width) + "x" +
                           std::to_string(height) + ")");
  return Status::Ok();
}

// Colour from an open file (on disk or in memory), its kind sniffed from the magic bytes.
Result<ColorImage> DecodeColorFile(const std::string& path, FILE* file) {
  auto kind = SniffKind(path, file);
  if (!kind.ok()) return kind.status();
  if (*kind == ImageKind::kJpeg) return DecodeJpeg(path, file);
  if (*kind != ImageKind::kPng) return Unsupported(path + ": not a PNG or JPEG file");
  PngPixels p;
  VOXPLAN_RETURN_IF_ERROR(DecodePngFile(path, file, PngMode::kColor, p));
  ColorImage color(int(p.width), int(p.height));
  const int c = p.channels;  // 1 or 2 (gray, alpha stripped leaves 1) or 3
  for (png_uint_32 y = 0; y < p.height; ++y) {
    const png_byte* row = p.rows[y];
    uint32_t* out = color.data.data() + size_t(y) * p.width;
    for (png_uint_32 x = 0; x < p.width; ++x) {
      const png_byte* px = row + size_t(x) * size_t(c);
      out[x] = c >= 3 ? PackRgb(px[0], px[1], px[2]) : PackRgb(px[0], px[0], px[0]);
    }
  }
  return color;
}

// Files up to this size are read whole for the depth fast path; larger ones stream through libpng.
constexpr long kMaxFastPngBytes = 64l << 20;

// png_fast::DecodeDepthPng over the whole of `file`, rewound after; nullopt when it declines.
std::optional<DepthImage> DecodeDepthPngFast(FILE* file, double depth_scale) {
  std::optional<DepthImage> depth;
  if (std::fseek(file, 0, SEEK_END) != 0) return depth;
  const long size = std::ftell(file);
  std::rewind(file);
  if (size <= 0 || size > kMaxFastPngBytes) return depth;
  thread_local std::vector<uint8_t> bytes;  // kept between frames, as png_fast's buffers
  bytes.resize(size_t(size));
  const bool read = std::fread(bytes.data(), 1, bytes.size(), file) == bytes.size();
  std::rewind(file);
  DepthImage image;
  if (read &&
      png_fast::DecodeDepthPng(bytes.data(), bytes.size(), kMaxImageSide, depth_scale, image))
    depth = std::move(image);
  return depth;
}

}  // namespace

Result<PngHeader> ReadPngHeader(const std::string& path) {
  PngPixels p;
  VOXPLAN_RETURN_IF_ERROR(DecodePng(path, PngMode::kHeader, p));
  PngHeader h;
  h.width = int(p.width);
  h.height = int(p.height);
  h.bit_depth = p.bit_depth;
  h.channels = p.channels;
  h.palette = p.color_type == PNG_COLOR_TYPE_PALETTE;
  return h;
}

Result<DepthImage> ReadDepthPng(const std::string& path, double depth_scale) {
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale))
    return InvalidArgument(path + ": depth scale must be positive and finite, got " +
                           std::to_string(depth_scale));
  FileCloser closer;
  auto file = OpenForRead(path, closer);
  if (!file.ok()) return file.status();
  // The common depth PNG decodes from memory (io/png_fast.h: libdeflate, SSE2 row filters; 7-Scenes
  // 3.6 -> 0.9 ms a frame); any other file, or anything irregular, goes to libpng as before.
  if (std::optional<DepthImage> fast = DecodeDepthPngFast(*file, depth_scale)) return *fast;
  PngPixels p;
  VOXPLAN_RETURN_IF_ERROR(DecodePngFile(path, *file, PngMode::kDepth, p));
  if (p.wrong_kind)
    return Unsupported(path + ": depth PNG must be 16-bit single-channel gray, found " +
                       DescribePng(p));
  DepthImage depth(int(p.width), int(p.height));
  const double inv_scale = 1.0 / depth_scale;
  for (png_uint_32 y = 0; y < p.height; ++y) {
    const png_byte* row = p.rows[y];
    float* out = depth.data.data() + size_t(y) * p.width;
    for (png_uint_32 x = 0; x < p.width; ++x) {
      const unsigned v = (unsigned(row[2 * x]) << 8) | unsigned(row[2 * x + 1]);  // big-endian
      out[x] = float(double(v) * inv_scale);  // 0 stays 0: invalid
    }
  }
  return depth;
}

Result<ColorImage> ReadColorImage(const std::string& path) {
  FileCloser closer;
  auto file = OpenForRead(path, closer);
  if (!file.ok()) return file.status();
  return DecodeColorFile(path, *file);
}

Result<ColorImage> DecodeColorImage(const void* data, size_t size, const std::string& name) {
  if (size == 0) return CorruptData(name + ": empty image");
  // A FILE over the bytes lets libpng and libjpeg read them as they read files.
  FileCloser closer;
  closer.file = fmemopen(const_cast<void*>(data), size, "rb");
  if (!closer.file)
    return IoError(name + ": cannot read image bytes (" + std::strerror(errno) + ")");
  return DecodeColorFile(name, closer.file);
}

Result<std::string> EncodeJpeg(const ColorImage& color, int quality) {
  if (color.width <= 0 || color.height <= 0)
    return InvalidArgument("cannot encode an empty image as JPEG");
  if (quality < 1 || quality > 100)
    return InvalidArgument("JPEG quality must be in [1, 100], got " + std::to_string(quality));
  std::vector<unsigned char> rgb(color.data.size() * 3);
  for (size_t i = 0; i < color.data.size(); ++i) {
    rgb[3 * i] = Red(color.data[i]);
    rgb[3 * i + 1] = Green(color.data[i]);
    rgb[3 * i + 2] = Blue(color.data[i]);
  }
  JpegEncodeJob job;
  const bool ok = RunJpegWrite(job, rgb.data(), color.width, color.height, quality);
  std::string bytes;
  if (ok) bytes.assign(reinterpret_cast<const char*>(job.buffer), job.size);
  if (job.created) jpeg_destroy_compress(&job.cinfo);
  std::free(job.buffer);  // jpeg_mem_dest's buffer is malloc'd and left to the caller
  if (!ok)
    return Status(StatusCode::kInternal, std::string("JPEG encode failed: ") + job.err.message);
  return bytes;
}

Status WriteDepthPng16(const std::string& path, const DepthImage& depth, double depth_scale) {
  VOXPLAN_RETURN_IF_ERROR(CheckSize(path, depth.width, depth.height));
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale))
    return InvalidArgument(path + ": depth scale must be positive and finite, got " +
                           std::to_string(depth_scale));
  std::vector<png_byte> bytes(depth.data.size() * 2);
  for (size_t i = 0; i < depth.data.size(); ++i) {
    const float d = depth.data[i];
    unsigned v = 0;
    if (std::isfinite(d) && d > 0.f) {
      const double units = std::round(double(d) * depth_scale);
      if (units > 65535.0)
        return InvalidArgument(path + ": depth " + std::to_string(d) + " m at pixel (" +
                               std::to_string(i % size_t(depth.width)) + ", " +
                               std::to_string(i / size_t(depth.width)) +
                               ") does not fit in 16 bits at scale " + std::to_string(depth_scale));
      v = unsigned(units);
    }
    bytes[2 * i] = png_byte(v >> 8);
    bytes[2 * i + 1] = png_byte(v & 0xff);
  }
  return WritePngBytes(path, depth.width, depth.height, 1, 16, bytes);
}

Status WriteColorPng(const std::string& path, const ColorImage& color) {
  VOXPLAN_RETURN_IF_ERROR(CheckSize(path, color.width, color.height));
  std::vector<png_byte> bytes(color.data.size() * 3);
  for (size_t i = 0; i < color.data.size(); ++i) {
    bytes[3 * i] = Red(color.data[i]);
    bytes[3 * i + 1] = Green(color.data[i]);
    bytes[3 * i + 2] = Blue(color.data[i]);
  }
  return WritePngBytes(path, color.width, color.height, 3, 8, bytes);
}

Status WritePngRaw(const std::string& path, int width, int height, int channels, int bit_depth,
                   const void* data) {
  VOXPLAN_RETURN_IF_ERROR(CheckSize(path, width, height));
  if (channels < 1 || channels > 4)
    return InvalidArgument(path + ": channels must be 1..4, got " + std::to_string(channels));
  if (bit_depth != 8 && bit_depth != 16)
    return InvalidArgument(path + ": bit depth must be 8 or 16, got " + std::to_string(bit_depth));
  const size_t samples = size_t(width) * size_t(height) * size_t(channels);
  std::vector<png_byte> bytes(samples * size_t(bit_depth / 8));
  if (bit_depth == 8) {
    std::memcpy(bytes.data(), data, samples);
  } else {
    const auto* src = static_cast<const uint16_t*>(data);
    for (size_t i = 0; i < samples; ++i) {
      bytes[2 * i] = png_byte(src[i] >> 8);
      bytes[2 * i + 1] = png_byte(src[i] & 0xff);
    }
  }
  return WritePngBytes(path, width, height, channels, bit_depth, bytes);
}

}  // namespace voxplan
