#include "io/ply_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "io/file_util.h"
#include "io/ply_header.h"
#include "io/ply_values.h"

namespace voxplan::internal {

namespace {

using ply::Element;
using ply::Header;
using ply::Property;
using ply::Type;

// What a vertex property is for; kSkip for everything voxplan does not read.
enum Slot { kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kSkip };

Slot VertexSlot(const std::string& name) {
  static const std::pair<const char*, Slot> kNames[] = {
      {"x", kX},     {"y", kY},         {"z", kZ},       {"nx", kNx}, {"ny", kNy},   {"nz", kNz},
      {"red", kRed}, {"green", kGreen}, {"blue", kBlue}, {"r", kRed}, {"g", kGreen}, {"b", kBlue}};
  for (const auto& [n, s] : kNames)
    if (name == n) return s;
  return kSkip;
}

bool IsIndexList(const Property& p) {
  return p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
}

// How the two elements voxplan reads are laid out; the others are skipped.
struct Layout {
  int vertex = -1, face = -1;      // element indices
  std::vector<Slot> vertex_slots;  // one per vertex property
  std::vector<Type> slot_type = std::vector<Type>(kSkip, Type::kFloat32);
  bool has_normals = false, has_colors = false;
  int index_list = -1;  // property index within the face element
};

Result<Layout> FindLayout(const Header& header) {
  Layout l;
  for (size_t e = 0; e < header.elements.size(); ++e) {
    if (header.elements[e].name == "vertex" && l.vertex < 0) l.vertex = int(e);
    if (header.elements[e].name == "face" && l.face < 0) l.face = int(e);
  }
  if (l.vertex < 0) return CorruptData("the header declares no vertex element");
  bool seen[kSkip] = {};
  for (const Property& p : header.elements[l.vertex].properties) {
    const Slot s = p.is_list ? kSkip : VertexSlot(p.name);
    if (s != kSkip) {
      if (seen[s]) return CorruptData("vertex property '" + p.name + "' is declared twice");
      seen[s] = true;
      l.slot_type[s] = p.type;
    }
    l.vertex_slots.push_back(s);
  }
  if (!seen[kX] || !seen[kY] || !seen[kZ])
    return CorruptData("the vertex element lacks one of the properties x, y, z");
  l.has_normals = seen[kNx] && seen[kNy] && seen[kNz];
  l.has_colors = seen[kRed] && seen[kGreen] && seen[kBlue];
  if (header.elements[l.vertex].count > uint64_t(UINT32_MAX))
    return Unsupported("more vertices than 32-bit indices can address");
  if (l.face < 0) return CorruptData("the header declares no face element (no triangles)");
  const auto& props = header.elements[l.face].properties;
  for (size_t p = 0; p < props.size(); ++p)
    if (IsIndexList(props[p]) && l.index_list < 0) l.index_list = int(p);
  if (l.index_list < 0) return CorruptData("the face element has no list property vertex_indices");
  if (!ply::IsInteger(props[l.index_list].type))
    return CorruptData("face indices are declared as floating point");
  return l;
}

// The fewest bytes one record of `e` can take: binary sizes, or for ascii one character and one
// separator per value. The face index list counts with its minimum of three entries.
uint64_t MinRecordBytes(const Element& e, bool ascii, const Property* index_list) {
  uint64_t bytes = 0;
  for (const Property& p : e.properties) {
    const uint64_t items = &p == index_list ? 3 : 0;
    if (ascii)
      bytes += 2 * (1 + (p.is_list ? items : 0));
    else
      bytes += p.is_list ? ply::TypeSize(p.count_type) + items * ply::TypeSize(p.type)
                         : ply::TypeSize(p.type);
  }
  return bytes;
}

// Every declared count must fit in the bytes after the header before anything is reserved.
Status CheckCounts(const Header& header, const Layout& layout, uint64_t data_bytes) {
  const bool ascii = header.encoding == ply::Encoding::kAscii;
  const uint64_t available = data_bytes + (ascii ? 1 : 0);  // the last value needs no separator
  uint64_t need = 0;
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& el = header.elements[e];
    const Property* list =
        int(e) == layout.face ? &el.properties[size_t(layout.index_list)] : nullptr;
    const uint64_t record = MinRecordBytes(el, ascii, list);
    if (record == 0) continue;  // no properties: the element holds no data
    if (el.count > (available - need) / record)
      return CorruptData("element '" + el.name + "' (header line " +
                         std::to_string(el.header_line) + ") declares " + std::to_string(el.count) +
                         " records of at least " + std::to_string(record) + " bytes, but only " +
                         std::to_string(data_bytes) + " bytes follow the header");
    need += el.count * record;
  }
  return Status::Ok();
}

// Integers as colour channels are scaled by their type's maximum, as assimp did.
float ColorChannel(double v, Type type) {
  double max = 1.0;
  switch (type) {
    case Type::kInt8:
      max = 127.0;
      break;
    case Type::kUInt8:
      max = 255.0;
      break;
    case Type::kInt16:
      max = 32767.0;
      break;
    case Type::kUInt16:
      max = 65535.0;
      break;
    case Type::kInt32:
      max = 2147483647.0;
      break;
    case Type::kUInt32:
      max = 4294967295.0;
      break;
    default:
      break;
  }
  return float(v / max);
}

uint8_t ToByte(float c) {
  if (!std::isfinite(c)) return 0;
  return uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
}

template <typename Source>
class BodyReader {
 public:
  BodyReader(Source& source, const Header& header, const Layout& layout)
      : src_(source), header_(header), layout_(layout) {}

  Status Read(Mesh* mesh) {
    for (size_t e = 0; e < header_.elements.size(); ++e) {
      const Element& el = header_.elements[e];
      if (el.properties.empty()) continue;
      if (int(e) == layout_.vertex) mesh->positions.reserve(el.count);
      if (int(e) == layout_.face) mesh->triangles.reserve(el.count);
      for (uint64_t r = 0; r < el.count; ++r) {
        Status s = int(e) == layout_.vertex ? ReadVertex(r, mesh)
                   : int(e) == layout_.face ? ReadFace(r, mesh)
                                            : SkipRecord(el);
        if (!s.ok()) return s;
      }
    }
    return Status::Ok();
  }

 private:
  Status Fail(const std::string& what, uint64_t record, const std::string& reason) const {
    return CorruptData(src_.Where() + ": " + what + " " + std::to_string(record) + ": " + reason);
  }
  bool Value(Type type, double* v) { return src_.Read(type, v); }

  bool SkipList(const Property& p) {
    double n = 0.0, v = 0.0;
    if (!Value(p.count_type, &n) || n < 0) return false;
    for (double i = 0; i < n; ++i)  // bounded by the file: each value consumes bytes
      if (!Value(p.type, &v)) return false;
    return true;
  }

  Status SkipRecord(const Element& el) {
    double v = 0.0;
    for (const Property& p : el.properties)
      if (p.is_list ? !SkipList(p) : !Value(p.type, &v))
        return CorruptData(src_.Where() + ": element '" + el.name + "': " + src_.Error());
    return Status::Ok();
  }

  Status ReadVertex(uint64_t r, Mesh* mesh) {
    const auto& props = header_.elements[size_t(layout_.vertex)].properties;
    double v[kSkip] = {};
    for (size_t p = 0; p < props.size(); ++p) {
      const Slot s = layout_.vertex_slots[p];
      double skipped = 0.0;
      const bool ok = props[p].is_list ? SkipList(props[p])
                      : s == kSkip     ? Value(props[p].type, &skipped)
                                       : Value(props[p].type, &v[s]);
      if (!ok) return Fail("vertex", r, src_.Error());
    }
    const Eigen::Vector3f pos{float(v[kX]), float(v[kY]), float(v[kZ])};
    if (!pos.allFinite())
      return Fail("vertex", r,
                  "coordinates (" + std::to_string(v[kX]) + ", " + std::to_string(v[kY]) + ", " +
                      std::to_string(v[kZ]) + ") are not finite floats");
    mesh->positions.push_back(pos);
    if (layout_.has_normals)
      mesh->normals.emplace_back(float(v[kNx]), float(v[kNy]), float(v[kNz]));
    if (layout_.has_colors)
      mesh->colors.push_back({ToByte(ColorChannel(v[kRed], layout_.slot_type[kRed])),
                              ToByte(ColorChannel(v[kGreen], layout_.slot_type[kGreen])),
                              ToByte(ColorChannel(v[kBlue], layout_.slot_type[kBlue]))});
    return Status::Ok();
  }

  Status ReadFace(uint64_t r, Mesh* mesh) {
    const auto& props = header_.elements[size_t(layout_.face)].properties;
    const uint64_t num_vertices = header_.elements[size_t(layout_.vertex)].count;
    for (size_t p = 0; p < props.size(); ++p) {
      if (int(p) != layout_.index_list) {
        double v = 0.0;
        if (props[p].is_list ? !SkipList(props[p]) : !Value(props[p].type, &v))
          return Fail("face", r, src_.Error());
        continue;
      }
      double n = 0.0;
      if (!Value(props[p].count_type, &n)) return Fail("face", r, src_.Error());
      if (n < 3 || n > kMaxPolygonVertices)
        return Fail("face", r,
                    "has " + std::to_string(int64_t(n)) + " vertex indices (a face needs 3 to " +
                        std::to_string(kMaxPolygonVertices) + ")");
      corners_.clear();
      for (int k = 0; k < int(n); ++k) {
        double index = 0.0;
        if (!Value(props[p].type, &index)) return Fail("face", r, src_.Error());
        if (index < 0 || index >= double(num_vertices))
          return Fail("face", r,
                      "vertex index " + std::to_string(int64_t(index)) + " is out of range (" +
                          std::to_string(num_vertices) + " vertices)");
        corners_.push_back(uint32_t(index));
      }
      for (size_t k = 1; k + 1 < corners_.size(); ++k)  // fan: (0, k, k+1)
        mesh->triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
    }
    return Status::Ok();
  }

  Source& src_;
  const Header& header_;
  const Layout& layout_;
  std::vector<uint32_t> corners_;
};

// A vertex's attributes as bytes, for merging equal vertices.
struct VertexKey {
  std::array<char, 27> bytes{};
  bool operator==(const VertexKey& o) const { return bytes == o.bytes; }
};
struct VertexKeyHash {
  size_t operator()(const VertexKey& k) const {
    return std::hash<std::string_view>()(std::string_view(k.bytes.data(), k.bytes.size()));
  }
};

VertexKey KeyOf(const Mesh& mesh, size_t v) {
  VertexKey key;
  std::memcpy(key.bytes.data(), mesh.positions[v].data(), 12);
  if (!mesh.normals.empty()) std::memcpy(key.bytes.data() + 12, mesh.normals[v].data(), 12);
  if (!mesh.colors.empty()) std::memcpy(key.bytes.data() + 24, mesh.colors[v].data(), 3);
  return key;
}

// Drops unused vertices and merges equal ones, keeping file order (see ReadPly).
void CompactVertices(Mesh* mesh) {
  std::vector<char> used(mesh->num_vertices(), 0);
  for (const auto& t : mesh->triangles)
    for (uint32_t i : t) used[i] = 1;
  std::vector<uint32_t> remap(mesh->num_vertices(), 0);
  std::unordered_map<VertexKey, uint32_t, VertexKeyHash> first;
  Mesh out;
  for (size_t v = 0; v < mesh->num_vertices(); ++v) {
    if (!used[v]) continue;
    const auto [it, inserted] = first.try_emplace(KeyOf(*mesh, v), uint32_t(out.num_vertices()));
    remap[v] = it->second;
    if (!inserted) continue;
    out.positions.push_back(mesh->positions[v]);
    if (!mesh->normals.empty()) out.normals.push_back(mesh->normals[v]);
    if (!mesh->colors.empty()) out.colors.push_back(mesh->colors[v]);
  }
  for (auto& t : mesh->triangles)
    for (uint32_t& i : t) i = remap[i];
  out.triangles = std::move(mesh->triangles);
  *mesh = std::move(out);
}

Result<Mesh> ParsePly(std::string_view bytes) {
  Result<Header> header = ply::ParseHeader(bytes);
  if (!header.ok()) return header.status();
  Result<Layout> layout = FindLayout(*header);
  if (!layout.ok()) return layout.status();
  const std::string_view data = bytes.substr(header->data_offset);
  VOXPLAN_RETURN_IF_ERROR(CheckCounts(*header, *layout, data.size()));
  Mesh mesh;
  if (header->encoding == ply::Encoding::kAscii) {
    ply::AsciiSource source(data, header->data_line);
    VOXPLAN_RETURN_IF_ERROR(BodyReader(source, *header, *layout).Read(&mesh));
  } else {
    ply::BinarySource source(data, header->encoding == ply::Encoding::kBinaryBigEndian);
    VOXPLAN_RETURN_IF_ERROR(BodyReader(source, *header, *layout).Read(&mesh));
  }
  if (mesh.triangles.empty()) return CorruptData("the file holds no triangles");
  CompactVertices(&mesh);
  return mesh;
}

}  // namespace

Result<Mesh> ReadPly(const std::string& path) {
  Result<std::string> bytes = ReadFileToString(path);
  if (!bytes.ok()) return bytes.status();
  Result<Mesh> mesh = ParsePly(*bytes);
  if (!mesh.ok()) return mesh.status().WithContext(path);
  return mesh;
}

}  // namespace voxplan::internal
