#include "fusion/mesh_block.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/assert.h"
#include "fusion/marching_cubes_table.h"

namespace voxplan::internal {

namespace {

constexpr int kGrid =
    kBlockSide + 1;  // a block's voxels plus the first layer of its +x/+y/+z neighbours
constexpr int kGridCells = kGrid * kGrid * kGrid;
constexpr int kCornerSlot = 3;  // the "axis" of a vertex on a corner, in keys and slots

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
constexpr int kAxisStep[3] = {1, kGrid, kGrid* kGrid};

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

// A voxel corner's coordinate along one axis, exactly as VoxelCenter computes it.
float CornerCoord(int32_t g, float s) { return (float(g) + 0.5f) * s; }

}  // namespace

uint64_t VertexKey(GlobalVoxelIndex g, int axis) {
  constexpr int32_t kBias = 1 << 19;
  VOXPLAN_DASSERT(std::abs(g.x) < kBias && std::abs(g.y) < kBias && std::abs(g.z) < kBias);
  return uint64_t(uint32_t(g.x + kBias) & 0xfffff) |
         (uint64_t(uint32_t(g.y + kBias) & 0xfffff) << 20) |
         (uint64_t(uint32_t(g.z + kBias) & 0xfffff) << 40) | (uint64_t(axis) << 60);
}

// Welding within a block: grid slot (cell * 4 + axis, axis 3 for the cell's corner) -> local
// vertex id, reset after each block through the list of entries it set.
struct BlockScratch {
  LocalGrid grid;
  std::vector<int32_t> vertex = std::vector<int32_t>(kGridCells * 4, -1);
  std::vector<int32_t> touched;
  void Reset() {
    for (int32_t i : touched) vertex[size_t(i)] = -1;
    touched.clear();
  }
};

void BlockScratchDeleter::operator()(BlockScratch* s) const { delete s; }
std::unique_ptr<BlockScratch, BlockScratchDeleter> MakeBlockScratch() {
  return std::unique_ptr<BlockScratch, BlockScratchDeleter>(new BlockScratch);
}

namespace {

bool IsCornerVertex(const BlockMesh& out, uint32_t v) { return (out.keys[v] >> 60) == kCornerSlot; }

// One block's meshing state: the grid, where its lower corner lies, the slots and the piece.
struct BlockMesher {
  const LocalGrid& grid;
  GlobalVoxelIndex origin;
  float s;
  BlockScratch& scratch;
  BlockMesh& out;

  uint32_t AddVertex(int slot, uint64_t key, bool shared, const Eigen::Vector3f& p,
                     const std::array<uint8_t, 3>& rgb) {
    scratch.vertex[size_t(slot)] = int32_t(out.positions.size());
    scratch.touched.push_back(slot);
    out.keys.push_back(key);
    out.shared.push_back(shared);
    out.positions.push_back(p);
    out.colors.push_back(rgb);
    return uint32_t(out.positions.size() - 1);
  }

  // The vertex on the voxel corner at grid cell `cell`, local coordinates `l`: one per corner
  // whichever edge reached it. The eight cubes around it reach into a neighbouring block when
  // any coordinate is 0 or 8.
  uint32_t CornerVertex(int cell, const int l[3]) {
    const int32_t known = scratch.vertex[size_t(cell) * 4 + kCornerSlot];
    if (known >= 0) return uint32_t(known);
    const GlobalVoxelIndex g{origin.x + l[0], origin.y + l[1], origin.z + l[2]};
    bool shared = false;
    for (int k = 0; k < 3; ++k) shared |= l[k] == 0 || l[k] == kBlockSide;
    return AddVertex(cell * 4 + kCornerSlot, VertexKey(g, kCornerSlot), shared,
                     {CornerCoord(g.x, s), CornerCoord(g.y, s), CornerCoord(g.z, s)},
                     {grid.rgb[cell][0], grid.rgb[cell][1], grid.rgb[cell][2]});
  }

  // The vertex where the surface crosses the edge from grid cell `a` (local coordinates `l`)
  // along `axis`. Where the crossing lands on an end corner (that corner's TSDF is exactly
  // zero, or the offset rounds away), it is that corner's vertex, so no two vertices share a
  // position: the edge coordinate is monotonic in t and equals a corner's only at the corner.
  uint32_t EdgeVertex(int a, const int l[3], int axis) {
    int32_t& slot = scratch.vertex[size_t(a) * 4 + size_t(axis)];
    if (slot >= 0) return uint32_t(slot);
    const int b = a + kAxisStep[axis];
    const float va = grid.tsdf[a], vb = grid.tsdf[b];
    const float t = va / (va - vb);
    const int32_t g[3] = {origin.x + l[0], origin.y + l[1], origin.z + l[2]};
    Eigen::Vector3f p(CornerCoord(g[0], s), CornerCoord(g[1], s), CornerCoord(g[2], s));
    const float lo = p[axis], hi = CornerCoord(g[axis] + 1, s);
    p[axis] = (float(g[axis]) + 0.5f + t) * s;
    if (p[axis] == lo || p[axis] == hi) {
      const bool at_b = p[axis] == hi;
      int lc[3] = {l[0], l[1], l[2]};
      lc[axis] += at_b;
      slot = int32_t(CornerVertex(at_b ? b : a, lc));
      scratch.touched.push_back(a * 4 + axis);
      return uint32_t(slot);
    }
    std::array<uint8_t, 3> rgb;
    for (int k = 0; k < 3; ++k)  // t in [0, 1]: +0.5 and truncation round to nearest
      rgb[k] = uint8_t(float(grid.rgb[a][k]) + t * (float(grid.rgb[b][k]) - float(grid.rgb[a][k])) +
                       0.5f);
    // The four cubes around an edge reach into the previous block when a perpendicular
    // coordinate is 0, and the edge lies in the next block when one is 8.
    const int e1 = (axis + 1) % 3, e2 = (axis + 2) % 3;
    const bool shared = l[e1] == 0 || l[e1] == kBlockSide || l[e2] == 0 || l[e2] == kBlockSide;
    return AddVertex(a * 4 + axis, VertexKey({g[0], g[1], g[2]}, axis), shared, p, rgb);
  }

  // A triangle through a corner vertex may have lost its area: two of its vertices became one,
  // or (rarely) the three lie on one line. In double the cross product of float coordinates is
  // zero whenever the exact one is, and otherwise only for areas far below any float's reach.
  bool Degenerate(const std::array<uint32_t, 3>& t) const {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
    const Eigen::Vector3d p0 = out.positions[t[0]].cast<double>();
    const Eigen::Vector3d n =
        (out.positions[t[1]].cast<double>() - p0).cross(out.positions[t[2]].cast<double>() - p0);
    return n.x() == 0.0 && n.y() == 0.0 && n.z() == 0.0;
  }

  void RemoveUnusedVertices();
  bool Cube(int x, int y, int z, int case_index);  // false when it dropped a triangle
};

// Dropped triangles can leave a vertex no triangle uses; a writer or reader would lose it, so
// the piece keeps only used ones (in order).
void BlockMesher::RemoveUnusedVertices() {
  std::vector<int32_t> renumber(out.positions.size(), -1);
  for (const auto& t : out.triangles)
    for (uint32_t v : t) renumber[v] = 0;
  uint32_t n = 0;
  for (size_t v = 0; v < renumber.size(); ++v) {
    if (renumber[v] < 0) continue;
    renumber[v] = int32_t(n);
    out.keys[n] = out.keys[v];
    out.shared[n] = out.shared[v];
    out.positions[n] = out.positions[v];
    out.colors[n] = out.colors[v];
    ++n;
  }
  out.keys.resize(n);
  out.shared.resize(n);
  out.positions.resize(n);
  out.colors.resize(n);
  for (auto& t : out.triangles)
    for (uint32_t& v : t) v = uint32_t(renumber[v]);
}

bool BlockMesher::Cube(int x, int y, int z, int case_index) {
  const int base = LocalGrid::Index(x, y, z);
  const McCase& mc = MarchingCubesTable()[size_t(case_index)];
  uint32_t vertex_of_edge[12];
  bool any_corner = false;
  for (int e = 0; e < 12; ++e) {
    if (!((mc.edge_mask >> e) & 1)) continue;
    const int c0 = kEdgeCorner[e][0];
    const int l[3] = {x + (c0 & 1), y + ((c0 >> 1) & 1), z + (c0 >> 2)};
    vertex_of_edge[e] = EdgeVertex(base + kCornerOffset[c0], l, kEdgeAxis[e]);
    any_corner |= IsCornerVertex(out, vertex_of_edge[e]);
  }
  bool kept_all = true;
  for (int k = 0; k < mc.num_triangles; ++k) {
    const std::array<uint32_t, 3> t = {vertex_of_edge[mc.edges[3 * k]],
                                       vertex_of_edge[mc.edges[3 * k + 1]],
                                       vertex_of_edge[mc.edges[3 * k + 2]]};
    if (any_corner && Degenerate(t)) {
      kept_all = false;
      continue;
    }
    out.triangles.push_back(t);
  }
  return kept_all;
}

}  // namespace

void MeshBlock(const TsdfVolume& volume, BlockIndex b, const MeshParams& params,
               BlockScratch& scratch, BlockMesh& out) {
  LocalGrid& grid = scratch.grid;
  if (!FillGrid(volume, b, uint16_t(std::ceil(params.min_weight * kWeightScale)), grid)) return;
  BlockMesher mesher{grid, GlobalOf(b, {0, 0, 0}), volume.voxel_size_m(), scratch, out};
  bool dropped = false;
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
        dropped |= !mesher.Cube(x, y, z, case_index);
      }
    }
  if (dropped) mesher.RemoveUnusedVertices();
  scratch.Reset();
}

}  // namespace voxplan::internal
