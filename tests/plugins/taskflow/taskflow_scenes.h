// Analytic objects for the task-flow reconstruction tests (header-only, plain data): unions of
// axis-aligned boxes standing on the floor z = 0, their surface samples, and map queries that
// say which space a camera has seen.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <vector>

#include "plugins/taskflow/algorithms/completion.h"

namespace voxplan::taskflow::testing {

using Region = std::function<bool(const Eigen::Vector3f&)>;

struct Surface {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
};

// Union of boxes on the floor.
struct Solid {
  std::vector<Eigen::AlignedBox3f> boxes;

  bool Inside(const Eigen::Vector3f& p, float margin) const {
    for (const Eigen::AlignedBox3f& b : boxes) {
      if ((p.array() > b.min().array() - margin).all() &&
          (p.array() < b.max().array() + margin).all())
        return true;
    }
    return false;
  }

  // Boundary samples (spacing apart) of the union where `seen` holds; no faces on the floor.
  Surface Sample(float spacing, const Region& seen) const {
    Surface s;
    for (const Eigen::AlignedBox3f& b : boxes) {
      for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
          const float c = side == 0 ? b.min()[axis] : b.max()[axis];
          if (axis == 2 && side == 0 && c <= 1e-6f) continue;  // on the floor
          const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
          const int n1 = std::max(1, static_cast<int>(std::lround(b.sizes()[a1] / spacing)));
          const int n2 = std::max(1, static_cast<int>(std::lround(b.sizes()[a2] / spacing)));
          Eigen::Vector3f normal = Eigen::Vector3f::Zero();
          normal[axis] = side == 0 ? -1.0f : 1.0f;
          for (int i = 0; i < n1; ++i) {
            for (int j = 0; j < n2; ++j) {
              Eigen::Vector3f p;
              p[axis] = c;
              p[a1] = b.min()[a1] + (static_cast<float>(i) + 0.5f) * b.sizes()[a1] / n1;
              p[a2] = b.min()[a2] + (static_cast<float>(j) + 0.5f) * b.sizes()[a2] / n2;
              // Faces shared with another box are inside the union.
              if (Inside(p + 1e-3f * normal, 0.0f)) continue;
              if (!seen(p)) continue;
              s.points.push_back(p);
              s.normals.push_back(normal);
            }
          }
        }
      }
    }
    return s;
  }
};

inline Solid UnitBox() {
  return {{Eigen::AlignedBox3f(Eigen::Vector3f(-0.5f, -0.5f, 0.0f),
                               Eigen::Vector3f(0.5f, 0.5f, 1.0f))}};
}

// A chair-like L in side view, mirror-symmetric about the plane x = 0: a seat block and a back.
inline Solid Chair() {
  return {{Eigen::AlignedBox3f(Eigen::Vector3f(-0.25f, -0.25f, 0.0f),
                               Eigen::Vector3f(0.25f, 0.25f, 0.45f)),
           Eigen::AlignedBox3f(Eigen::Vector3f(-0.25f, 0.15f, 0.45f),
                               Eigen::Vector3f(0.25f, 0.25f, 0.9f))}};
}

// An L-shaped footprint with unequal arms: no vertical mirror symmetry.
inline Solid LShape() {
  return {
      {Eigen::AlignedBox3f(Eigen::Vector3f(0.0f, 0.0f, 0.0f), Eigen::Vector3f(1.2f, 0.3f, 0.6f)),
       Eigen::AlignedBox3f(Eigen::Vector3f(0.0f, 0.3f, 0.0f), Eigen::Vector3f(0.3f, 0.7f, 0.6f))}};
}

// The map a camera leaves: occupied near the object where seen, free where seen and empty,
// unobserved elsewhere; below the floor is occupied.
inline SpaceQuery MapQuery(const Solid& solid, const Region& seen, float margin = 0.02f) {
  return [solid, seen, margin](std::span<const Eigen::Vector3f> points,
                               std::span<std::uint8_t> state) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3f& p = points[i];
      if (p.z() < 0.0f) {
        state[i] = kObservedOccupied;
      } else if (!seen(p)) {
        state[i] = kUnobserved;
      } else {
        state[i] = solid.Inside(p, margin) ? kObservedOccupied : kObservedFree;
      }
    }
  };
}

inline Region Everywhere() {
  return [](const Eigen::Vector3f&) { return true; };
}

// Share of `truth` points with a point of `cloud` within `radius`.
inline float CoveredShare(const std::vector<Eigen::Vector3f>& truth,
                          const std::vector<Eigen::Vector3f>& cloud, float radius) {
  if (truth.empty()) return 0.0f;
  const std::vector<float> d = NearestDistances(cloud, truth);
  int near = 0;
  for (const float x : d) near += x <= radius ? 1 : 0;
  return static_cast<float>(near) / static_cast<float>(truth.size());
}

}  // namespace voxplan::taskflow::testing
