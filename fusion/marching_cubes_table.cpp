#include "fusion/marching_cubes_table.h"

#include <cstddef>
#include <vector>

namespace voxplan::internal {

namespace {

int EdgeBetween(int a, int b) {
  for (int e = 0; e < 12; ++e)
    if ((kEdgeCorner[e][0] == a && kEdgeCorner[e][1] == b) ||
        (kEdgeCorner[e][0] == b && kEdgeCorner[e][1] == a))
      return e;
  return -1;
}

// The four corners of each face in counter-clockwise order seen from outside the cube.
constexpr int kFaceCorners[6][4] = {
    {0, 4, 6, 2},  // x = 0, outward -x
    {1, 3, 7, 5},  // x = 1, outward +x
    {0, 1, 5, 4},  // y = 0, outward -y
    {2, 6, 7, 3},  // y = 1, outward +y
    {0, 2, 3, 1},  // z = 0, outward -z
    {4, 5, 7, 6},  // z = 1, outward +z
};

McCase BuildCase(int index) {
  auto inside = [&](int c) { return (index >> c) & 1; };
  // next[e]: the edge that follows crossing edge e along the surface's boundary loop.
  int next[12];
  for (int& n : next) n = -1;
  for (const auto& face : kFaceCorners) {
    // Walking the face counter-clockwise from outside, each crossing enters or leaves the
    // inside; the surface boundary runs from an entering crossing to the next leaving one.
    int enter = -1;
    int first_exit = -1;
    std::vector<std::pair<int, bool>> crossings;  // (edge, entering)
    for (int k = 0; k < 4; ++k) {
      const int a = face[k], b = face[(k + 1) % 4];
      if (inside(a) != inside(b)) crossings.push_back({EdgeBetween(a, b), bool(inside(b))});
    }
    for (std::size_t k = 0; k < crossings.size(); ++k) {
      const auto [edge, entering] = crossings[k];
      if (entering) {
        enter = edge;
      } else if (enter >= 0) {
        next[enter] = edge;
        enter = -1;
      } else {
        first_exit = edge;
      }
    }
    if (enter >= 0 && first_exit >= 0) next[enter] = first_exit;  // wrap around the face
  }
  McCase out;
  bool used[12] = {};
  for (int start = 0; start < 12; ++start) {
    if (next[start] < 0 || used[start]) continue;
    std::vector<int> loop;
    for (int e = start; !used[e]; e = next[e]) {
      used[e] = true;
      loop.push_back(e);
    }
    for (std::size_t k = 1; k + 1 < loop.size(); ++k) {
      const int t = out.num_triangles++;
      out.edges[3 * t + 0] = int8_t(loop[0]);
      out.edges[3 * t + 1] = int8_t(loop[k]);
      out.edges[3 * t + 2] = int8_t(loop[k + 1]);
    }
    for (int e : loop) out.edge_mask |= uint16_t(1u << e);
  }
  return out;
}

}  // namespace

const std::array<McCase, 256>& MarchingCubesTable() {
  static const std::array<McCase, 256> table = [] {
    std::array<McCase, 256> t;
    for (int i = 0; i < 256; ++i) t[i] = BuildCase(i);
    return t;
  }();
  return table;
}

}  // namespace voxplan::internal
