// The map loader (io/map_io.h) and what `voxplan mesh`, `render` and `info` do with a map it
// accepts. The file's trailing checksum would stop almost every mutation at the door, so each
// input is tried twice: as given, and with its last 8 bytes replaced by the checksum of the rest
// (FNV-1a 64, as map_io.cpp computes it), which lets the fuzzer reach the block records and the
// voxels behind them. An accepted map must mesh to indices in range, ray cast the same with the
// scalar and the AVX2 march, and save and load back to the same blocks and up axis (version 1
// files load as unknown up and save as version 2).
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/raycast.h"
#include "fusion/mesh_extract.h"
#include "io/map_io.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

using namespace voxplan;

uint64_t Fnv1a64(const uint8_t* p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

void CheckMesh(const TsdfVolume& volume) {
  const Mesh mesh = ExtractMesh(volume);
  for (const auto& t : mesh.triangles)
    for (uint32_t v : t)
      if (v >= mesh.num_vertices()) std::abort();
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.num_vertices()) std::abort();
}

// A small view of the allocated blocks from in front of them, as `render` frames a map.
void CheckRaycast(const TsdfVolume& volume) {
  if (volume.num_blocks() == 0) return;
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock&) {
    const Eigen::Vector3f corner =
        Eigen::Vector3f(float(b.x), float(b.y), float(b.z)) * volume.block_size_m();
    lo = lo.cwiseMin(corner);
    hi = hi.cwiseMax(corner + Eigen::Vector3f::Constant(volume.block_size_m()));
  });
  const float extent = (hi - lo).maxCoeff();
  PinholeCamera camera{16, 12, 10.f, 10.f, 7.5f, 5.5f};
  Pose3f T_W_C = Pose3f::Identity();
  T_W_C.translation() = 0.5f * (lo + hi) - Eigen::Vector3f(0.f, 0.f, extent);
  RaycastParams params;
  params.max_depth_m = 3.f * extent;
  params.simd = false;
  const RaycastImages scalar = Raycast(volume, camera, T_W_C, params);
  params.simd = true;
  const RaycastImages simd = Raycast(volume, camera, T_W_C, params);
  if (scalar.status.data != simd.status.data) std::abort();
  if (std::memcmp(scalar.depth.data.data(), simd.depth.data.data(),
                  scalar.depth.data.size() * sizeof(float)) != 0)
    std::abort();
}

void CheckRoundTrip(const TsdfVolume& volume, WorldUp up) {
  const std::string path = (fuzz::ScratchDir() / "saved.vpmap").string();
  if (!SaveMap(volume, path, up).ok()) std::abort();
  WorldUp up_again = WorldUp::kUnknown;
  const Result<TsdfVolume> again = LoadMap(path, &up_again);
  if (!again.ok() || again->num_blocks() != volume.num_blocks() || up_again != up) std::abort();
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
    const TsdfBlock* other = again->FindBlock(b);
    if (!other || std::memcmp(other, &block, sizeof(TsdfBlock)) != 0) std::abort();
  });
}

void Try(const std::string& path) {
  const Result<MapHeader> header = ReadMapHeader(path);
  WorldUp up = WorldUp::kUnknown;
  const Result<TsdfVolume> volume = LoadMap(path, &up);
  if (!volume.ok()) return;
  if (!header.ok() || header->num_blocks != volume->num_blocks() || header->up != up) std::abort();
  if (header->version == 1 && up != WorldUp::kUnknown) std::abort();
  CheckMesh(*volume);
  CheckRaycast(*volume);
  CheckRoundTrip(*volume, up);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Try(fuzz::InputFile(data, size, "input.vpmap"));
  if (size < 8) return 0;
  std::vector<uint8_t> fixed(data, data + size);
  const uint64_t checksum = Fnv1a64(fixed.data(), size - 8);
  std::memcpy(fixed.data() + size - 8, &checksum, 8);
  Try(fuzz::InputFile(fixed.data(), size, "fixed.vpmap"));
  return 0;
}
