#include "io/glb_check.h"

#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace voxplan::internal {

namespace {

using nlohmann::json;

constexpr uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr uint32_t kBinChunk = 0x004E4942;   // "BIN\0"

uint32_t U32(std::string_view b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);  // glTF is little-endian, as is every machine voxplan runs on
  return v;
}

// A non-negative integer member (absent: `fallback`), or -1 when it is not one.
int64_t Int(const json& j, const char* key, int64_t fallback = -1) {
  if (!j.is_object() || !j.contains(key)) return fallback;
  const json& v = j[key];
  if (v.is_number_unsigned())
    return v.get<uint64_t>() > (uint64_t(1) << 53) ? -1 : v.get<int64_t>();
  return -1;
}

const json& Array(const json& doc, const char* key) {
  static const json kEmpty = json::array();
  return doc.contains(key) && doc[key].is_array() ? doc[key] : kEmpty;
}

Status Bad(const std::string& what) { return CorruptData("GLB: " + what); }

// An index member that must name one of `n` entries when present.
Status Ref(const json& j, const char* key, size_t n, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) return Status::Ok();
  const int64_t i = Int(j, key);
  if (i < 0 || uint64_t(i) >= n)
    return Bad(where + "." + key + " = " + j[key].dump() + " names none of the " +
               std::to_string(n) + " entries");
  return Status::Ok();
}

int64_t ComponentSize(int64_t type) {
  switch (type) {
    case 5120:
    case 5121:
      return 1;
    case 5122:
    case 5123:
      return 2;
    case 5125:
    case 5126:
      return 4;
    default:
      return -1;
  }
}

int64_t Components(const std::string& type) {
  static const std::pair<const char*, int64_t> kTypes[] = {
      {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT2", 4}, {"MAT3", 9}, {"MAT4", 16}};
  for (const auto& [name, n] : kTypes)
    if (type == name) return n;
  return -1;
}

Status CheckBuffers(const json& doc, uint64_t bin_bytes, std::vector<int64_t>* view_bytes) {
  const json& buffers = Array(doc, "buffers");
  std::vector<int64_t> buffer_bytes;
  for (size_t b = 0; b < buffers.size(); ++b) {
    const int64_t n = Int(buffers[b], "byteLength");
    const bool in_bin = b == 0 && !buffers[b].contains("uri");
    if (n < 0 || (in_bin && uint64_t(n) > bin_bytes))
      return Bad("buffers[" + std::to_string(b) + "].byteLength is missing, negative or larger " +
                 "than the BIN chunk (" + std::to_string(bin_bytes) + " bytes)");
    buffer_bytes.push_back(n);
  }
  const json& views = Array(doc, "bufferViews");
  for (size_t v = 0; v < views.size(); ++v) {
    const std::string where = "bufferViews[" + std::to_string(v) + "]";
    VOXPLAN_RETURN_IF_ERROR(Ref(views[v], "buffer", buffers.size(), where));
    const int64_t buffer = Int(views[v], "buffer"), offset = Int(views[v], "byteOffset", 0),
                  length = Int(views[v], "byteLength");
    if (buffer < 0 || offset < 0 || length < 0 || offset + length > buffer_bytes[size_t(buffer)])
      return Bad(where + " lies outside its buffer");
    view_bytes->push_back(length);
  }
  return Status::Ok();
}

// `count` elements of `element` bytes each, `stride` apart, from `offset` in view `view`.
Status CheckRange(const json& views, const std::vector<int64_t>& view_bytes, int64_t view,
                  int64_t offset, int64_t count, int64_t element, const std::string& where) {
  if (view < 0 || uint64_t(view) >= view_bytes.size() || offset < 0 || count < 0)
    return Bad(where + ": bad bufferView, byteOffset or count");
  const int64_t stride = Int(views[size_t(view)], "byteStride", element);
  if (stride < element || stride > 252) return Bad(where + ": bad byteStride");
  if (count > 0 && (count - 1) > (view_bytes[size_t(view)] - offset - element) / stride)
    return Bad(where + ": " + std::to_string(count) + " elements run past the end of bufferViews[" +
               std::to_string(view) + "]");
  if (count > 0 && offset + element > view_bytes[size_t(view)])
    return Bad(where + " runs past the end of bufferViews[" + std::to_string(view) + "]");
  return Status::Ok();
}

Status CheckAccessors(const json& doc, const std::vector<int64_t>& view_bytes, size_t file_bytes) {
  const json& views = Array(doc, "bufferViews");
  const json& accessors = Array(doc, "accessors");
  for (size_t a = 0; a < accessors.size(); ++a) {
    const json& acc = accessors[a];
    const std::string where = "accessors[" + std::to_string(a) + "]";
    const int64_t size = ComponentSize(Int(acc, "componentType"));
    const int64_t n = acc.contains("type") && acc["type"].is_string()
                          ? Components(acc["type"].get<std::string>())
                          : -1;
    const int64_t count = Int(acc, "count");
    if (size < 0 || n < 0 || count < 0) return Bad(where + ": bad componentType, type or count");
    if (acc.contains("bufferView"))
      VOXPLAN_RETURN_IF_ERROR(CheckRange(views, view_bytes, Int(acc, "bufferView"),
                                         Int(acc, "byteOffset", 0), count, size * n, where));
    else if (uint64_t(count) > file_bytes)  // zeros, allocated by assimp: no larger than the file
      return Bad(where + ": " + std::to_string(count) + " elements without a bufferView");
    if (!acc.contains("sparse")) continue;
    const json& sparse = acc["sparse"];
    const int64_t sparse_count = Int(sparse, "count");
    if (sparse_count < 0 || sparse_count > count || !sparse.contains("indices") ||
        !sparse.contains("values"))
      return Bad(where + ".sparse is malformed");
    const json& idx = sparse["indices"];
    VOXPLAN_RETURN_IF_ERROR(
        CheckRange(views, view_bytes, Int(idx, "bufferView"), Int(idx, "byteOffset", 0),
                   sparse_count, ComponentSize(Int(idx, "componentType")), where + ".sparse"));
    const json& val = sparse["values"];
    VOXPLAN_RETURN_IF_ERROR(CheckRange(views, view_bytes, Int(val, "bufferView"),
                                       Int(val, "byteOffset", 0), sparse_count, size * n,
                                       where + ".sparse"));
  }
  return Status::Ok();
}

Status CheckMeshes(const json& doc) {
  const size_t accessors = Array(doc, "accessors").size();
  const json& meshes = Array(doc, "meshes");
  for (size_t m = 0; m < meshes.size(); ++m) {
    const json& prims = Array(meshes[m], "primitives");
    for (size_t p = 0; p < prims.size(); ++p) {
      const std::string where =
          "meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "]";
      VOXPLAN_RETURN_IF_ERROR(Ref(prims[p], "indices", accessors, where));
      if (!prims[p].contains("attributes") || !prims[p]["attributes"].is_object()) continue;
      for (const auto& item : prims[p]["attributes"].items())
        if (!item.value().is_number_unsigned() || item.value().get<uint64_t>() >= accessors)
          return Bad(where + ".attributes." + item.key() + " names none of the " +
                     std::to_string(accessors) + " accessors");
    }
  }
  return Status::Ok();
}

// Node references in range, and every node the child of at most one parent, with no cycle.
Status CheckNodes(const json& doc) {
  const json& nodes = Array(doc, "nodes");
  const size_t meshes = Array(doc, "meshes").size();
  std::vector<int64_t> parent(nodes.size(), -1);
  for (size_t n = 0; n < nodes.size(); ++n) {
    const std::string where = "nodes[" + std::to_string(n) + "]";
    VOXPLAN_RETURN_IF_ERROR(Ref(nodes[n], "mesh", meshes, where));
    for (const json& c : Array(nodes[n], "children")) {
      const int64_t child = c.is_number_unsigned() ? c.get<int64_t>() : -1;
      if (child < 0 || uint64_t(child) >= nodes.size() || parent[size_t(child)] >= 0)
        return Bad(where + ".children names a missing node or one that has a parent already");
      parent[size_t(child)] = int64_t(n);
    }
  }
  for (size_t n = 0; n < nodes.size(); ++n) {
    int64_t up = int64_t(n);
    for (size_t steps = 0; up >= 0; ++steps, up = parent[size_t(up)])
      if (steps > nodes.size()) return Bad("the nodes form a cycle");
  }
  for (const json& scene : Array(doc, "scenes"))
    for (const json& n : Array(scene, "nodes"))
      if (!n.is_number_unsigned() || n.get<uint64_t>() >= nodes.size())
        return Bad("a scene names a missing node");
  return Status::Ok();
}

}  // namespace

Status CheckGlb(std::string_view bytes) {
  if (bytes.size() < 20 || U32(bytes, 0) != kMagic)
    return Bad("not a binary glTF file (no 'glTF' magic at the start)");
  if (U32(bytes, 4) != 2)
    return Bad("glTF version " + std::to_string(U32(bytes, 4)) + ", only version 2 is read");
  if (U32(bytes, 8) != bytes.size())
    return Bad("the header gives a length of " + std::to_string(U32(bytes, 8)) +
               " bytes, the file has " + std::to_string(bytes.size()));
  std::string_view json_text;
  uint64_t bin_bytes = 0;
  for (size_t at = 12, chunk = 0; at < bytes.size(); ++chunk) {
    if (bytes.size() - at < 8)
      return Bad("a chunk header is cut off at byte " + std::to_string(at));
    const uint64_t length = U32(bytes, at), type = U32(bytes, at + 4);
    if (length > bytes.size() - at - 8)
      return Bad("chunk " + std::to_string(chunk) + " (" + std::to_string(length) +
                 " bytes) runs past the end of the file");
    if (chunk == 0 && type != kJsonChunk) return Bad("the first chunk is not JSON");
    if (chunk == 0) json_text = bytes.substr(at + 8, length);
    if (chunk == 1 && type == kBinChunk) bin_bytes = length;
    at += 8 + length;
  }
  const json doc = json::parse(json_text.begin(), json_text.end(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return Bad("the JSON chunk is not a JSON object");
  std::vector<int64_t> view_bytes;
  VOXPLAN_RETURN_IF_ERROR(CheckBuffers(doc, bin_bytes, &view_bytes));
  VOXPLAN_RETURN_IF_ERROR(CheckAccessors(doc, view_bytes, bytes.size()));
  VOXPLAN_RETURN_IF_ERROR(CheckMeshes(doc));
  return CheckNodes(doc);
}

}  // namespace voxplan::internal
