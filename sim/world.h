#pragma once
// A simulated indoor world: one Z-up, metric triangle mesh whose triangles carry instance ids,
// and the table of those instances. Scene loaders and the apartment generator make worlds; the
// renderer, robots, planners' ground truth and the evaluator read them.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace voxplan {

inline constexpr uint32_t kNoInstance = 0;  // label of triangles and pixels with no instance

struct Instance {
  uint32_t id = kNoInstance;  // >= 1, unique within a world
  std::string class_name;     // "wall", "floor", "door", "chair", "sofa", ...
  std::string model;          // source model or generator shape it came from
  Eigen::AlignedBox3f bounds_W;
};

// An axis-aligned room footprint of a generated world (loaded scenes have none).
struct Room {
  std::string name;  // "living", "bedroom_1", "corridor", ...
  Eigen::AlignedBox2f footprint_W;
};

struct World {
  std::string name;
  Mesh mesh;                                // Z-up metres
  std::vector<uint32_t> triangle_instance;  // one per mesh triangle; kNoInstance where none
  std::vector<Instance> instances;          // sorted by id
  std::vector<Room> rooms;                  // empty unless the world was generated
  // The source file's z of this world's floor (z = 0): LoadWorld moved the file's geometry down
  // by it (SceneLoadOptions::floor_z_m, detect_floor). 0 for generated worlds.
  float source_floor_z_m = 0.0f;
};

}  // namespace voxplan
