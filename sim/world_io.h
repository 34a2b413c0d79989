#pragma once
// Writing a World to a folder, and the instance / room tables that let LoadWorld read it back.
//
// WriteWorld(world, dir) writes, all atomically (temporary file, then rename):
//   <name>.ply / <name>.glb     the mesh, triangles grouped by instance: the triangles of the
//                               instance table's first row, then the second row's, ..., then the
//                               kNoInstance triangles (the table's `triangles` column gives the
//                               counts; mesh readers keep triangle order, so no per-triangle
//                               label file is needed)
//   <name>_instances.tsv        id, class, model, triangles, bbox min x y z, max x y z
//   <name>_rooms.tsv            name, footprint min x y, max x y (only when there are rooms)
//   <name>_floor_plan.png       RasterizeFloorPlan as 8-bit gray: free 255, obstacle 0,
//                               outside 128; image row 0 is the plan's largest y (north up)
//   <name>_floor_plan.yaml      ROS map_server-style metadata: image, resolution, origin, band
// Same World and options -> the same bytes in every file.
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "sim/floor_plan.h"
#include "sim/world.h"

namespace voxplan {

struct WorldWriteOptions {
  std::string basename = "world";
  bool write_ply = true;
  bool write_glb = true;
  bool write_floor_plan = true;
  FloorPlanParams floor_plan;
};

struct WrittenWorld {
  std::vector<std::string> paths;  // every file written, in the order above
  FloorPlan floor_plan;            // empty unless write_floor_plan
};

// `out_dir` must exist. The world must be consistent (one triangle_instance per triangle, ids
// unique and listed in `instances`).
Result<WrittenWorld> WriteWorld(const World& world, const std::string& out_dir,
                                const WorldWriteOptions& options = {});
// Every file WriteWorld may write with these options (the room table even when there are no
// rooms), known before the world exists: what a caller checks against its inputs.
std::vector<std::string> WorldFilePaths(const std::string& out_dir,
                                        const WorldWriteOptions& options = {});

// The world with its triangles reordered as WriteWorld stores them (grouped by instance in the
// order of world.instances, kNoInstance last; order kept within a group); vertices untouched.
World GroupTrianglesByInstance(const World& world);

// FNV-1a (64 bit) over the world as WriteWorld stores it (GroupTrianglesByInstance): each
// triangle's corner positions and instance id, in order. A world read back from WriteWorld's files
// has the same; another seed, another furniture set or a moved floor has another.
uint64_t WorldFingerprint(const World& world);
// As 16 lower-case hex digits (metrics.json's world_fingerprint).
std::string WorldFingerprintHex(const World& world);

Status WriteInstanceTable(const World& world, const std::string& path);  // world grouped
Status WriteRoomTable(const std::vector<Room>& rooms, const std::string& path);
Result<std::vector<Room>> ReadRoomTable(const std::string& path);
// 8-bit gray PNG, values as above.
Status WriteFloorPlanPng(const FloorPlan& plan, const std::string& path);
Status WriteFloorPlanYaml(const FloorPlan& plan, const FloorPlanParams& params,
                          const std::string& image_name, const std::string& path);

}  // namespace voxplan
