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
  float tsdf[kGridCells];
  bool observed[kGridCells];
  uint8_t rgb[kGridCells][3];
  static int Index(int x, int y, int z) { return x + kGrid * (y + kGrid * z); }
};

void FillGrid(const TsdfVolume& volume, BlockIndex b, uint16_t min_weight, LocalGrid& grid) {
  std::fill(std::begin(grid.observed), std::end(grid.observed), false);
  for (int n = 0; n < 8; ++n) {
    const int dx = n & 1, dy = (n >> 1) & 1, dz = n >> 2;
    const TsdfBlock* block = volume.FindBlock({b.x + dx, b.y + dy, b.z + dz});
    if (!block) continue;
    // Neighbour (dx,dy,dz) contributes its first voxel layer along each offset axis.
    const int x0 = dx ? kBlockSide : 0, x1 = dx ? kGrid : kBlockSide;
    const int y0 = dy ? kBlockSide : 0, y1 = dy ? kGrid : kBlockSide;
    const int z0 = dz ? kBlockSide : 0, z1 = dz ? kGrid : kBlockSide;
    for (int z = z0; z < z1; ++z)
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const int src = LinearIndex(x & kBlockMask, y & kBlockMask, z & kBlockMask);
          const int dst = LocalGrid::Index(x, y, z);
          grid.observed[dst] = block->weight[src] >= min_weight && block->weight[src] > 0;
          grid.tsdf[dst] = DecodeTsdf(block->tsdf[src]);
          grid.rgb[dst][0] = block->r[src];
          grid.rgb[dst][1] = block->g[src];
          grid.rgb[dst][2] = block->b[src];
        }
  }
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

struct BlockMesh {
  std::vector<uint64_t> keys;  // one per local vertex
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<std::array<uint32_t, 3>> triangles;  // local vertex ids
};

void MeshBlock(const TsdfVolume& volume, BlockIndex b, const MeshParams& params, LocalGrid& grid,
               std::vector<int32_t>& edge_vertex, BlockMesh& out) {
  const auto& table = internal::MarchingCubesTable();
  const float s = volume.voxel_size_m();
  FillGrid(volume, b, uint16_t(std::ceil(params.min_weight * kWeightScale)), grid);
  std::fill(edge_vertex.begin(), edge_vertex.end(), -1);
  const GlobalVoxelIndex origin = GlobalOf(b, {0, 0, 0});

  for (int z = 0; z < kBlockSide; ++z)
    for (int y = 0; y < kBlockSide; ++y)
      for (int x = 0; x < kBlockSide; ++x) {
        int corner_cell[8];
        int case_index = 0;
        bool complete = true;
        for (int c = 0; c < 8; ++c) {
          corner_cell[c] = LocalGrid::Index(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2));
          complete &= grid.observed[corner_cell[c]];
          if (grid.tsdf[corner_cell[c]] < 0.f) case_index |= 1 << c;
        }
        if (!complete || case_index == 0 || case_index == 255) continue;
        const internal::McCase& mc = table[case_index];
        uint32_t vertex_of_edge[12];
        for (int e = 0; e < 12; ++e) {
          bool used = false;
          for (int k = 0; k < 3 * mc.num_triangles; ++k) used |= mc.edges[k] == e;
          if (!used) continue;
          const int c0 = internal::kEdgeCorner[e][0], axis = internal::kEdgeAxis[e];
          const int lx = x + (c0 & 1), ly = y + ((c0 >> 1) & 1), lz = z + (c0 >> 2);
          int32_t& slot = edge_vertex[LocalGrid::Index(lx, ly, lz) * 3 + axis];
          if (slot < 0) {
            const int a = corner_cell[c0], bcell = corner_cell[internal::kEdgeCorner[e][1]];
            const float va = grid.tsdf[a], vb = grid.tsdf[bcell];
            const float t = va / (va - vb);
            const GlobalVoxelIndex g{origin.x + lx, origin.y + ly, origin.z + lz};
            Eigen::Vector3f p = VoxelCenter(g, s);
            p[axis] += t * s;
            std::array<uint8_t, 3> rgb;
            for (int k = 0; k < 3; ++k)
              rgb[k] = uint8_t(std::lround(
                  float(grid.rgb[a][k]) + t * (float(grid.rgb[bcell][k]) - float(grid.rgb[a][k]))));
            slot = int32_t(out.positions.size());
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

}  // namespace

Mesh ExtractMesh(const TsdfVolume& volume, const MeshParams& params) {
  const std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
  std::vector<BlockMesh> parts(blocks.size());
  ParallelFor(blocks.size(), 8, [&](size_t begin, size_t end) {
    auto grid = std::make_unique<LocalGrid>();
    std::vector<int32_t> edge_vertex(kGridCells * 3);
    for (size_t i = begin; i < end; ++i)
      MeshBlock(volume, blocks[i], params, *grid, edge_vertex, parts[i]);
  });

  // Weld: blocks meet on shared edges, which carry the same key and identical values.
  size_t total = 0;
  std::vector<size_t> offset(parts.size() + 1, 0);
  for (size_t i = 0; i < parts.size(); ++i) offset[i + 1] = offset[i] + parts[i].keys.size();
  total = offset.back();
  std::vector<std::pair<uint64_t, uint32_t>> order(total);
  for (size_t i = 0; i < parts.size(); ++i)
    for (size_t k = 0; k < parts[i].keys.size(); ++k)
      order[offset[i] + k] = {parts[i].keys[k], uint32_t(offset[i] + k)};
  std::sort(order.begin(), order.end());

  Mesh mesh;
  std::vector<uint32_t> welded(total);
  for (size_t k = 0; k < total; ++k) {
    if (k == 0 || order[k].first != order[k - 1].first) {
      const uint32_t seq = order[k].second;
      const size_t part =
          size_t(std::upper_bound(offset.begin(), offset.end(), seq) - offset.begin()) - 1;
      mesh.positions.push_back(parts[part].positions[seq - offset[part]]);
      if (params.with_color) mesh.colors.push_back(parts[part].colors[seq - offset[part]]);
    }
    welded[order[k].second] = uint32_t(mesh.positions.size() - 1);
  }
  for (size_t i = 0; i < parts.size(); ++i)
    for (const auto& tri : parts[i].triangles) {
      const std::array<uint32_t, 3> t = {welded[offset[i] + tri[0]], welded[offset[i] + tri[1]],
                                         welded[offset[i] + tri[2]]};
      if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) mesh.triangles.push_back(t);
    }

  // Area-weighted vertex normals, accumulated in triangle order (deterministic).
  mesh.normals.assign(mesh.positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                  .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (uint32_t v : t) mesh.normals[v] += n;
  }
  for (auto& n : mesh.normals) {
    const float len = n.norm();
    n = len > 0.f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
  return mesh;
}

}  // namespace voxplan
