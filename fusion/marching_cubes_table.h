#pragma once
// Marching-cubes case table, derived at start-up from the cube's geometry instead of typed in:
// for each of the 256 sign patterns, the crossing edges on each face are joined into segments
// (an ambiguous face keeps its inside corners apart, a rule that depends only on the face, so
// neighbouring cubes agree and the surface is watertight), the segments are chained into loops
// and each loop is fanned into triangles wound so normals point to the positive (free) side.
#include <array>
#include <cstdint>

namespace voxplan::internal {

// Corner c of a cube sits at offset (c & 1, (c >> 1) & 1, c >> 2). Edge e runs from corner
// kEdgeCorner[e][0] to kEdgeCorner[e][1] along axis kEdgeAxis[e].
inline constexpr int kEdgeCorner[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                           {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
inline constexpr int kEdgeAxis[12] = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};

struct McCase {
  uint8_t num_triangles = 0;
  uint16_t edge_mask = 0;          // bit e set when edge e carries a vertex
  std::array<int8_t, 36> edges{};  // 3 edge ids per triangle
};

// Case index: bit c set when corner c is inside (negative signed distance).
const std::array<McCase, 256>& MarchingCubesTable();

}  // namespace voxplan::internal
