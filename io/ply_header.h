#pragma once
// Internal to io: the header of a PLY file (Turk's format, as MeshLab, Open3D and voxplan write
// it), parsed and checked before any of the data is touched.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace voxplan::internal::ply {

enum class Encoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };
enum class Type : uint8_t { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

size_t TypeSize(Type type);
bool IsInteger(Type type);

struct Property {
  std::string name;
  Type type = Type::kFloat32;  // a list's item type
  bool is_list = false;
  Type count_type = Type::kUInt8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  int header_line = 0;
};

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  size_t data_offset = 0;  // first byte after the end_header line
  int data_line = 0;       // line number of that byte (ascii messages)
};

// A header larger than this is refused: real ones are a few hundred bytes, and the bound keeps
// a file without end_header from being scanned whole.
constexpr size_t kMaxHeaderBytes = 64 * 1024;

// The header at the start of `bytes`. Errors are reasons without the file name
// ("line 4: unknown property type 'flaot'"); the caller puts the file in front.
Result<Header> ParseHeader(std::string_view bytes);

}  // namespace voxplan::internal::ply
