// Worlds built from boxes for the sim tests.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "sim/world.h"

namespace voxplan::test {

// Appends an axis-aligned box (12 outward-facing triangles) as instance `id`.
inline void AddBox(World* world, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, uint32_t id,
                   const std::string& cls) {
  Mesh& m = world->mesh;
  const uint32_t base = uint32_t(m.positions.size());
  for (int k = 0; k < 8; ++k)
    m.positions.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                             k & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    m.triangles.push_back({base + q[0], base + q[2], base + q[3]});
    world->triangle_instance.push_back(id);
    world->triangle_instance.push_back(id);
  }
  world->instances.push_back({id, cls, cls, Eigen::AlignedBox3f(lo, hi)});
}

}  // namespace voxplan::test
