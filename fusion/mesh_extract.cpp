#include "fusion/mesh_extract.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/parallel.h"
#include "fusion/mesh_block.h"

namespace voxplan {

namespace {

using internal::BlockMesh;

// Meshes `blocks` in parallel, one piece each (empty where no surface passes).
void MeshBlocks(const TsdfVolume& volume, const std::vector<BlockIndex>& blocks,
                const MeshParams& params, std::vector<BlockMesh>& parts) {
  parts.assign(blocks.size(), BlockMesh{});
  ParallelFor(blocks.size(), 8, [&](size_t begin, size_t end) {
    const auto scratch = internal::MakeBlockScratch();
    for (size_t i = begin; i < end; ++i)
      internal::MeshBlock(volume, blocks[i], params, *scratch, parts[i]);
  });
}

constexpr size_t kPartsPerTask = 64;  // block pieces per parallel task

// Exclusive prefix sums of count(i) over [0, n), the counts taken in parallel: out[i] is the
// sum of the counts before i, out[n] the total.
template <typename Count>
std::vector<size_t> PrefixSums(size_t n, Count&& count) {
  std::vector<size_t> out(n + 1, 0);
  ParallelFor(n, kPartsPerTask, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) out[i + 1] = count(i);
  });
  for (size_t i = 0; i < n; ++i) out[i + 1] += out[i];
  return out;
}

// Welds per-block pieces, given in block order, into one mesh with area-weighted normals. The
// passes over pieces run in parallel; each writes where prefix sums over the pieces put it, so
// the mesh is the same for any thread count.
Mesh Assemble(const std::vector<const BlockMesh*>& parts, const MeshParams& params) {
  const size_t num_parts = parts.size();
  // Weld: blocks meet on shared edges, which carry the same key and identical values. Only
  // vertices on block borders can be shared; the first in block order stands for all.
  const std::vector<size_t> offset =
      PrefixSums(num_parts, [&](size_t i) { return parts[i]->keys.size(); });
  const size_t total = offset.back();
  const std::vector<size_t> border_offset = PrefixSums(num_parts, [&](size_t i) {
    return size_t(std::count(parts[i]->shared.begin(), parts[i]->shared.end(), uint8_t{1}));
  });
  std::vector<std::pair<uint64_t, uint32_t>> border(border_offset.back());
  std::vector<uint32_t> canonical(total);
  ParallelFor(num_parts, kPartsPerTask, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      size_t b = border_offset[i];
      for (size_t k = 0; k < parts[i]->keys.size(); ++k) {
        canonical[offset[i] + k] = uint32_t(offset[i] + k);
        if (parts[i]->shared[k]) border[b++] = {parts[i]->keys[k], uint32_t(offset[i] + k)};
      }
    }
  });
  std::sort(border.begin(), border.end());
  for (size_t k = 1; k < border.size(); ++k)
    if (border[k].first == border[k - 1].first)
      canonical[border[k].second] = canonical[border[k - 1].second];

  // Vertices: the canonical ones, in order; the others take their canonical vertex's id.
  const std::vector<size_t> vertex_offset = PrefixSums(num_parts, [&](size_t i) {
    size_t n = 0;
    for (size_t k = 0; k < parts[i]->keys.size(); ++k)
      n += canonical[offset[i] + k] == offset[i] + k;
    return n;
  });
  Mesh mesh;
  mesh.positions.resize(vertex_offset.back());
  if (params.with_color) mesh.colors.resize(vertex_offset.back());
  std::vector<uint32_t> welded(total);
  ParallelFor(num_parts, kPartsPerTask, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      size_t v = vertex_offset[i];
      for (size_t k = 0; k < parts[i]->keys.size(); ++k) {
        const size_t seq = offset[i] + k;
        if (canonical[seq] != seq) continue;
        welded[seq] = uint32_t(v);
        mesh.positions[v] = parts[i]->positions[k];
        if (params.with_color) mesh.colors[v] = parts[i]->colors[k];
        ++v;
      }
    }
  });
  // Canonical vertices come first in block order, so every one is numbered by now.
  ParallelFor(num_parts, kPartsPerTask, [&](size_t begin, size_t end) {
    for (size_t seq = offset[begin]; seq < offset[end]; ++seq)
      if (canonical[seq] != seq) welded[seq] = welded[canonical[seq]];
  });

  // Triangles, welded in parallel. Pieces are free of degenerate triangles and use each key
  // once, so welding cannot make one; the check below guards that.
  const std::vector<size_t> triangle_offset =
      PrefixSums(num_parts, [&](size_t i) { return parts[i]->triangles.size(); });
  mesh.triangles.resize(triangle_offset.back());
  auto degenerate = [](const std::array<uint32_t, 3>& t) {
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
  };
  std::vector<uint8_t> any_degenerate(num_parts, 0);
  ParallelFor(num_parts, kPartsPerTask, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      // data() + offset, not &triangles[offset]: a part without triangles may sit at the end
      // (offset == size, or an empty vector), where operator[] is undefined.
      std::array<uint32_t, 3>* out = mesh.triangles.data() + triangle_offset[i];
      for (const auto& tri : parts[i]->triangles) {
        *out = {welded[offset[i] + tri[0]], welded[offset[i] + tri[1]], welded[offset[i] + tri[2]]};
        any_degenerate[i] |= uint8_t(degenerate(*out++));
      }
    }
  });
  if (std::count(any_degenerate.begin(), any_degenerate.end(), uint8_t{1}) > 0)
    mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(), degenerate),
                         mesh.triangles.end());

  // Area-weighted vertex normals, accumulated in triangle order (deterministic), normalised in
  // parallel.
  mesh.normals.assign(mesh.positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                  .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (uint32_t v : t) mesh.normals[v] += n;
  }
  ParallelFor(mesh.normals.size(), 4096, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      Eigen::Vector3f& n = mesh.normals[v];
      const float len = n.norm();
      n = len > 0.f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
    }
  });
  return mesh;
}

}  // namespace

Mesh ExtractMesh(const TsdfVolume& volume, const MeshParams& params) {
  const std::vector<BlockMesh> parts = MeshBlockPieces(volume, volume.SortedBlockIndices(), params);
  std::vector<const BlockMesh*> pointers;
  pointers.reserve(parts.size());
  for (const BlockMesh& part : parts) pointers.push_back(&part);
  return Assemble(pointers, params);
}

std::vector<BlockMesh> MeshBlockPieces(const TsdfVolume& volume,
                                       const std::vector<BlockIndex>& blocks,
                                       const MeshParams& params) {
  std::vector<BlockMesh> parts;
  MeshBlocks(volume, blocks, params, parts);
  return parts;
}

Mesh AssembleMeshPieces(const std::vector<const BlockMesh*>& pieces_in_block_order,
                        const MeshParams& params) {
  return Assemble(pieces_in_block_order, params);
}

std::array<BlockIndex, 7> MeshStencilNeighbours(BlockIndex b) {
  std::array<BlockIndex, 7> out;
  for (int n = 1; n < 8; ++n) out[n - 1] = {b.x + (n & 1), b.y + ((n >> 1) & 1), b.z + (n >> 2)};
  return out;
}

IncrementalMesher::IncrementalMesher(const MeshParams& params) : params_(params) {}
IncrementalMesher::~IncrementalMesher() = default;
IncrementalMesher::IncrementalMesher(IncrementalMesher&&) noexcept = default;
IncrementalMesher& IncrementalMesher::operator=(IncrementalMesher&&) noexcept = default;

size_t IncrementalMesher::Update(const TsdfVolume& volume, const std::vector<BlockIndex>& changed) {
  std::vector<BlockIndex> dirty;
  dirty.reserve(changed.size() * 8);
  for (const BlockIndex& c : changed)
    for (int n = 0; n < 8; ++n)
      dirty.push_back({c.x - (n & 1), c.y - ((n >> 1) & 1), c.z - (n >> 2)});
  std::sort(dirty.begin(), dirty.end());
  dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
  // Only allocated blocks have cubes of their own; the others just lose their piece.
  std::vector<BlockIndex> remesh;
  remesh.reserve(dirty.size());
  for (const BlockIndex& b : dirty) {
    if (volume.FindBlock(b))
      remesh.push_back(b);
    else
      pieces_.erase(b);
  }
  std::vector<BlockMesh> parts;
  MeshBlocks(volume, remesh, params_, parts);
  for (size_t i = 0; i < remesh.size(); ++i) {
    if (parts[i].triangles.empty())
      pieces_.erase(remesh[i]);
    else
      pieces_[remesh[i]] = std::make_unique<BlockMesh>(std::move(parts[i]));
  }
  return remesh.size();
}

void IncrementalMesher::Rebuild(const TsdfVolume& volume) {
  pieces_.clear();
  Update(volume, volume.SortedBlockIndices());
}

Mesh IncrementalMesher::Assemble() const {
  std::vector<const BlockMesh*> pointers;
  pointers.reserve(pieces_.size());
  for (const auto& [b, piece] : pieces_) pointers.push_back(piece.get());
  return voxplan::Assemble(pointers, params_);
}

}  // namespace voxplan
