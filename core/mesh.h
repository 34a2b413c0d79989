#pragma once
// Triangle mesh POD shared by meshing, export, scene loading and evaluation.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace voxplan {

struct Mesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;            // empty or one per vertex, unit length
  std::vector<std::array<uint8_t, 3>> colors;      // empty or one RGB per vertex
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside

  size_t num_vertices() const { return positions.size(); }
  size_t num_triangles() const { return triangles.size(); }
  bool empty() const { return triangles.empty(); }
};

}  // namespace voxplan
