// The fast path of ReadDepthPng (png_fast.h): chunk walk with every check that could make libpng
// refuse or warn turned into a refusal here, libdeflate for the zlib stream, an SSE2 unfilter.
// On this machine (7-Scenes / ICL-NUIM depth, 640 x 480) inflating is 0.30 / 0.22 ms with
// libdeflate against 1.07 / 0.79 ms with zlib, and the row filters (mostly Paeth, which libpng
// undoes a byte at a time for 2-byte pixels) 1.3 / 0.8 ms scalar.
#include "io/png_fast.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace voxplan::png_fast {

namespace {

// ---------------------------------------------------------------------------------------------
// Row filters.

inline uint8_t Paeth(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  if (pa <= pb && pa <= pc) return uint8_t(a);
  return uint8_t(pb <= pc ? b : c);
}

// One row; `prev` is the row above (zeros for the first row).
bool UnfilterRow(int type, const uint8_t* src, const uint8_t* prev, size_t n, size_t bpp,
                 uint8_t* cur) {
  switch (type) {
    case 0:
      std::memcpy(cur, src, n);
      return true;
    case 1:
      for (size_t i = 0; i < n; ++i) cur[i] = uint8_t(src[i] + (i >= bpp ? cur[i - bpp] : 0));
      return true;
    case 2:
      for (size_t i = 0; i < n; ++i) cur[i] = uint8_t(src[i] + prev[i]);
      return true;
    case 3:
      for (size_t i = 0; i < n; ++i)
        cur[i] = uint8_t(src[i] + (((i >= bpp ? cur[i - bpp] : 0) + prev[i]) >> 1));
      return true;
    case 4:
      for (size_t i = 0; i < n; ++i)
        cur[i] = uint8_t(src[i] +
                         Paeth(i >= bpp ? cur[i - bpp] : 0, prev[i], i >= bpp ? prev[i - bpp] : 0));
      return true;
    default:
      return false;
  }
}

#if defined(__SSE2__)

// Eight rows at once. Row j of the group runs one pixel behind row j - 1: at step s, lane j (its
// two bytes) holds row j's pixel s - j, so its left neighbour is the lane's own result of step
// s - 1, the pixel above is lane j - 1's result of step s - 1 and the one above-left lane
// j - 1's of step s - 2 (lane 0 takes both from the row above the group). Eight steps are done
// per block: the rows' staggered pixels are loaded as eight vectors and transposed, the results
// transposed back and stored. Rows are copied into buffers padded with zero pixels on both sides,
// so pixels left of 0 come out as 0 and no load or store leaves the buffers.
constexpr size_t kGroup = 8;
constexpr size_t kPadPx = 16;  // >= 8 + 7: a block reads and writes up to 15 pixels past a row

inline void Transpose8x16(__m128i v[8]) {
  const __m128i a0 = _mm_unpacklo_epi16(v[0], v[1]), a1 = _mm_unpackhi_epi16(v[0], v[1]);
  const __m128i a2 = _mm_unpacklo_epi16(v[2], v[3]), a3 = _mm_unpackhi_epi16(v[2], v[3]);
  const __m128i a4 = _mm_unpacklo_epi16(v[4], v[5]), a5 = _mm_unpackhi_epi16(v[4], v[5]);
  const __m128i a6 = _mm_unpacklo_epi16(v[6], v[7]), a7 = _mm_unpackhi_epi16(v[6], v[7]);
  const __m128i b0 = _mm_unpacklo_epi32(a0, a2), b1 = _mm_unpackhi_epi32(a0, a2);
  const __m128i b2 = _mm_unpacklo_epi32(a1, a3), b3 = _mm_unpackhi_epi32(a1, a3);
  const __m128i b4 = _mm_unpacklo_epi32(a4, a6), b5 = _mm_unpackhi_epi32(a4, a6);
  const __m128i b6 = _mm_unpacklo_epi32(a5, a7), b7 = _mm_unpackhi_epi32(a5, a7);
  v[0] = _mm_unpacklo_epi64(b0, b4);
  v[1] = _mm_unpackhi_epi64(b0, b4);
  v[2] = _mm_unpacklo_epi64(b1, b5);
  v[3] = _mm_unpackhi_epi64(b1, b5);
  v[4] = _mm_unpacklo_epi64(b2, b6);
  v[5] = _mm_unpackhi_epi64(b2, b6);
  v[6] = _mm_unpacklo_epi64(b3, b7);
  v[7] = _mm_unpackhi_epi64(b3, b7);
}

inline __m128i Abs16(__m128i v) { return _mm_max_epi16(v, _mm_sub_epi16(_mm_setzero_si128(), v)); }

// The Paeth predictor of eight 16-bit lanes (bytes widened), as Paeth() above.
inline __m128i Paeth16(__m128i a, __m128i b, __m128i c) {
  const __m128i b_c = _mm_sub_epi16(b, c), a_c = _mm_sub_epi16(a, c);
  const __m128i pa = Abs16(b_c), pb = Abs16(a_c), pc = Abs16(_mm_add_epi16(b_c, a_c));
  const __m128i not_a = _mm_or_si128(_mm_cmpgt_epi16(pa, pb), _mm_cmpgt_epi16(pa, pc));
  const __m128i not_b = _mm_cmpgt_epi16(pb, pc);
  const __m128i b_or_c = _mm_or_si128(_mm_and_si128(not_b, c), _mm_andnot_si128(not_b, b));
  return _mm_or_si128(_mm_and_si128(not_a, b_or_c), _mm_andnot_si128(not_a, a));
}

struct GroupMasks {
  __m128i sub, up, avg, paeth;
};

// The predictor of every lane for its row's filter type (none: 0).
template <bool kAnyAvg, bool kAnyPaeth>
inline __m128i Predict(__m128i a, __m128i b, __m128i c, const GroupMasks& m) {
  __m128i pred = _mm_or_si128(_mm_and_si128(m.sub, a), _mm_and_si128(m.up, b));
  if constexpr (kAnyAvg) {
    // floor((a + b) / 2): avg_epu8 rounds up, so take the lost low bit back.
    const __m128i avg =
        _mm_sub_epi8(_mm_avg_epu8(a, b), _mm_and_si128(_mm_xor_si128(a, b), _mm_set1_epi8(1)));
    pred = _mm_or_si128(pred, _mm_and_si128(m.avg, avg));
  }
  if constexpr (kAnyPaeth) {
    const __m128i z = _mm_setzero_si128();
    const __m128i lo =
        Paeth16(_mm_unpacklo_epi8(a, z), _mm_unpacklo_epi8(b, z), _mm_unpacklo_epi8(c, z));
    const __m128i hi =
        Paeth16(_mm_unpackhi_epi8(a, z), _mm_unpackhi_epi8(b, z), _mm_unpackhi_epi8(c, z));
    pred = _mm_or_si128(pred, _mm_and_si128(m.paeth, _mm_packus_epi16(lo, hi)));
  }
  return pred;
}

inline __m128i LoadPixel(const uint8_t* p) {
  uint16_t v;
  std::memcpy(&v, p, 2);
  return _mm_cvtsi32_si128(int(v));
}

// One group: `in` and `out` hold kGroup padded rows of `padded` bytes (pixel 0 at byte
// 2 * kPadPx), `above` the padded row above the group.
template <bool kAnyAvg, bool kAnyPaeth>
void UnfilterGroup(const uint8_t* in, const uint8_t* above, size_t padded, size_t width,
                   const GroupMasks& m, uint8_t* out) {
  __m128i left = _mm_setzero_si128(), left2 = _mm_setzero_si128();  // steps s - 1, s - 2
  const uint8_t* above0 = above + 2 * kPadPx;
  for (size_t s0 = 0; s0 < width + kGroup - 1; s0 += kGroup) {
    __m128i v[kGroup];
    for (size_t j = 0; j < kGroup; ++j)
      v[j] = _mm_loadu_si128(
          reinterpret_cast<const __m128i*>(in + j * padded + 2 * (kPadPx + s0 - j)));
    Transpose8x16(v);  // v[k]: step s0 + k, lane j = row j's pixel s0 + k - j
    for (size_t k = 0; k < kGroup; ++k) {
      const size_t s = s0 + k;
      const __m128i b = _mm_or_si128(_mm_slli_si128(left, 2), LoadPixel(above0 + 2 * s));
      const __m128i c = _mm_or_si128(_mm_slli_si128(left2, 2), LoadPixel(above0 + 2 * s - 2));
      const __m128i r = _mm_add_epi8(v[k], Predict<kAnyAvg, kAnyPaeth>(left, b, c, m));
      left2 = left;
      left = r;
      v[k] = r;
    }
    Transpose8x16(v);  // v[j]: row j's pixels s0 - j .. s0 - j + 7
    for (size_t j = 0; j < kGroup; ++j)
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + j * padded + 2 * (kPadPx + s0 - j)), v[j]);
  }
}

bool UnfilterGray16Sse2(const uint8_t* filtered, size_t width, size_t height, uint8_t* out) {
  const size_t row_bytes = 2 * width, padded = 2 * (width + 2 * kPadPx);
  // in: the group's rows; rows: the group's results; above: the row above (zeros at first).
  std::unique_ptr<uint8_t[]> buffers(new uint8_t[(2 * kGroup + 1) * padded]());
  uint8_t* in = buffers.get();
  uint8_t* rows = in + kGroup * padded;
  uint8_t* above = rows + kGroup * padded;
  size_t y = 0;
  for (; y + kGroup <= height; y += kGroup) {
    GroupMasks m{_mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128(),
                 _mm_setzero_si128()};
    bool any_avg = false, any_paeth = false;
    for (size_t j = 0; j < kGroup; ++j) {
      const uint8_t* src = filtered + (y + j) * (row_bytes + 1);
      const int type = src[0];
      if (type > 4) return false;
      std::memcpy(in + j * padded + 2 * kPadPx, src + 1, row_bytes);
      // Lane j is bytes 2j and 2j + 1.
      alignas(16) uint16_t bits[kGroup] = {};
      bits[j] = 0xffff;
      const __m128i lane_mask = _mm_load_si128(reinterpret_cast<const __m128i*>(bits));
      if (type == 1) m.sub = _mm_or_si128(m.sub, lane_mask);
      if (type == 2) m.up = _mm_or_si128(m.up, lane_mask);
      if (type == 3) m.avg = _mm_or_si128(m.avg, lane_mask);
      if (type == 4) m.paeth = _mm_or_si128(m.paeth, lane_mask);
      any_avg |= type == 3;
      any_paeth |= type == 4;
    }
    if (any_paeth && any_avg)
      UnfilterGroup<true, true>(in, above, padded, width, m, rows);
    else if (any_paeth)
      UnfilterGroup<false, true>(in, above, padded, width, m, rows);
    else if (any_avg)
      UnfilterGroup<true, false>(in, above, padded, width, m, rows);
    else
      UnfilterGroup<false, false>(in, above, padded, width, m, rows);
    for (size_t j = 0; j < kGroup; ++j)
      std::memcpy(out + (y + j) * row_bytes, rows + j * padded + 2 * kPadPx, row_bytes);
    // The last row is the next group's row above; its padding must stay zero on the left (the
    // results left of pixel 0 are 0) and is never read on the right beyond results past the row.
    std::memcpy(above, rows + (kGroup - 1) * padded, padded);
  }
  // The last rows one by one.
  for (; y < height; ++y) {
    const uint8_t* src = filtered + y * (row_bytes + 1);
    const uint8_t* prev = y > 0 ? out + (y - 1) * row_bytes : above + 2 * kPadPx;
    if (!UnfilterRow(src[0], src + 1, prev, row_bytes, 2, out + y * row_bytes)) return false;
  }
  return true;
}

#endif  // __SSE2__

// ---------------------------------------------------------------------------------------------
// Chunks.

constexpr uint8_t kSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
// Ancillary chunks larger than this, or more of them, are left to libpng (it refuses chunks
// over 8 MB and caches a limited number).
constexpr uint32_t kMaxAncillaryBytes = 1u << 20;
constexpr int kMaxAncillaryChunks = 64;

inline uint32_t Be32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

inline bool IsLetter(uint8_t c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

struct LibdeflateDecompressor {
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  LibdeflateDecompressor() = default;
  LibdeflateDecompressor(const LibdeflateDecompressor&) = delete;
  LibdeflateDecompressor& operator=(const LibdeflateDecompressor&) = delete;
  ~LibdeflateDecompressor() {
    if (d) libdeflate_free_decompressor(d);
  }
};

// What a decode needs beyond the image: the inflater, the filtered rows, the unfiltered samples.
struct Scratch {
  LibdeflateDecompressor inflater;
  std::vector<uint8_t> raw, samples;
};

}  // namespace

bool UnfilterScalar(const uint8_t* filtered, size_t row_bytes, size_t height, int bpp,
                    uint8_t* out) {
  std::vector<uint8_t> zeros(row_bytes, 0);
  for (size_t y = 0; y < height; ++y) {
    const uint8_t* src = filtered + y * (row_bytes + 1);
    const uint8_t* prev = y > 0 ? out + (y - 1) * row_bytes : zeros.data();
    if (!UnfilterRow(src[0], src + 1, prev, row_bytes, size_t(bpp), out + y * row_bytes))
      return false;
  }
  return true;
}

bool UnfilterGray16(const uint8_t* filtered, size_t width, size_t height, uint8_t* out) {
#if defined(__SSE2__)
  return UnfilterGray16Sse2(filtered, width, height, out);
#else
  return UnfilterScalar(filtered, 2 * width, height, 2, out);
#endif
}

void BigEndianToMetres(const uint8_t* samples, size_t count, double depth_scale, float* out) {
  const double inv_scale = 1.0 / depth_scale;
  size_t i = 0;
#if defined(__SSE2__)
  // The scalar arithmetic exactly: a double multiply, then rounding to float.
  const __m128d inv = _mm_set1_pd(inv_scale);
  const __m128i z = _mm_setzero_si128();
  for (; i + 8 <= count; i += 8) {
    const __m128i be = _mm_loadu_si128(reinterpret_cast<const __m128i*>(samples + 2 * i));
    const __m128i v = _mm_or_si128(_mm_slli_epi16(be, 8), _mm_srli_epi16(be, 8));
    const __m128i lo = _mm_unpacklo_epi16(v, z), hi = _mm_unpackhi_epi16(v, z);
    const __m128 f0 =
        _mm_movelh_ps(_mm_cvtpd_ps(_mm_mul_pd(_mm_cvtepi32_pd(lo), inv)),
                      _mm_cvtpd_ps(_mm_mul_pd(_mm_cvtepi32_pd(_mm_shuffle_epi32(lo, 0x4e)), inv)));
    const __m128 f1 =
        _mm_movelh_ps(_mm_cvtpd_ps(_mm_mul_pd(_mm_cvtepi32_pd(hi), inv)),
                      _mm_cvtpd_ps(_mm_mul_pd(_mm_cvtepi32_pd(_mm_shuffle_epi32(hi, 0x4e)), inv)));
    _mm_storeu_ps(out + i, f0);
    _mm_storeu_ps(out + i + 4, f1);
  }
#endif
  for (; i < count; ++i) {
    const unsigned v = (unsigned(samples[2 * i]) << 8) | unsigned(samples[2 * i + 1]);
    out[i] = float(double(v) * inv_scale);
  }
}

bool DecodeDepthPng(const uint8_t* file, size_t size, int max_side, double depth_scale,
                    DepthImage& depth) {
  if (size < 8 + 25 || std::memcmp(file, kSignature, 8) != 0) return false;
  size_t pos = 8;
  uint32_t width = 0, height = 0;
  bool have_ihdr = false, idat_done = false, have_iend = false;
  int ancillary = 0;
  // The IDAT stream: in place when there is one chunk, else gathered.
  const uint8_t* stream = nullptr;
  size_t stream_bytes = 0;
  std::vector<uint8_t> gathered;
  size_t raw_bytes = 0;
  while (!have_iend) {
    if (size - pos < 12) return false;  // no IEND: libpng refuses a truncated file
    const uint32_t length = Be32(file + pos);
    const uint8_t* type = file + pos + 4;
    if (length > 0x7fffffffu || length > size - pos - 12) return false;
    const uint8_t* data = type + 4;
    if (!IsLetter(type[0]) || !IsLetter(type[1]) || !IsLetter(type[2]) || !IsLetter(type[3]) ||
        (type[2] & 0x20))
      return false;
    if (libdeflate_crc32(0, type, size_t(length) + 4) != Be32(data + length)) return false;
    const bool critical = !(type[0] & 0x20);
    if (!have_ihdr) {
      // IHDR first: 16-bit gray, deflate, standard filters, not interlaced.
      if (std::memcmp(type, "IHDR", 4) != 0 || length != 13) return false;
      width = Be32(data);
      height = Be32(data + 4);
      if (width == 0 || height == 0 || width > uint32_t(max_side) || height > uint32_t(max_side))
        return false;
      if (data[8] != 16 || data[9] != 0 || data[10] != 0 || data[11] != 0 || data[12] != 0)
        return false;
      have_ihdr = true;
      raw_bytes = size_t(height) * (2 * size_t(width) + 1);
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      // IDATs apart, or one over libpng's limit (its bound is never below this one).
      if (idat_done || length > raw_bytes + 6 + 5 * (size_t(height) + 1)) return false;
      if (stream_bytes == 0 && gathered.empty()) {
        stream = data;
      } else {
        if (gathered.empty()) gathered.assign(stream, stream + stream_bytes);
        gathered.insert(gathered.end(), data, data + length);
        stream = gathered.data();
      }
      stream_bytes += length;
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      if (length != 0) return false;
      have_iend = true;
    } else if (critical || length > kMaxAncillaryBytes || ++ancillary > kMaxAncillaryChunks) {
      return false;  // PLTE or an unknown critical chunk, or an odd ancillary one
    }
    if (stream_bytes > 0 && std::memcmp(type, "IDAT", 4) != 0) idat_done = true;
    pos += 12 + size_t(length);
  }
  if (stream_bytes < 2) return false;
  // zlib header: deflate with a 32 KiB window (libpng enforces a smaller declared window,
  // libdeflate would not), no preset dictionary.
  const uint8_t cmf = stream[0], flg = stream[1];
  if (cmf != 0x78 || (flg & 0x20) || ((unsigned(cmf) << 8) | flg) % 31 != 0) return false;

  // Per-thread buffers, kept from frame to frame: fresh ones cost more in page faults than the
  // decoding itself (2.5 against 1.2 ms per 7-Scenes frame).
  thread_local Scratch scratch;
  if (!scratch.inflater.d) return false;
  const size_t pixels = size_t(width) * size_t(height);
  if (scratch.raw.size() < raw_bytes) scratch.raw.resize(raw_bytes);
  if (scratch.samples.size() < 2 * pixels) scratch.samples.resize(2 * pixels);
  size_t consumed = 0;
  // Exactly the rows (no shorter or longer stream) and no bytes after the stream.
  if (libdeflate_zlib_decompress_ex(scratch.inflater.d, stream, stream_bytes, scratch.raw.data(),
                                    raw_bytes, &consumed, nullptr) != LIBDEFLATE_SUCCESS ||
      consumed != stream_bytes)
    return false;
  if (!UnfilterGray16(scratch.raw.data(), width, height, scratch.samples.data())) return false;
  DepthImage image(static_cast<int>(width), static_cast<int>(height));
  BigEndianToMetres(scratch.samples.data(), pixels, depth_scale, image.data.data());
  depth = std::move(image);
  return true;
}

}  // namespace voxplan::png_fast
