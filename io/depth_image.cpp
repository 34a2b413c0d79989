// Depth images of every type (depth_image.h): PNG through image_io.h; TIFF through libtiff and
// OpenEXR through OpenEXR's C++ library, the one file of voxplan that includes either. Their
// headers are parsed here first (TIFF's first image directory; EXR's attributes and its chunk
// offset table), so that the refusals name the file and say why and sizes are bounded before
// either library allocates or decodes anything; each decoder then checks that its library sees
// the image the header stated. Nothing is printed: libtiff's messages go to handlers of each
// call (TiffMessages), OpenEXR's to the exceptions caught here, both into the error returned.
#include "io/depth_image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <tiffio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "io/file_util.h"
#include "io/image_io.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

// As PNG depth (image_io.cpp): larger than any depth camera, and a corrupt header cannot ask for
// gigabytes.
constexpr int64_t kMaxSide = 16384;
// An EXR header (its attributes) longer than this is refused; real ones take a few hundred bytes.
constexpr size_t kMaxExrHeaderBytes = 64 << 10;

// Random access to a file: every read must lie inside it.
class FileBytes {
 public:
  FileBytes() = default;
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  ~FileBytes() {
    if (file_) std::fclose(file_);
  }
  Status Open(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return NotFound(path + ": file not found");
    if (!fs::is_regular_file(path, ec)) return InvalidArgument(path + ": not a regular file");
    const auto size = fs::file_size(path, ec);
    if (ec) return IoError(path + ": cannot read its size (" + ec.message() + ")");
    size_ = uint64_t(size);
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) return IoError(path + ": cannot open (" + std::strerror(errno) + ")");
    return Status::Ok();
  }
  uint64_t size() const { return size_; }
  // False when [offset, offset + n) is not inside the file, or the read fails.
  bool Read(uint64_t offset, void* out, size_t n) const {
    if (offset > size_ || n > size_ - offset) return false;
    if (n == 0) return true;
    if (fseeko(file_, off_t(offset), SEEK_SET) != 0) return false;
    return std::fread(out, 1, n, file_) == n;
  }

 private:
  std::FILE* file_ = nullptr;
  uint64_t size_ = 0;
};

std::string Text(uint64_t v) { return std::to_string(v); }

Status CheckSides(const std::string& path, const char* what, int64_t width, int64_t height) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    return CorruptData(path + ": " + what + " image is " + std::to_string(width) + "x" +
                       std::to_string(height) + "; each side must be 1 to " +
                       std::to_string(kMaxSide) + " pixels");
  return Status::Ok();
}

// Tiles no larger than the image needs (a side up to twice the image's, or up to 1024), so that a
// corrupt header cannot make the decoder allocate more than a few times the image.
Status CheckTiles(const std::string& path, const char* what, uint64_t tile_w, uint64_t tile_h,
                  uint64_t width, uint64_t height) {
  const auto fits = [](uint64_t tile, uint64_t side) {
    return tile >= 1 && tile <= std::max<uint64_t>(2 * side, 1024);
  };
  if (!fits(tile_w, width) || !fits(tile_h, height))
    return CorruptData(path + ": " + what + " tiles of " + Text(tile_w) + "x" + Text(tile_h) +
                       " pixels for a " + Text(width) + "x" + Text(height) + " image; a tile " +
                       "side must be 1 to twice the image's side (or to 1024)");
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// TIFF: the byte order, the first image file directory and the tags that say what a pixel is.

struct Endian {
  bool little = true;
  uint64_t Get(const uint8_t* p, int bytes) const {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t(p[little ? i : bytes - 1 - i]) << (8 * i);
    return v;
  }
};

Result<DepthFileHeader> ParseTiff(const std::string& path, const FileBytes& f) {
  uint8_t h[16] = {};
  if (!f.Read(0, h, 8))
    return CorruptData(path + ": not a TIFF file (" + Text(f.size()) + " bytes)");
  Endian e;
  if (h[0] == 'I' && h[1] == 'I') {
    e.little = true;
  } else if (h[0] == 'M' && h[1] == 'M') {
    e.little = false;
  } else {
    return CorruptData(path + ": not a TIFF file (no II or MM byte order mark)");
  }
  const uint64_t magic = e.Get(h + 2, 2);
  bool big = false;  // BigTIFF: 8-byte counts and offsets
  uint64_t ifd = 0;
  if (magic == 42) {
    ifd = e.Get(h + 4, 4);
  } else if (magic == 43) {
    if (!f.Read(0, h, 16) || e.Get(h + 4, 2) != 8 || e.Get(h + 6, 2) != 0)
      return CorruptData(path + ": BigTIFF header is not 8-byte offsets");
    big = true;
    ifd = e.Get(h + 8, 8);
  } else {
    return CorruptData(path + ": not a TIFF file (version " + Text(magic) + ", expected 42)");
  }
  const size_t count_bytes = big ? 8 : 2, entry_bytes = big ? 20 : 12, field = big ? 8 : 4;
  uint8_t c[8] = {};
  if (ifd < 8 || !f.Read(ifd, c, count_bytes))
    return CorruptData(path + ": TIFF image directory at byte " + Text(ifd) +
                       " lies outside the file (" + Text(f.size()) + " bytes)");
  const uint64_t n = e.Get(c, int(count_bytes));
  if (n == 0 || n > 4096)
    return CorruptData(path + ": TIFF image directory holds " + Text(n) + " entries");
  std::vector<uint8_t> entries(size_t(n) * entry_bytes);
  if (!f.Read(ifd + count_bytes, entries.data(), entries.size()))
    return CorruptData(path + ": TIFF image directory runs past the end of the file");

  // The first value of each tag read; absent ones take TIFF's defaults (no width or height).
  uint64_t width = 0, height = 0, bits = 1, samples = 1, format = 1, photometric = 1;
  uint64_t tile_w = 0, tile_h = 0;
  bool have_width = false, have_height = false, tiled = false;
  for (uint64_t i = 0; i < n; ++i) {
    const uint8_t* entry = entries.data() + size_t(i) * entry_bytes;
    const uint64_t tag = e.Get(entry, 2), type = e.Get(entry + 2, 2);
    if (tag != 256 && tag != 257 && tag != 258 && tag != 262 && tag != 277 && tag != 322 &&
        tag != 323 && tag != 339)
      continue;
    const uint64_t count = e.Get(entry + 4, big ? 8 : 4);
    const uint8_t* value_field = entry + (big ? 12 : 8);
    // BYTE, SHORT, LONG, LONG8.
    const size_t bytes = type == 1 ? 1 : type == 3 ? 2 : type == 4 ? 4 : type == 16 ? 8 : 0;
    if (bytes == 0)
      return CorruptData(path + ": TIFF tag " + Text(tag) + " has type " + Text(type) +
                         ", not an unsigned integer");
    if (count == 0) return CorruptData(path + ": TIFF tag " + Text(tag) + " has no value");
    uint8_t v[8] = {};
    if (count <= field / bytes) {  // the values sit in the entry itself
      std::memcpy(v, value_field, bytes);
    } else if (!f.Read(e.Get(value_field, int(field)), v, bytes)) {
      return CorruptData(path + ": TIFF tag " + Text(tag) + "'s values lie outside the file");
    }
    const uint64_t value = e.Get(v, int(bytes));
    switch (tag) {
      case 256:
        width = value, have_width = true;
        break;
      case 257:
        height = value, have_height = true;
        break;
      case 258:
        bits = value;
        break;
      case 262:
        photometric = value;
        break;
      case 277:
        samples = value;
        break;
      case 322:
        tile_w = value, tiled = true;
        break;
      case 323:
        tile_h = value, tiled = true;
        break;
      default:  // 339
        format = value;
        break;
    }
  }
  if (!have_width || !have_height)
    return CorruptData(path + ": TIFF image directory has no " +
                       (have_width ? "ImageLength" : "ImageWidth") + " tag");
  VOXPLAN_RETURN_IF_ERROR(CheckSides(path, "TIFF", int64_t(std::min<uint64_t>(width, 1u << 30)),
                                     int64_t(std::min<uint64_t>(height, 1u << 30))));
  if (tiled) VOXPLAN_RETURN_IF_ERROR(CheckTiles(path, "TIFF", tile_w, tile_h, width, height));
  if (samples != 1)
    return Unsupported(path + ": depth TIFF must be single-channel, found " + Text(samples) +
                       " samples per pixel");
  if (photometric != 1)
    return Unsupported(path + ": depth TIFF must be gray with black at zero (photometric " +
                       "interpretation 1), found " + Text(photometric));
  DepthFileHeader header;
  header.type = DepthFileType::kTiff;
  header.width = int(width);
  header.height = int(height);
  if (format == 1 && bits == 16) {
    header.bits = 16;
  } else if (format == 3 && bits == 32) {
    header.bits = 32;
    header.metres = true;
  } else {
    const std::string kind = format == 1   ? "unsigned integer"
                             : format == 2 ? "signed integer"
                             : format == 3 ? "float"
                                           : "sample format " + Text(format);
    return Unsupported(path + ": depth TIFF must hold 16-bit unsigned integers or 32-bit " +
                       "floats (metres), found " + Text(bits) + "-bit " + kind + " samples");
  }
  return header;
}

// ---------------------------------------------------------------------------------------------
// OpenEXR: the version flags, the header's attributes (channels, dataWindow, compression) and,
// for scanline images, the chunk offset table, every chunk inside the file.

struct ExrChannel {
  std::string name;
  int32_t pixel_type = 0;  // 0 UINT, 1 HALF, 2 FLOAT
  int32_t x_sampling = 1, y_sampling = 1;
};

int32_t Int32(const uint8_t* p) {
  return int32_t(uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 |
                 uint32_t(p[3]) << 24);
}

// A null-terminated string starting at `at`, within [at, end); advances `at` past the null.
bool ExrString(const std::vector<uint8_t>& b, size_t end, size_t& at, std::string& out) {
  const size_t start = at;
  while (at < end && b[at] != 0) ++at;
  if (at >= end || at - start > 255) return false;
  out.assign(reinterpret_cast<const char*>(b.data() + start), at - start);
  ++at;
  return true;
}

// Scanlines per chunk of each compression (OpenEXR's file layout).
int ExrLinesPerChunk(int compression) {
  switch (compression) {
    case 0:  // none
    case 1:  // RLE
    case 2:  // ZIPS
      return 1;
    case 3:  // ZIP
    case 5:  // PXR24
      return 16;
    case 4:  // PIZ
    case 6:  // B44
    case 7:  // B44A
    case 8:  // DWAA
      return 32;
    case 9:  // DWAB
      return 256;
    default:
      return 0;
  }
}

Result<DepthFileHeader> ParseExr(const std::string& path, const FileBytes& f) {
  const size_t have = size_t(std::min<uint64_t>(f.size(), 8 + kMaxExrHeaderBytes));
  std::vector<uint8_t> b(have);
  if (have < 8 || !f.Read(0, b.data(), have))
    return CorruptData(path + ": not an OpenEXR file (" + Text(f.size()) + " bytes)");
  if (!(b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01))
    return CorruptData(path + ": not an OpenEXR file (no magic number 76 2f 31 01)");
  const uint32_t version = uint32_t(Int32(b.data() + 4));
  if ((version & 0xff) != 2)
    return Unsupported(path + ": OpenEXR version " + Text(version & 0xff) + ", expected 2");
  const bool tiled = version & 0x200, deep = version & 0x800, multipart = version & 0x1000;
  if (deep || multipart)
    return Unsupported(path + ": a " + (deep ? "deep" : "multi-part") + " OpenEXR file; depth " +
                       "must be a single-part scanline or tiled image");

  std::vector<ExrChannel> channels;
  bool have_channels = false, have_window = false, have_compression = false;
  int64_t x_min = 0, y_min = 0, x_max = -1, y_max = -1;
  int compression = 0;
  bool have_tiles = false;
  uint64_t tile_w = 0, tile_h = 0;
  size_t at = 8;
  for (;;) {
    if (at >= have)
      return CorruptData(path + ": OpenEXR header " +
                         (have < f.size() ? "longer than " + Text(kMaxExrHeaderBytes) + " bytes"
                                          : std::string("runs past the end of the file")));
    if (b[at] == 0) {  // the empty name that ends the header
      ++at;
      break;
    }
    std::string name, type;
    if (!ExrString(b, have, at, name) || !ExrString(b, have, at, type) || at + 4 > have)
      return CorruptData(path + ": OpenEXR header attribute at byte " + Text(at) + " is malformed");
    const int32_t size = Int32(b.data() + at);
    at += 4;
    if (size < 0 || size_t(size) > have - at)
      return CorruptData(path + ": OpenEXR attribute '" + name + "' of " + std::to_string(size) +
                         " bytes runs past the header");
    const size_t value = at, value_end = at + size_t(size);
    at = value_end;
    if (name == "channels" && type == "chlist") {
      have_channels = true;
      size_t c = value;
      while (c < value_end && b[c] != 0) {
        ExrChannel ch;
        if (!ExrString(b, value_end, c, ch.name) || c + 16 > value_end)
          return CorruptData(path + ": OpenEXR channel list is malformed");
        ch.pixel_type = Int32(b.data() + c);
        ch.x_sampling = Int32(b.data() + c + 8);
        ch.y_sampling = Int32(b.data() + c + 12);
        c += 16;
        channels.push_back(ch);
      }
    } else if (name == "dataWindow" && type == "box2i" && size == 16) {
      have_window = true;
      x_min = Int32(b.data() + value);
      y_min = Int32(b.data() + value + 4);
      x_max = Int32(b.data() + value + 8);
      y_max = Int32(b.data() + value + 12);
    } else if (name == "compression" && type == "compression" && size == 1) {
      have_compression = true;
      compression = b[value];
    } else if (name == "tiles" && type == "tiledesc" && size == 9) {
      have_tiles = true;
      tile_w = uint32_t(Int32(b.data() + value));
      tile_h = uint32_t(Int32(b.data() + value + 4));
    }
  }
  if (!have_channels || !have_window || !have_compression)
    return CorruptData(path + ": OpenEXR header has no '" +
                       (!have_channels ? "channels"
                        : !have_window ? "dataWindow"
                                       : "compression") +
                       "' attribute");
  const int64_t width = x_max - x_min + 1, height = y_max - y_min + 1;
  VOXPLAN_RETURN_IF_ERROR(CheckSides(path, "OpenEXR", width, height));
  if (channels.size() != 1) {
    std::string names;
    for (const ExrChannel& ch : channels) names += (names.empty() ? "" : " ") + ch.name;
    return Unsupported(path + ": depth EXR must have one channel, found " +
                       std::to_string(channels.size()) + (names.empty() ? "" : " (" + names + ")"));
  }
  const ExrChannel& ch = channels.front();  // any name: Y, R, Z, Depth.Z, ...
  if (ch.pixel_type != 1 && ch.pixel_type != 2)
    return Unsupported(path + ": depth EXR channel " + ch.name + " must hold float metres (32- " +
                       "or 16-bit), found " +
                       (ch.pixel_type == 0 ? std::string("32-bit unsigned integers")
                                           : "pixel type " + std::to_string(ch.pixel_type)));
  if (ch.x_sampling != 1 || ch.y_sampling != 1)
    return Unsupported(path + ": depth EXR channel " + ch.name + " is subsampled");
  const int lines = ExrLinesPerChunk(compression);
  if (lines == 0)
    return Unsupported(path + ": OpenEXR compression " + std::to_string(compression) +
                       " is unknown");

  if (tiled) {
    if (!have_tiles) return CorruptData(path + ": tiled OpenEXR header has no 'tiles' attribute");
    VOXPLAN_RETURN_IF_ERROR(
        CheckTiles(path, "OpenEXR", tile_w, tile_h, uint64_t(width), uint64_t(height)));
  } else {
    // The offset table, then each chunk's y and size: all inside the file, so that a truncated
    // file is refused by its header, before OpenEXR reads a pixel.
    const uint64_t chunks = uint64_t((height + lines - 1) / lines);
    std::vector<uint8_t> table(size_t(chunks) * 8);
    if (!f.Read(at, table.data(), table.size()))
      return CorruptData(path + ": OpenEXR offset table of " + Text(chunks) +
                         " chunks runs past the end of the file (truncated?)");
    const uint64_t data_start = at + table.size();
    for (uint64_t k = 0; k < chunks; ++k) {
      uint64_t offset = 0;
      for (int i = 0; i < 8; ++i) offset |= uint64_t(table[size_t(k) * 8 + size_t(i)]) << (8 * i);
      uint8_t chunk[8];
      if (offset < data_start || !f.Read(offset, chunk, 8))
        return CorruptData(path + ": OpenEXR chunk " + Text(k) + " of " + Text(chunks) +
                           " lies outside the file (truncated?)");
      const int32_t bytes = Int32(chunk + 4);
      if (bytes < 0 || uint64_t(bytes) > f.size() - offset - 8)
        return CorruptData(path + ": OpenEXR chunk " + Text(k) + " of " + Text(chunks) +
                           " runs past the end of the file (truncated?)");
    }
  }
  DepthFileHeader header;
  header.type = DepthFileType::kExr;
  header.width = int(width);
  header.height = int(height);
  header.bits = ch.pixel_type == 2 ? 32 : 16;
  header.metres = true;
  return header;
}

Result<DepthFileHeader> ParseHeader(const std::string& path, DepthFileType type,
                                    const FileBytes& f) {
  return type == DepthFileType::kTiff ? ParseTiff(path, f) : ParseExr(path, f);
}

// ---------------------------------------------------------------------------------------------
// Decoding: TIFF through libtiff, EXR through OpenEXR, each checked against the parsed header.

// NaN fails the first test; +inf the second; negative (and -0) depth is no depth.
void ZeroInvalid(DepthImage& metres) {
  for (float& v : metres.data) v = v > 0.f && v <= std::numeric_limits<float>::max() ? v : 0.f;
}

// libtiff's errors and warnings for one TIFF handle, never printed. The handlers are given to
// TIFFOpenExt with this call's own TiffMessages as their user data, and return 1 so that
// libtiff's process-wide handlers (stderr by default) are not called: nothing is shared between
// the threads that decode at once (Dataset::Load), and the process's handlers are left alone.
struct TiffMessages {
  std::string first_error;

  static int OnError(TIFF*, void* user, const char* module, const char* fmt, va_list ap) {
    auto* self = static_cast<TiffMessages*>(user);
    if (self->first_error.empty()) {
      char text[512];
      std::vsnprintf(text, sizeof text, fmt, ap);
      self->first_error = module && *module ? std::string(module) + ": " + text : text;
    }
    return 1;
  }
  static int OnWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }
  std::string Suffix() const {
    return first_error.empty() ? "" : " (libtiff: " + first_error + ")";
  }
};

struct TiffCloser {
  void operator()(TIFF* tif) const { TIFFClose(tif); }
};
struct TiffOptionsFree {
  void operator()(TIFFOpenOptions* options) const { TIFFOpenOptionsFree(options); }
};

Result<DepthImage> DecodeTiff(const std::string& path, const DepthFileHeader& header,
                              double depth_scale) {
  TiffMessages messages;
  std::unique_ptr<TIFF, TiffCloser> tif;
  {
    std::unique_ptr<TIFFOpenOptions, TiffOptionsFree> options(TIFFOpenOptionsAlloc());
    if (!options) return IoError(path + ": libtiff cannot allocate its open options");
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), &TiffMessages::OnError, &messages);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), &TiffMessages::OnWarning, &messages);
    // "m": read(), not mmap: a file truncated while it is read is an error, not SIGBUS. The
    // handle keeps the handlers; the options may go.
    tif.reset(TIFFOpenExt(path.c_str(), "rm", options.get()));
  }
  if (!tif) return CorruptData(path + ": libtiff cannot read this TIFF file" + messages.Suffix());
  uint32_t width = 0, height = 0;
  uint16_t bits = 0, samples = 0, format = 0;
  if (!TIFFGetField(tif.get(), TIFFTAG_IMAGEWIDTH, &width) ||
      !TIFFGetField(tif.get(), TIFFTAG_IMAGELENGTH, &height) ||
      !TIFFGetFieldDefaulted(tif.get(), TIFFTAG_BITSPERSAMPLE, &bits) ||
      !TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLESPERPIXEL, &samples) ||
      !TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLEFORMAT, &format))
    return CorruptData(path + ": libtiff finds no image size or sample layout" + messages.Suffix());
  const uint16_t expected_format = header.metres ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT;
  if (int64_t(width) != header.width || int64_t(height) != header.height || bits != header.bits ||
      samples != 1 || format != expected_format)
    return CorruptData(path + ": libtiff reads a " + Text(width) + "x" + Text(height) +
                       " image of " + Text(samples) + " " + Text(bits) + "-bit samples (format " +
                       Text(format) + ") but the header states " + std::to_string(header.width) +
                       "x" + std::to_string(header.height) + " " + header.Encoding());
  // With one sample per pixel both planar configurations lay the samples out alike.
  const size_t bytes = size_t(bits / 8), row_bytes = size_t(width) * bytes;
  std::vector<uint16_t> units;
  DepthImage depth(header.width, header.height);
  uint8_t* out = reinterpret_cast<uint8_t*>(depth.data.data());
  if (!header.metres) {
    units.resize(size_t(width) * height);
    out = reinterpret_cast<uint8_t*>(units.data());
  }
  if (TIFFIsTiled(tif.get())) {
    uint32_t tile_w = 0, tile_h = 0;
    if (!TIFFGetField(tif.get(), TIFFTAG_TILEWIDTH, &tile_w) ||
        !TIFFGetField(tif.get(), TIFFTAG_TILELENGTH, &tile_h))
      return CorruptData(path + ": tiled TIFF without its tile size" + messages.Suffix());
    VOXPLAN_RETURN_IF_ERROR(CheckTiles(path, "TIFF", tile_w, tile_h, width, height));
    const size_t tile_row_bytes = size_t(tile_w) * bytes;
    std::vector<uint8_t> tile(tile_row_bytes * tile_h);
    const uint32_t tiles = TIFFNumberOfTiles(tif.get());
    for (uint32_t y = 0; y < height; y += tile_h) {
      for (uint32_t x = 0; x < width; x += tile_w) {
        const uint32_t k = TIFFComputeTile(tif.get(), x, y, 0, 0);
        if (TIFFReadEncodedTile(tif.get(), k, tile.data(), tmsize_t(tile.size())) !=
            tmsize_t(tile.size()))
          return CorruptData(path + ": TIFF tile " + Text(k) + " of " + Text(tiles) +
                             " does not decode (corrupt or truncated pixel data)" +
                             messages.Suffix());
        const uint32_t rows = std::min(tile_h, height - y), cols = std::min(tile_w, width - x);
        for (uint32_t r = 0; r < rows; ++r)
          std::memcpy(out + size_t(y + r) * row_bytes + size_t(x) * bytes,
                      tile.data() + size_t(r) * tile_row_bytes, size_t(cols) * bytes);
      }
    }
  } else {
    uint32_t rows_per_strip = 0;
    TIFFGetFieldDefaulted(tif.get(), TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
    if (rows_per_strip == 0 || rows_per_strip > height) rows_per_strip = height;
    const uint32_t strips = TIFFNumberOfStrips(tif.get());
    for (uint32_t y = 0; y < height; y += rows_per_strip) {
      const uint32_t k = TIFFComputeStrip(tif.get(), y, 0);
      const size_t size = size_t(std::min(rows_per_strip, height - y)) * row_bytes;
      if (TIFFReadEncodedStrip(tif.get(), k, out + size_t(y) * row_bytes, tmsize_t(size)) !=
          tmsize_t(size))
        return CorruptData(path + ": TIFF strip " + Text(k) + " of " + Text(strips) +
                           " does not decode (corrupt or truncated pixel data)" +
                           messages.Suffix());
    }
  }
  if (header.metres) {
    ZeroInvalid(depth);
  } else {
    const double inv_scale = 1.0 / depth_scale;  // as ReadDepthPng: the same floats
    for (size_t i = 0; i < units.size(); ++i) depth.data[i] = float(double(units[i]) * inv_scale);
  }
  return depth;
}

// The one channel as 32-bit floats, whatever its name (the header parser allows one channel of
// HALF or FLOAT; OpenEXR widens HALF exactly). OpenEXR reports every failure by an exception;
// it prints nothing.
Result<DepthImage> DecodeExr(const std::string& path, const DepthFileHeader& header) {
  DepthImage depth(header.width, header.height);
  try {
    // Threads: OpenEXR's global count, 0 unless the process set it: decoded on this thread.
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const Imf::ChannelList& channels = file.header().channels();
    auto channel = channels.begin();
    size_t count = 0;
    for (auto c = channels.begin(); c != channels.end(); ++c) ++count;
    if (int64_t(window.max.x) - window.min.x + 1 != header.width ||
        int64_t(window.max.y) - window.min.y + 1 != header.height || count != 1)
      return CorruptData(path + ": OpenEXR reads another image than its header states (" +
                         std::to_string(header.width) + "x" + std::to_string(header.height) +
                         ", one channel)");
    Imf::FrameBuffer frame;
    frame.insert(channel.name(),
                 Imf::Slice::Make(Imf::FLOAT, depth.data.data(), window, sizeof(float),
                                  sizeof(float) * size_t(header.width)));
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
  } catch (const std::exception& e) {
    return CorruptData(path +
                       ": OpenEXR cannot decode it (corrupt or truncated pixel data): " + e.what());
  } catch (...) {
    return CorruptData(path + ": OpenEXR cannot decode it (corrupt or truncated pixel data)");
  }
  ZeroInvalid(depth);
  return depth;
}

Status CheckScale(const std::string& path, double depth_scale) {
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale))
    return InvalidArgument(path + ": depth scale must be positive and finite, got " +
                           std::to_string(depth_scale));
  return Status::Ok();
}

}  // namespace

DepthFileType DepthFileTypeOf(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".tif" || ext == ".tiff") return DepthFileType::kTiff;
  if (ext == ".exr") return DepthFileType::kExr;
  return DepthFileType::kPng;
}

const char* DepthFileTypeName(DepthFileType type) {
  switch (type) {
    case DepthFileType::kTiff:
      return "TIFF";
    case DepthFileType::kExr:
      return "EXR";
    case DepthFileType::kPng:
      break;
  }
  return "PNG";
}

std::string DepthFileHeader::Encoding() const {
  return std::to_string(bits) + (metres ? "-bit float " : "-bit ") + DepthFileTypeName(type);
}

Result<DepthFileHeader> ReadDepthHeader(const std::string& path) {
  const DepthFileType type = DepthFileTypeOf(path);
  if (type == DepthFileType::kPng) {
    Result<PngHeader> png = ReadPngHeader(path);
    if (!png.ok()) return png.status();
    if (png->bit_depth != 16 || png->channels != 1 || png->palette)
      return Unsupported(path + ": depth PNG must be 16-bit single-channel gray, found " +
                         std::to_string(png->bit_depth) + "-bit with " +
                         std::to_string(png->channels) + " channel(s)");
    DepthFileHeader header;
    header.width = png->width;
    header.height = png->height;
    return header;
  }
  FileBytes f;
  VOXPLAN_RETURN_IF_ERROR(f.Open(path));
  return ParseHeader(path, type, f);
}

Result<DepthImage> ReadDepthImage(const std::string& path, double depth_scale,
                                  DepthFileHeader* header_out) {
  const DepthFileType type = DepthFileTypeOf(path);
  if (type == DepthFileType::kPng) {
    Result<DepthImage> depth = ReadDepthPng(path, depth_scale);  // refuses all but 16-bit gray
    if (depth.ok() && header_out) {
      *header_out = DepthFileHeader{};
      header_out->width = depth->width;
      header_out->height = depth->height;
    }
    return depth;
  }
  FileBytes f;
  VOXPLAN_RETURN_IF_ERROR(f.Open(path));
  Result<DepthFileHeader> header = ParseHeader(path, type, f);
  if (!header.ok()) return header.status();
  if (!header->metres) VOXPLAN_RETURN_IF_ERROR(CheckScale(path, depth_scale));
  if (header_out) *header_out = *header;
  return type == DepthFileType::kTiff ? DecodeTiff(path, *header, depth_scale)
                                      : DecodeExr(path, *header);
}

}  // namespace voxplan
