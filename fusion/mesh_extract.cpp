#include "fusion/mesh_extract.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/assert.h"
#include "core/parallel.h"
#include "fusion/marching_cubes_table.h"

namespace voxplan {

namespace {

constexpr int kGrid =
    kBlockSide + 1;  // a block's voxels plus the first layer of its +x/+y/+z neighbours
constexpr int kGridCells = kGrid * kGrid * kGrid;

// A block and its +1 neighbour layer copied into one dense 9^3 grid, so every cube's corners
// are plain array reads.
struct LocalGrid {
  static constexpr uint8_t kObserved = 1, kInside = 2;
  float tsdf[kGridCells];
  uint8_t flags[kGridCells];  // kObserved | kInside (negative distance)
  uint8_t rgb[kGridCells][3];
  // Per x-row (index y + 9 z) bit x set when that cell is observed / inside: a cube's 8 signs
  // are then two bits from each of four rows.
  uint16_t observed_row[kGrid * kGrid];
  uint16_t inside_row[kGrid * kGrid];
  static int Index(int x, int y, int z) { return x + kGrid * (y + kGrid * z); }
};

// Cube corner c (offset (c & 1, (c >> 1) & 1, c >> 2)) as an offset in the grid.
constexpr int kCornerOffset[8] = {0,
                                  1,
                                  kGrid,
                                  kGrid + 1,
                                  kGrid* kGrid,
                                  kGrid* kGrid + 1,
                                  kGrid* kGrid + kGrid,
                                  kGrid* kGrid + kGrid + 1};

// Fills the grid; false when no surface can pass through it (no observed voxel inside or
// none outside), the common case that then costs no cube visits.
bool FillGrid(const TsdfVolume& volume, BlockIndex b, uint16_t min_weight, LocalGrid& grid) {
  std::fill(std::begin(grid.flags), std::end(grid.flags), uint8_t(0));
  bool any_inside = false, any_outside = false;
  for (int n = 0; n < 8; ++n) {
    const int dx = n & 1, dy = (n >> 1) & 1, dz = n >> 2;
    const TsdfBlock* block = volume.FindBlock({b.x + dx, b.y + dy, b.z + dz});
    if (!block) continue;
    // Neighbour (dx,dy,dz) contributes its first voxel layer along each offset axis.
    for (int z = dz ? kBlockSide : 0; z < (dz ? kGrid : kBlockSide); ++z)
      for (int y = dy ? kBlockSide : 0; y < (dy ? kGrid : kBlockSide); ++y)
        for (int x = dx ? kBlockSide : 0; x < (dx ? kGrid : kBlockSide); ++x) {
          const int src = LinearIndex(x & kBlockMask, y & kBlockMask, z & kBlockMask);
          const int dst = LocalGrid::Index(x, y, z);
          if (block->weight[src] < min_weight || block->weight[src] == 0) continue;
          const bool inside = block->tsdf[src] < 0;
          any_inside |= inside;
          any_outside |= !inside;
          grid.flags[dst] = LocalGrid::kObserved | (inside ? LocalGrid::kInside : 0);
          grid.tsdf[dst] = DecodeTsdf(block->tsdf[src]);
          grid.rgb[dst][0] = block->r[src];
          grid.rgb[dst][1] = block->g[src];
          grid.rgb[dst][2] = block->b[src];
        }
  }
  if (!(any_inside && any_outside)) return false;
  for (int r = 0; r < kGrid * kGrid; ++r) {
    uint16_t observed = 0, inside = 0;
    for (int x = 0; x < kGrid; ++x) {
      const uint8_t f = grid.flags[r * kGrid + x];
      observed |= uint16_t((f & LocalGrid::kObserved) << x);
      inside |= uint16_t(((f & LocalGrid::kInside) >> 1) << x);
    }
    grid.observed_row[r] = observed;
    grid.inside_row[r] = inside;
  }
  return true;
}

// An edge is named by its lower voxel (global) and axis: the same key from every block that
// uses it, which is what welds vertices across block borders. 20 bits per axis (+-524k voxels).
uint64_t EdgeKey(GlobalVoxelIndex g, int axis) {
  constexpr int32_t kBias = 1 << 19;
  VOXPLAN_DASSERT(std::abs(g.x) < kBias && std::abs(g.y) < kBias && std::abs(g.z) < kBias);
  return uint64_t(uint32_t(g.x + kBias) & 0xfffff) |
         (uint64_t(uint32_t(g.y + kBias) & 0xfffff) << 20) |
         (uint64_t(uint32_t(g.z + kBias) & 0xfffff) << 40) | (uint64_t(axis) << 60);
}

}  // namespace

namespace internal {
struct BlockMesh {
  std::vector<uint64_t> keys;   // one per local vertex
  std::vector<uint8_t> shared;  // 1 when a neighbouring block's cubes use the same edge
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<std::array<uint32_t, 3>> triangles;  // local vertex ids
};
}  // namespace internal

namespace {
using internal::BlockMesh;

// Welding within a block: grid edge (cell, axis) -> local vertex id, reset after each block
// through the list of entries it set.
struct EdgeVertexMap {
  std::vector<int32_t> vertex = std::vector<int32_t>(kGridCells * 3, -1);
  std::vector<int32_t> touched;
  void Reset() {
    for (int32_t i : touched) vertex[size_t(i)] = -1;
    touched.clear();
  }
};

void MeshBlock(const TsdfVolume& volume, BlockIndex b, const MeshParams& params, LocalGrid& grid,
               EdgeVertexMap& edges, BlockMesh& out) {
  const auto& table = internal::MarchingCubesTable();
  const float s = volume.voxel_size_m();
  if (!FillGrid(volume, b, uint16_t(std::ceil(params.min_weight * kWeightScale)), grid)) return;
  const GlobalVoxelIndex origin = GlobalOf(b, {0, 0, 0});

  for (int z = 0; z < kBlockSide; ++z)
    for (int y = 0; y < kBlockSide; ++y) {
      const int r0 = y + kGrid * z, r1 = r0 + 1, r2 = r0 + kGrid, r3 = r2 + 1;
      const uint32_t observed = grid.observed_row[r0] & grid.observed_row[r1] &
                                grid.observed_row[r2] & grid.observed_row[r3];
      const uint32_t any_inside =
          grid.inside_row[r0] | grid.inside_row[r1] | grid.inside_row[r2] | grid.inside_row[r3];
      const uint32_t all_inside =
          grid.inside_row[r0] & grid.inside_row[r1] & grid.inside_row[r2] & grid.inside_row[r3];
      if (observed == 0 || any_inside == 0 || all_inside == 0x1ff) continue;  // no surface here
      for (int x = 0; x < kBlockSide; ++x) {
        if (((observed >> x) & 3) != 3) continue;
        const int case_index =
            int((grid.inside_row[r0] >> x) & 3) | int((grid.inside_row[r1] >> x) & 3) << 2 |
            int((grid.inside_row[r2] >> x) & 3) << 4 | int((grid.inside_row[r3] >> x) & 3) << 6;
        if (case_index == 0 || case_index == 255) continue;
        const int base = LocalGrid::Index(x, y, z);
        const internal::McCase& mc = table[case_index];
        uint32_t vertex_of_edge[12];
        for (int e = 0; e < 12; ++e) {
          if (!((mc.edge_mask >> e) & 1)) continue;
          const int c0 = internal::kEdgeCorner[e][0], axis = internal::kEdgeAxis[e];
          const int a = base + kCornerOffset[c0];
          int32_t& slot = edges.vertex[size_t(a) * 3 + size_t(axis)];
          if (slot < 0) {
            const int bcell = base + kCornerOffset[internal::kEdgeCorner[e][1]];
            const float va = grid.tsdf[a], vb = grid.tsdf[bcell];
            const float t = va / (va - vb);
            const GlobalVoxelIndex g{origin.x + x + (c0 & 1), origin.y + y + ((c0 >> 1) & 1),
                                     origin.z + z + (c0 >> 2)};
            Eigen::Vector3f p = VoxelCenter(g, s);
            p[axis] += t * s;
            std::array<uint8_t, 3> rgb;
            for (int k = 0; k < 3; ++k)  // t in [0, 1]: +0.5 and truncation round to nearest
              rgb[k] = uint8_t(float(grid.rgb[a][k]) +
                               t * (float(grid.rgb[bcell][k]) - float(grid.rgb[a][k])) + 0.5f);
            slot = int32_t(out.positions.size());
            edges.touched.push_back(a * 3 + axis);
            // The four cubes around an edge reach into the previous block when a perpendicular
            // coordinate is 0, and the edge lies in the next block when one is 8.
            const int l[3] = {x + (c0 & 1), y + ((c0 >> 1) & 1), z + (c0 >> 2)};
            const int e1 = (axis + 1) % 3, e2 = (axis + 2) % 3;
            out.shared.push_back(l[e1] == 0 || l[e1] == kBlockSide || l[e2] == 0 ||
                                 l[e2] == kBlockSide);
            out.keys.push_back(EdgeKey(g, axis));
            out.positions.push_back(p);
            out.colors.push_back(rgb);
          }
          vertex_of_edge[e] = uint32_t(slot);
        }
        for (int k = 0; k < mc.num_triangles; ++k)
          out.triangles.push_back({vertex_of_edge[mc.edges[3 * k]],
                                   vertex_of_edge[mc.edges[3 * k + 1]],
                                   vertex_of_edge[mc.edges[3 * k + 2]]});
      }
    }
  edges.Reset();
}

// Meshes `blocks` in parallel, one piece each (empty where no surface passes).
void MeshBlocks(const TsdfVolume& volume, const std::vector<BlockIndex>& blocks,
                const MeshParams& params, std::vector<BlockMesh>& parts) {
  parts.assign(blocks.size(), BlockMesh{});
  ParallelFor(blocks.size(), 8, [&](size_t begin, size_t end) {
    auto grid = std::make_unique<LocalGrid>();
    EdgeVertexMap edges;
    for (size_t i = begin; i < end; ++i)
      MeshBlock(volume, blocks[i], params, *grid, edges, parts[i]);
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

  // Triangles, welded in parallel; the few that welding made degenerate are dropped after.
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
  std::vector<BlockMesh> parts;
  MeshBlocks(volume, volume.SortedBlockIndices(), params, parts);
  std::vector<const BlockMesh*> pointers;
  pointers.reserve(parts.size());
  for (const BlockMesh& part : parts) pointers.push_back(&part);
  return Assemble(pointers, params);
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
