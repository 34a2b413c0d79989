#pragma once
// Internal to io: where ply_reader.cpp takes the values of a PLY body from. Both sources
// refuse rather than guess: a read past the end or a malformed token is an error, never zero.
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "io/ply_header.h"

namespace voxplan::internal::ply {

// Binary data of either byte order.
class BinarySource {
 public:
  BinarySource(std::string_view data, bool big_endian)
      : data_(data), swap_(big_endian != (std::endian::native == std::endian::big)) {}

  // False at the end of the data (the value is then untouched).
  bool Read(Type type, double* value) {
    const size_t n = TypeSize(type);
    if (data_.size() - offset_ < n) return false;
    unsigned char b[8];
    std::memcpy(b, data_.data() + offset_, n);
    offset_ += n;
    if (swap_)
      for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    *value = Decode(type, b);
    return true;
  }
  std::string Where() const { return "at byte " + std::to_string(offset_) + " of the data"; }
  std::string Error() const { return "the file ends in the middle of a record"; }

 private:
  static double Decode(Type type, const unsigned char* b) {
    switch (type) {
      case Type::kInt8:
        return As<int8_t>(b);
      case Type::kUInt8:
        return As<uint8_t>(b);
      case Type::kInt16:
        return As<int16_t>(b);
      case Type::kUInt16:
        return As<uint16_t>(b);
      case Type::kInt32:
        return As<int32_t>(b);
      case Type::kUInt32:
        return As<uint32_t>(b);
      case Type::kFloat32:
        return As<float>(b);
      case Type::kFloat64:
        return As<double>(b);
    }
    return 0.0;
  }
  template <typename T>
  static double As(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof(T));
    return double(v);
  }

  std::string_view data_;
  size_t offset_ = 0;
  bool swap_;
};

// ascii data: whitespace-separated numbers, records usually one per line (not required).
class AsciiSource {
 public:
  AsciiSource(std::string_view data, int first_line) : data_(data), line_(first_line) {}

  // False at the end of the data or on a token that is not a number of `type`.
  bool Read(Type type, double* value) {
    while (offset_ < data_.size() && IsSpace(data_[offset_]))
      if (data_[offset_++] == '\n') ++line_;
    size_t end = offset_;
    while (end < data_.size() && !IsSpace(data_[end])) ++end;
    const std::string_view token = data_.substr(offset_, end - offset_);
    offset_ = end;
    if (token.empty()) {
      error_ = "the file ends in the middle of a record";
      return false;
    }
    double v = 0.0;
    const auto [p, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || p != token.data() + token.size() || !FitsType(type, v)) {
      // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + std::string(...).
      error_.assign(1, '\'');
      error_.append(token.substr(0, 40));
      error_.append("' is not a value of the declared type");
      return false;
    }
    *value = v;
    return true;
  }
  std::string Where() const { return "line " + std::to_string(line_); }
  const std::string& Error() const { return error_; }

 private:
  static bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  static bool FitsType(Type type, double v) {
    if (!IsInteger(type)) return true;  // non-finite floats are judged by what they are for
    if (v != std::floor(v)) return false;
    switch (type) {
      case Type::kInt8:
        return v >= -128 && v <= 127;
      case Type::kUInt8:
        return v >= 0 && v <= 255;
      case Type::kInt16:
        return v >= -32768 && v <= 32767;
      case Type::kUInt16:
        return v >= 0 && v <= 65535;
      case Type::kInt32:
        return v >= -2147483648.0 && v <= 2147483647.0;
      default:
        return v >= 0 && v <= 4294967295.0;
    }
  }

  std::string_view data_;
  size_t offset_ = 0;
  int line_;
  std::string error_;
};

}  // namespace voxplan::internal::ply
