#pragma once
// Loading an existing scene file as a World: one Z-up metric mesh plus per-triangle instance ids.
//
// Where the instances come from, first match wins:
//  1. an instance table beside the mesh, `<stem>_instances.tsv` (or SceneLoadOptions::
//     instance_table): one row per instance, in the order of the mesh's triangles, each with a
//     `triangles` count. The mesh's triangles are the instances' triangles concatenated in table
//     order; triangles past the table's total are "structure" (a foreign table such as the AWS
//     small house's) or kNoInstance (a table written by WriteWorld, which has an `id` column).
//     This is how `WriteWorld` output is read back, and how the AWS small house's
//     `small_house_visual_instances.tsv` labels its single-mesh PLY.
//  2. a file with several meshes / nodes (GLB, OBJ groups, COLLADA): each node's meshes become one
//     instance, its class guessed from the node name ("Chair_01" -> "chair").
//  3. a single mesh and no table: no instances (every triangle kNoInstance).
// Rooms come from `<stem>_rooms.tsv` when present (WriteWorld writes one for generated worlds).
//
// Floor: the simulator puts the floor at z = 0. A scene whose floor lies elsewhere (Replica's
// office at z = -1.17) is moved down by its floor height, after the up axis and the scale: by
// SceneLoadOptions::floor_z_m, or by the height DetectFloor (sim/floor_detect.h) finds with
// detect_floor. The mesh and the instances' boxes follow (room footprints are 2-D);
// World::source_floor_z_m keeps the height, so a point of the world is the file's point minus (0,
// 0, source_floor_z_m).
//
// Classes: a table's `class` column; else the furniture index (objects/aws_furniture_index.tsv,
// found by walking up from the scene file, or SceneLoadOptions::furniture_index) `category` of
// the row's model, with the index's "structure" split into wall / floor / ceiling / door /
// window by model name; else a guess from the model or instance name.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.h"
#include "io/mesh_io.h"
#include "sim/floor_detect.h"
#include "sim/world.h"

namespace voxplan {

struct SceneLoadOptions {
  float scale = 1.0f;          // multiplies coordinates after the file's own unit scale
  UpAxis up = UpAxis::kZ;      // kY rotates a Y-up file into the Z-up world (x, -z, y)
  std::string instance_table;  // empty: `<stem>_instances.tsv` beside the mesh, if any
  bool use_instance_table = true;
  std::string furniture_index;  // empty: search objects/aws_furniture_index.tsv upwards
  // Sanity range of the scene's largest horizontal extent after scaling; outside it the scale or
  // unit is wrong (a house 1 km wide, a kitchen 2 cm wide) and the scene is refused.
  float max_extent_m = 200.0f;
  float min_extent_m = 0.5f;
  // The file's floor height (metres, after up and scale): the world is moved down by it. With
  // detect_floor, DetectFloor(floor_detect) finds it instead, and a scene without a floor it can
  // find is refused. |floor_z_m| must not exceed max_extent_m.
  float floor_z_m = 0.0f;
  bool detect_floor = false;
  FloorDetectParams floor_detect;
};

Result<World> LoadWorld(const std::string& path, const SceneLoadOptions& options = {});

// One row of objects/aws_furniture_index.tsv (paths made absolute: relative to the index's
// parent folder's parent, i.e. the shared data folder).
struct FurnitureModel {
  std::string model;      // "ChairA_01"
  std::string category;   // the index's category: "chair", "table/desk", "structure", ...
  std::string mesh_kind;  // "visual", "visual_alt", "collision"
  std::string path;       // absolute path of the .DAE
  int triangles = 0;
  Eigen::Vector3f size_m = Eigen::Vector3f::Zero();  // x, y, z (native Z-up), metres
};
Result<std::vector<FurnitureModel>> ReadFurnitureIndex(const std::string& path);
// The index above `path` (a file or folder): <ancestor>/objects/aws_furniture_index.tsv, or
// empty when none is found.
std::string FindFurnitureIndex(const std::string& path);

// The voxplan class of a furniture model: its index category, cleaned ("table/desk" -> "desk",
// "floor covering" -> "carpet", "small object" -> "small_object"), with "structure" split by
// name. `category` may be empty (unknown model): the class is then guessed from the name.
std::string ClassForModel(const std::string& model, const std::string& category);

// Bounds of each instance from its triangles (instances without triangles keep theirs).
void ComputeInstanceBounds(World* world);

}  // namespace voxplan
