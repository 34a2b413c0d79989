// Binary glTF written directly: assimp's glTF 2 exporter always runs its JoinIdenticalVertices
// step first, which merged voxplan's vertices and made degenerate triangles.
#include <bit>
#include <cstring>
#include <nlohmann/json.hpp>

#include "io/mesh_encode.h"

namespace voxplan::internal {

namespace {

constexpr int kFloat = 5126, kUnsignedInt = 5125;                 // accessor componentType
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;  // bufferView target
constexpr uint32_t kMagic = 0x46546C67, kJsonChunk = 0x4E4F534A, kBinChunk = 0x004E4942;

void AppendU32(std::string& out, uint32_t v) {
  char bytes[4];
  std::memcpy(bytes, &v, 4);
  out.append(bytes, 4);
}

// Appends `count` items of `item_bytes` each to the binary buffer as one buffer view (4-byte
// aligned, as glTF requires of vertex attributes) and one accessor; returns the accessor id.
template <typename Fill>
int AddAccessor(nlohmann::json& gltf, std::string& bin, size_t count, size_t item_bytes,
                int component_type, const char* type, int target, Fill&& fill) {
  const size_t offset = bin.size();
  bin.resize(offset + count * item_bytes);
  fill(bin.data() + offset);
  const int view = int(gltf["bufferViews"].size());
  gltf["bufferViews"].push_back({{"buffer", 0},
                                 {"byteOffset", offset},
                                 {"byteLength", count * item_bytes},
                                 {"target", target}});
  const int accessor = int(gltf["accessors"].size());
  gltf["accessors"].push_back(
      {{"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}});
  return accessor;
}

// Copies three floats per item from `get(i)` into the buffer.
template <typename Get>
auto Vec3Filler(size_t count, Get&& get) {
  return [count, get](char* dst) {
    for (size_t i = 0; i < count; ++i, dst += 12) {
      const float v[3] = {get(i, 0), get(i, 1), get(i, 2)};
      std::memcpy(dst, v, 12);
    }
  };
}

}  // namespace

Result<std::string> EncodeGlb(const Mesh& mesh) {
  static_assert(std::endian::native == std::endian::little, "GLB writer assumes little-endian");
  const size_t n = mesh.num_vertices();
  if (n * 36 + mesh.num_triangles() * 12 > size_t(UINT32_MAX) - (1u << 20))
    return Unsupported("the mesh is too large for a .glb file (4 GiB at most)");
  nlohmann::json gltf = {{"asset", {{"version", "2.0"}, {"generator", "voxplan"}}},
                         {"scene", 0},
                         {"scenes", {{{"nodes", {0}}}}},
                         {"nodes", {{{"mesh", 0}}}},
                         {"bufferViews", nlohmann::json::array()},
                         {"accessors", nlohmann::json::array()}};
  std::string bin;
  nlohmann::json attributes;
  attributes["POSITION"] =
      AddAccessor(gltf, bin, n, 12, kFloat, "VEC3", kArrayBuffer,
                  Vec3Filler(n, [&](size_t i, int k) { return mesh.positions[i][k]; }));
  Eigen::Vector3f lo = mesh.positions[0], hi = mesh.positions[0];  // glTF requires the bounds
  for (const auto& p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  gltf["accessors"][0]["min"] = {lo.x(), lo.y(), lo.z()};
  gltf["accessors"][0]["max"] = {hi.x(), hi.y(), hi.z()};
  if (!mesh.normals.empty())
    attributes["NORMAL"] =
        AddAccessor(gltf, bin, n, 12, kFloat, "VEC3", kArrayBuffer,
                    Vec3Filler(n, [&](size_t i, int k) { return mesh.normals[i][k]; }));
  if (!mesh.colors.empty())
    attributes["COLOR_0"] = AddAccessor(
        gltf, bin, n, 12, kFloat, "VEC3", kArrayBuffer,
        Vec3Filler(n, [&](size_t i, int k) { return float(mesh.colors[i][k]) / 255.0f; }));
  const size_t num_indices = 3 * mesh.num_triangles();
  const int indices = AddAccessor(gltf, bin, num_indices, 4, kUnsignedInt, "SCALAR",
                                  kElementArrayBuffer, [&](char* dst) {
                                    for (const auto& t : mesh.triangles) {
                                      std::memcpy(dst, t.data(), 12);
                                      dst += 12;
                                    }
                                  });
  gltf["meshes"] = {
      {{"primitives", {{{"attributes", attributes}, {"indices", indices}, {"mode", 4}}}}}};
  gltf["buffers"] = {{{"byteLength", bin.size()}}};

  // Chunks are 4-byte aligned: JSON padded with spaces, the binary chunk with zeros.
  std::string json = gltf.dump();
  json.resize((json.size() + 3) / 4 * 4, ' ');
  bin.resize((bin.size() + 3) / 4 * 4, '\0');
  std::string out;
  out.reserve(28 + json.size() + bin.size());
  AppendU32(out, kMagic);
  AppendU32(out, 2);
  AppendU32(out, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  AppendU32(out, uint32_t(json.size()));
  AppendU32(out, kJsonChunk);
  out += json;
  AppendU32(out, uint32_t(bin.size()));
  AppendU32(out, kBinChunk);
  out += bin;
  return out;
}

}  // namespace voxplan::internal
