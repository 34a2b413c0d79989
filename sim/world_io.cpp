#include "sim/world_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "io/file_util.h"
#include "io/image_io.h"
#include "io/mesh_io.h"

namespace voxplan {

namespace fs = std::filesystem;

namespace {

std::string Num(float v) {
  if (v == 0.0f) v = 0.0f;  // no "-0.0000"
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4f", double(v));
  std::string s = buf;
  if (s == "-0.0000") s = "0.0000";
  return s;
}

// Tabs and newlines would break the table.
std::string Clean(const std::string& s) {
  std::string out = s;
  for (char& c : out)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return out;
}

Status CheckWorld(const World& world) {
  if (world.mesh.empty()) return InvalidArgument("the world has no triangles");
  if (world.triangle_instance.size() != world.mesh.num_triangles())
    return InvalidArgument("the world has " + std::to_string(world.triangle_instance.size()) +
                           " triangle instance ids for " +
                           std::to_string(world.mesh.num_triangles()) + " triangles");
  std::set<uint32_t> ids;
  for (const Instance& inst : world.instances) {
    if (inst.id == kNoInstance) return InvalidArgument("instance id 0 is reserved");
    if (!ids.insert(inst.id).second)
      return InvalidArgument("instance id " + std::to_string(inst.id) + " appears twice");
  }
  for (uint32_t id : world.triangle_instance)
    if (id != kNoInstance && !ids.count(id))
      return InvalidArgument("a triangle has instance id " + std::to_string(id) +
                             ", which no instance has");
  return Status::Ok();
}

}  // namespace

World GroupTrianglesByInstance(const World& world) {
  World out;
  out.name = world.name;
  out.instances = world.instances;
  out.rooms = world.rooms;
  out.mesh.positions = world.mesh.positions;
  out.mesh.normals = world.mesh.normals;
  out.mesh.colors = world.mesh.colors;
  std::map<uint32_t, size_t> rank;
  for (size_t i = 0; i < world.instances.size(); ++i) rank[world.instances[i].id] = i;
  const size_t none = world.instances.size();
  std::vector<std::vector<size_t>> groups(none + 1);
  for (size_t t = 0; t < world.mesh.num_triangles(); ++t) {
    const uint32_t id = t < world.triangle_instance.size() ? world.triangle_instance[t] : 0;
    auto it = rank.find(id);
    groups[it == rank.end() ? none : it->second].push_back(t);
  }
  out.mesh.triangles.reserve(world.mesh.num_triangles());
  out.triangle_instance.reserve(world.mesh.num_triangles());
  for (size_t g = 0; g <= none; ++g)
    for (size_t t : groups[g]) {
      out.mesh.triangles.push_back(world.mesh.triangles[t]);
      out.triangle_instance.push_back(g == none ? kNoInstance : world.instances[g].id);
    }
  return out;
}

uint64_t WorldFingerprint(const World& world) {
  const World grouped = GroupTrianglesByInstance(world);
  uint64_t h = 1469598103934665603ull;
  const auto add = [&h](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  // Corner positions by value, not vertex indices: the PLY writer shares equal vertices.
  const std::vector<Eigen::Vector3f>& p = grouped.mesh.positions;
  for (size_t t = 0; t < grouped.mesh.triangles.size(); ++t) {
    for (const uint32_t v : grouped.mesh.triangles[t])
      if (v < p.size()) add(p[v].data(), 3 * sizeof(float));
    add(&grouped.triangle_instance[t], sizeof(uint32_t));
  }
  return h;
}

std::string WorldFingerprintHex(const World& world) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx",
                static_cast<unsigned long long>(WorldFingerprint(world)));
  return text;
}

Status WriteInstanceTable(const World& world, const std::string& path) {
  std::map<uint32_t, size_t> count;
  for (uint32_t id : world.triangle_instance) ++count[id];
  // The table describes triangle order: check the world is grouped as the table says.
  size_t t = 0;
  for (const Instance& inst : world.instances) {
    const size_t n = count.count(inst.id) ? count[inst.id] : 0;
    for (size_t k = 0; k < n; ++k, ++t)
      if (t >= world.triangle_instance.size() || world.triangle_instance[t] != inst.id)
        return InvalidArgument(
            "cannot write instance table " + path +
            ": triangles are not grouped by instance (GroupTrianglesByInstance)");
  }
  std::string out = "id\tclass\tmodel\ttriangles\tmin_x\tmin_y\tmin_z\tmax_x\tmax_y\tmax_z\n";
  for (const Instance& inst : world.instances) {
    const size_t n = count.count(inst.id) ? count[inst.id] : 0;
    out += std::to_string(inst.id) + "\t" + Clean(inst.class_name) + "\t" + Clean(inst.model) +
           "\t" + std::to_string(n);
    const bool empty = inst.bounds_W.isEmpty();
    for (int k = 0; k < 6; ++k) {
      out += '\t';
      out += empty ? std::string("nan")
                   : Num(k < 3 ? inst.bounds_W.min()[k] : inst.bounds_W.max()[k - 3]);
    }
    out += "\n";
  }
  return WriteFileAtomically(path, out);
}

Status WriteRoomTable(const std::vector<Room>& rooms, const std::string& path) {
  std::string out = "name\tmin_x\tmin_y\tmax_x\tmax_y\n";
  for (const Room& r : rooms)
    out += Clean(r.name) + "\t" + Num(r.footprint_W.min().x()) + "\t" +
           Num(r.footprint_W.min().y()) + "\t" + Num(r.footprint_W.max().x()) + "\t" +
           Num(r.footprint_W.max().y()) + "\n";
  return WriteFileAtomically(path, out);
}

Result<std::vector<Room>> ReadRoomTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) return IoError("cannot open room table " + path);
  std::string line;
  std::vector<Room> rooms;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line_number == 1) {
      if (line.rfind("name\t", 0) != 0) return CorruptData(path + ": not a room table");
      continue;
    }
    if (line.empty()) continue;
    const size_t tab = line.find('\t');
    if (tab == std::string::npos) return CorruptData(path + " line " + std::to_string(line_number));
    Room room;
    room.name = line.substr(0, tab);
    float v[4];
    const char* p = line.c_str() + tab;
    for (int k = 0; k < 4; ++k) {
      char* end = nullptr;
      v[k] = std::strtof(p, &end);
      if (end == p || !std::isfinite(v[k]))
        return CorruptData(path + " line " + std::to_string(line_number) + ": bad number");
      p = end;
    }
    room.footprint_W =
        Eigen::AlignedBox2f(Eigen::Vector2f(v[0], v[1]), Eigen::Vector2f(v[2], v[3]));
    rooms.push_back(std::move(room));
  }
  return rooms;
}

Status WriteFloorPlanPng(const FloorPlan& plan, const std::string& path) {
  if (plan.width <= 0 || plan.height <= 0 ||
      plan.cells.size() != size_t(plan.width) * size_t(plan.height))
    return InvalidArgument("cannot write floor plan " + path + ": empty or inconsistent plan");
  std::vector<uint8_t> pixels(plan.cells.size());
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x) {
      const PlanCell c = plan.at(x, y);
      pixels[size_t(plan.height - 1 - y) * plan.width + x] = c == PlanCell::kFree       ? 255
                                                             : c == PlanCell::kObstacle ? 0
                                                                                        : 128;
    }
  return WritePngRaw(path, plan.width, plan.height, 1, 8, pixels.data());
}

Status WriteFloorPlanYaml(const FloorPlan& plan, const FloorPlanParams& params,
                          const std::string& image_name, const std::string& path) {
  std::string out =
      "# voxplan floor plan: gray PNG, free 255, obstacle 0, outside 128;\n"
      "# image row 0 is the largest y; origin is the lower-left corner (x, y, yaw)\n";
  out += "image: " + image_name + "\n";
  out += "resolution: " + Num(plan.resolution_m) + "\n";
  out += "origin: [" + Num(plan.origin_W.x()) + ", " + Num(plan.origin_W.y()) + ", 0.0]\n";
  out += "width: " + std::to_string(plan.width) + "\nheight: " + std::to_string(plan.height) + "\n";
  out += "min_z: " + Num(params.min_z_m) + "\nmax_z: " + Num(params.max_z_m) + "\n";
  out += "free_value: 255\nobstacle_value: 0\noutside_value: 128\n";
  return WriteFileAtomically(path, out);
}

std::vector<std::string> WorldFilePaths(const std::string& out_dir,
                                        const WorldWriteOptions& options) {
  std::vector<std::string> suffixes;
  if (options.write_ply) suffixes.push_back(".ply");
  if (options.write_glb) suffixes.push_back(".glb");
  suffixes.insert(suffixes.end(), {"_instances.tsv", "_rooms.tsv"});
  if (options.write_floor_plan)
    suffixes.insert(suffixes.end(), {"_floor_plan.png", "_floor_plan.yaml"});
  std::vector<std::string> paths;
  for (const std::string& s : suffixes)
    paths.push_back((fs::path(out_dir) / (options.basename + s)).string());
  return paths;
}

Result<WrittenWorld> WriteWorld(const World& world_in, const std::string& out_dir,
                                const WorldWriteOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(out_dir, ec))
    return InvalidArgument("output folder " + out_dir + " does not exist");
  if (options.basename.empty() || options.basename.find('/') != std::string::npos)
    return InvalidArgument("bad world file name '" + options.basename + "'");
  VOXPLAN_RETURN_IF_ERROR(CheckWorld(world_in).WithContext("cannot write world to " + out_dir));
  const World world = GroupTrianglesByInstance(world_in);
  WrittenWorld written;
  auto file = [&](const std::string& suffix) {
    return (fs::path(out_dir) / (options.basename + suffix)).string();
  };
  if (options.write_ply) {
    VOXPLAN_RETURN_IF_ERROR(WriteMesh(world.mesh, file(".ply")));
    written.paths.push_back(file(".ply"));
  }
  if (options.write_glb) {
    VOXPLAN_RETURN_IF_ERROR(WriteMesh(world.mesh, file(".glb")));
    written.paths.push_back(file(".glb"));
  }
  VOXPLAN_RETURN_IF_ERROR(WriteInstanceTable(world, file("_instances.tsv")));
  written.paths.push_back(file("_instances.tsv"));
  if (!world.rooms.empty()) {
    VOXPLAN_RETURN_IF_ERROR(WriteRoomTable(world.rooms, file("_rooms.tsv")));
    written.paths.push_back(file("_rooms.tsv"));
  }
  if (options.write_floor_plan) {
    Result<FloorPlan> plan = RasterizeFloorPlan(world, options.floor_plan);
    if (!plan.ok()) return plan.status();
    VOXPLAN_RETURN_IF_ERROR(WriteFloorPlanPng(plan.value(), file("_floor_plan.png")));
    written.paths.push_back(file("_floor_plan.png"));
    VOXPLAN_RETURN_IF_ERROR(WriteFloorPlanYaml(plan.value(), options.floor_plan,
                                               options.basename + "_floor_plan.png",
                                               file("_floor_plan.yaml")));
    written.paths.push_back(file("_floor_plan.yaml"));
    written.floor_plan = std::move(plan.value());
  }
  return written;
}

}  // namespace voxplan
