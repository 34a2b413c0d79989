#include "io/ply_header.h"

#include <charconv>
#include <sstream>

namespace voxplan::internal::ply {

size_t TypeSize(Type type) {
  switch (type) {
    case Type::kInt8:
    case Type::kUInt8:
      return 1;
    case Type::kInt16:
    case Type::kUInt16:
      return 2;
    case Type::kInt32:
    case Type::kUInt32:
    case Type::kFloat32:
      return 4;
    case Type::kFloat64:
      return 8;
  }
  return 0;
}

bool IsInteger(Type type) { return type != Type::kFloat32 && type != Type::kFloat64; }

namespace {

bool ParseType(const std::string& name, Type* type) {
  static const std::pair<const char*, Type> kNames[] = {
      {"char", Type::kInt8},      {"int8", Type::kInt8},       {"uchar", Type::kUInt8},
      {"uint8", Type::kUInt8},    {"short", Type::kInt16},     {"int16", Type::kInt16},
      {"ushort", Type::kUInt16},  {"uint16", Type::kUInt16},   {"int", Type::kInt32},
      {"int32", Type::kInt32},    {"uint", Type::kUInt32},     {"uint32", Type::kUInt32},
      {"float", Type::kFloat32},  {"float32", Type::kFloat32}, {"double", Type::kFloat64},
      {"float64", Type::kFloat64}};
  for (const auto& [n, t] : kNames)
    if (name == n) {
      *type = t;
      return true;
    }
  return false;
}

std::vector<std::string> Words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

Status LineError(int line, const std::string& reason) {
  return CorruptData("line " + std::to_string(line) + ": " + reason);
}

Status ParseProperty(const std::vector<std::string>& w, int line, Header* header) {
  if (header->elements.empty()) return LineError(line, "property before any element");
  Property p;
  if (w.size() == 5 && w[1] == "list") {
    p.is_list = true;
    if (!ParseType(w[2], &p.count_type) || !ParseType(w[3], &p.type))
      return LineError(line, "unknown list type '" + w[2] + " " + w[3] + "'");
    if (!IsInteger(p.count_type))
      return LineError(line, "list count type '" + w[2] + "' is not an integer type");
    p.name = w[4];
  } else if (w.size() == 3) {
    if (!ParseType(w[1], &p.type)) return LineError(line, "unknown property type '" + w[1] + "'");
    p.name = w[2];
  } else {
    return LineError(line, "malformed property line");
  }
  header->elements.back().properties.push_back(std::move(p));
  return Status::Ok();
}

Status ParseElement(const std::vector<std::string>& w, int line, Header* header) {
  Element e;
  const char* end = w.size() == 3 ? w[2].data() + w[2].size() : nullptr;
  if (!end || std::from_chars(w[2].data(), end, e.count).ptr != end)
    return LineError(line, "malformed element line (expected 'element <name> <count>')");
  e.name = w[1];
  e.header_line = line;
  header->elements.push_back(std::move(e));
  return Status::Ok();
}

Status ParseFormat(const std::vector<std::string>& w, int line, Header* header) {
  if (w.size() != 3 || w[2] != "1.0") return LineError(line, "malformed format line");
  if (w[1] == "ascii")
    header->encoding = Encoding::kAscii;
  else if (w[1] == "binary_little_endian")
    header->encoding = Encoding::kBinaryLittleEndian;
  else if (w[1] == "binary_big_endian")
    header->encoding = Encoding::kBinaryBigEndian;
  else
    return LineError(line, "unknown format '" + w[1] + "'");
  return Status::Ok();
}

}  // namespace

Result<Header> ParseHeader(std::string_view bytes) {
  Header header;
  bool have_format = false;
  size_t pos = 0;
  // Only the first kMaxHeaderBytes are ever searched, however large the file.
  const std::string_view head = bytes.substr(0, kMaxHeaderBytes);
  for (int line = 1;; ++line) {
    const size_t eol = head.find('\n', pos);
    if (eol == std::string_view::npos)
      return CorruptData(bytes.size() <= kMaxHeaderBytes
                             ? "the header ends without an end_header line"
                             : "no end_header line within the first " +
                                   std::to_string(kMaxHeaderBytes) + " bytes");
    std::string text(head.substr(pos, eol - pos));
    if (!text.empty() && text.back() == '\r') text.pop_back();
    pos = eol + 1;
    if (line == 1) {
      if (text != "ply") return CorruptData("not a PLY file (the first line is not 'ply')");
      continue;
    }
    const std::vector<std::string> w = Words(text);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    Status status;
    if (w[0] == "end_header") {
      if (!have_format) return LineError(line, "end_header before the format line");
      header.data_offset = pos;
      header.data_line = line + 1;
      return header;
    } else if (w[0] == "format") {
      status = ParseFormat(w, line, &header);
      have_format = true;
    } else if (w[0] == "element") {
      status = ParseElement(w, line, &header);
    } else if (w[0] == "property") {
      status = ParseProperty(w, line, &header);
    } else {
      status = LineError(line, "unknown header keyword '" + w[0] + "'");
    }
    if (!status.ok()) return status;
  }
}

}  // namespace voxplan::internal::ply
