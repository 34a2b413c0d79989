#include "sim/scene_loader.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "io/assimp_material.h"
#include "io/mesh_import.h"
#include "sim/world_io.h"

namespace voxplan {

namespace fs = std::filesystem;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::vector<std::string> SplitTabs(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t tab = line.find('\t', start);
    out.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) break;
    start = tab + 1;
  }
  if (!out.empty() && !out.back().empty() && out.back().back() == '\r') out.back().pop_back();
  return out;
}

bool ParseLong(const std::string& s, long long* v) {
  const char* end = s.data() + s.size();
  auto [p, ec] = std::from_chars(s.data(), end, *v);
  return ec == std::errc() && p == end;
}

bool ParseFloat(const std::string& s, float* v) {
  if (s.empty()) return false;
  char* end = nullptr;
  *v = std::strtof(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(*v);
}

// Reads a TSV: header names -> column index, then rows (blank lines skipped).
struct Tsv {
  std::map<std::string, size_t> columns;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> line_numbers;
  int Column(const std::string& name) const {
    auto it = columns.find(name);
    return it == columns.end() ? -1 : int(it->second);
  }
};

Result<Tsv> ReadTsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) return IoError("cannot open " + path);
  Tsv tsv;
  std::string line;
  int line_number = 0;
  bool header = true;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    std::vector<std::string> fields = SplitTabs(line);
    if (header) {
      for (size_t i = 0; i < fields.size(); ++i) tsv.columns[fields[i]] = i;
      header = false;
      continue;
    }
    if (fields.size() != tsv.columns.size())
      return CorruptData(path + " line " + std::to_string(line_number) + ": " +
                         std::to_string(fields.size()) + " fields, the header has " +
                         std::to_string(tsv.columns.size()));
    tsv.rows.push_back(std::move(fields));
    tsv.line_numbers.push_back(line_number);
  }
  if (in.bad()) return IoError("error reading " + path);
  if (header) return CorruptData(path + " is empty (no header line)");
  return tsv;
}

constexpr const char* kAwsPrefix = "aws_robomaker_residential_";

std::string StripAwsPrefix(const std::string& model) {
  const size_t n = std::strlen(kAwsPrefix);
  return model.compare(0, n, kAwsPrefix) == 0 ? model.substr(n) : model;
}

// "Chair_01.002" -> "chair"; "KitchenTable" -> "kitchentable".
std::string GuessClassFromName(const std::string& name) {
  const std::string l = Lower(name);
  static const std::pair<const char*, const char*> kKeywords[] = {
      {"ceiling", "ceiling"},   {"floor", "floor"},
      {"wall", "wall"},         {"window", "window"},
      {"door", "door"},         {"chair", "chair"},
      {"sofa", "sofa"},         {"couch", "sofa"},
      {"bed", "bed"},           {"desk", "desk"},
      {"table", "table"},       {"shelf", "shelf"},
      {"wardrobe", "wardrobe"}, {"cabinet", "cabinet"},
      {"lamp", "lamp"},         {"tv", "tv"},
      {"fridge", "appliance"},  {"refrigerator", "appliance"},
      {"carpet", "carpet"},     {"rug", "carpet"},
      {"plant", "plant"},
  };
  for (const auto& [key, cls] : kKeywords)
    if (l.find(key) != std::string::npos) return cls;
  std::string out;
  for (char c : l) {
    if (std::isalpha(static_cast<unsigned char>(c)))
      out += c;
    else if (!out.empty() && out.back() != '_')
      out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out.empty() ? "object" : out;
}

struct InstanceRow {
  uint32_t id = kNoInstance;
  std::string class_name, model;
  long long triangles = 0;
  Eigen::AlignedBox3f bounds;  // from the table (ours), else empty
};

struct InstanceTable {
  std::vector<InstanceRow> rows;
  bool own_format = false;  // written by WriteWorld (has an id column)
};

Result<InstanceTable> ReadInstanceTable(const std::string& path,
                                        const std::vector<FurnitureModel>& index) {
  Result<Tsv> tsv = ReadTsv(path);
  if (!tsv.ok()) return tsv.status();
  const int c_tri = tsv->Column("triangles");
  const int c_id = tsv->Column("id");
  const int c_class = tsv->Column("class");
  const int c_model = tsv->Column("model");
  const int c_name = tsv->Column("instance");
  if (c_tri < 0)
    return CorruptData(path +
                       ": instance table has no 'triangles' column (header: id or "
                       "instance, model, class, triangles, ...)");
  if (c_model < 0 && c_name < 0 && c_class < 0)
    return CorruptData(path + ": instance table has none of the columns model, instance, class");
  std::map<std::string, std::string> category;
  for (const FurnitureModel& m : index)
    if (!category.count(m.model)) category[m.model] = m.category;

  InstanceTable table;
  table.own_format = c_id >= 0;
  std::set<uint32_t> seen;
  const char* bbox_names[6] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"};
  int c_bbox[6];
  bool has_bbox = true;
  for (int k = 0; k < 6; ++k) {
    c_bbox[k] = tsv->Column(bbox_names[k]);
    if (c_bbox[k] < 0) has_bbox = false;
  }
  uint32_t next_id = 1;
  for (size_t r = 0; r < tsv->rows.size(); ++r) {
    const auto& f = tsv->rows[r];
    const std::string where = path + " line " + std::to_string(tsv->line_numbers[r]);
    InstanceRow row;
    if (!ParseLong(f[c_tri], &row.triangles) || row.triangles < 0)
      return CorruptData(where + ": bad triangle count '" + f[c_tri] + "'");
    if (c_id >= 0) {
      long long id = 0;
      if (!ParseLong(f[c_id], &id) || id < 1 || id > UINT32_MAX)
        return CorruptData(where + ": bad instance id '" + f[c_id] + "' (ids are >= 1)");
      row.id = uint32_t(id);
      if (!seen.insert(row.id).second)
        return CorruptData(where + ": instance id " + f[c_id] + " appears twice");
    } else {
      // A foreign table: instances not in the mesh (0 triangles) are not in the world.
      if (row.triangles == 0) continue;
      row.id = next_id++;
    }
    const std::string raw_model = c_model >= 0 ? f[c_model] : (c_name >= 0 ? f[c_name] : "");
    row.model = StripAwsPrefix(raw_model);
    if (c_class >= 0 && !f[c_class].empty()) {
      row.class_name = f[c_class];
    } else {
      auto it = category.find(row.model);
      row.class_name = ClassForModel(row.model.empty() && c_name >= 0 ? f[c_name] : row.model,
                                     it == category.end() ? "" : it->second);
    }
    if (has_bbox) {
      float v[6];
      bool ok = true;
      for (int k = 0; k < 6; ++k) ok = ok && ParseFloat(f[c_bbox[k]], &v[k]);
      if (ok && v[0] <= v[3] && v[1] <= v[4] && v[2] <= v[5])
        row.bounds = Eigen::AlignedBox3f(Eigen::Vector3f(v[0], v[1], v[2]),
                                         Eigen::Vector3f(v[3], v[4], v[5]));
    }
    table.rows.push_back(std::move(row));
  }
  return table;
}

// The triangles of one or more assimp meshes appended to a Mesh, transformed into the world.
struct MeshBuilder {
  const aiScene& scene;
  const SceneLoadOptions& options;
  bool format_has_materials;
  bool any_color = false, all_normals = true;
  Mesh mesh;

  Eigen::Vector3f Orient(const aiVector3D& v, float k) const {
    if (options.up == UpAxis::kY) return {k * v.x, -k * v.z, k * v.y};
    return {k * v.x, k * v.y, k * v.z};
  }

  bool MaterialDiffuse(unsigned int index, aiColor4D* color) const {
    return internal::MaterialDiffuse(scene, index, format_has_materials, color);
  }

  static bool IsTriangleMesh(const aiMesh& m) {
    return (m.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) && m.mNumFaces > 0;
  }

  void Survey() {
    for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
      const aiMesh& mesh_in = *scene.mMeshes[m];
      if (!IsTriangleMesh(mesh_in)) continue;
      aiColor4D c;
      if (mesh_in.HasVertexColors(0) || MaterialDiffuse(mesh_in.mMaterialIndex, &c))
        any_color = true;
      if (!mesh_in.HasNormals()) all_normals = false;
    }
  }

  // Appends mesh m under the node transform; returns the number of triangles added.
  Result<size_t> Append(unsigned int m, const aiMatrix4x4& transform) {
    const aiMesh& in = *scene.mMeshes[m];
    if (!IsTriangleMesh(in)) return size_t(0);
    const size_t base = mesh.positions.size();
    if (base + in.mNumVertices > size_t(UINT32_MAX))
      return Unsupported("more vertices than 32-bit indices can address");
    aiMatrix3x3 normal_matrix(transform);
    normal_matrix.Inverse().Transpose();
    for (unsigned int v = 0; v < in.mNumVertices; ++v)
      mesh.positions.push_back(Orient(transform * in.mVertices[v], options.scale));
    if (all_normals) {
      for (unsigned int v = 0; v < in.mNumVertices; ++v) {
        Eigen::Vector3f n = Orient(normal_matrix * in.mNormals[v], 1.0f);
        const float len = n.norm();
        mesh.normals.push_back(len > 0.0f && std::isfinite(len) ? Eigen::Vector3f(n / len)
                                                                : Eigen::Vector3f::UnitZ());
      }
    }
    if (any_color) {
      aiColor4D diffuse(0.6f, 0.6f, 0.6f, 1.0f);
      const bool has_vertex_colors = in.HasVertexColors(0);
      if (!has_vertex_colors) MaterialDiffuse(in.mMaterialIndex, &diffuse);
      auto to_byte = [](float c) -> uint8_t {
        if (!std::isfinite(c)) return 0;
        return uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
      };
      for (unsigned int v = 0; v < in.mNumVertices; ++v) {
        const aiColor4D& c = has_vertex_colors ? in.mColors[0][v] : diffuse;
        mesh.colors.push_back({to_byte(c.r), to_byte(c.g), to_byte(c.b)});
      }
    }
    size_t added = 0;
    for (unsigned int f = 0; f < in.mNumFaces; ++f) {
      const aiFace& face = in.mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back({uint32_t(base + face.mIndices[0]),
                                uint32_t(base + face.mIndices[1]),
                                uint32_t(base + face.mIndices[2])});
      ++added;
    }
    return added;
  }
};

struct NodeMeshes {
  std::string name;
  std::vector<unsigned int> meshes;
  aiMatrix4x4 transform;
};

void CollectNodes(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                  std::vector<NodeMeshes>* out) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  std::vector<unsigned int> meshes;
  for (unsigned int i = 0; i < node.mNumMeshes; ++i) {
    const unsigned int m = node.mMeshes[i];
    if (m < scene.mNumMeshes && MeshBuilder::IsTriangleMesh(*scene.mMeshes[m])) meshes.push_back(m);
  }
  if (!meshes.empty()) {
    std::string name = node.mName.C_Str();
    if (name.empty() && node.mNumMeshes == 1) name = scene.mMeshes[meshes[0]]->mName.C_Str();
    out->push_back({name, meshes, transform});
  }
  for (unsigned int c = 0; c < node.mNumChildren; ++c)
    CollectNodes(scene, *node.mChildren[c], transform, out);
}

// The scene's mesh and its nodes (name, triangle count), in the world frame. Every format goes
// through io's validating loader: PLY by ReadMesh (one node), the others by its confined assimp.
struct ImportedMesh {
  Mesh mesh;
  std::vector<std::string> node_names;
  std::vector<size_t> node_triangles;
};

Result<ImportedMesh> ImportSceneMesh(const std::string& path, const SceneLoadOptions& options) {
  ImportedMesh out;
  if (Lower(fs::path(path).extension().string()) == ".ply") {
    Result<Mesh> mesh = ReadMesh(path, {options.scale, options.up});
    if (!mesh.ok()) return mesh.status();
    out.mesh = std::move(mesh.value());
    out.node_names = {""};
    out.node_triangles = {out.mesh.num_triangles()};
    return out;
  }
  Result<internal::AssimpScene> imported = internal::ImportWithAssimp(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!imported.ok()) return imported.status();
  const aiScene& scene = *imported->scene;
  const std::string ext = Lower(fs::path(path).extension().string());
  MeshBuilder builder{scene, options, ext != ".stl", false, true, Mesh()};
  builder.Survey();
  std::vector<NodeMeshes> nodes;
  CollectNodes(scene, *scene.mRootNode, aiMatrix4x4(), &nodes);
  for (const NodeMeshes& node : nodes) {
    size_t n = 0;
    for (unsigned int m : node.meshes) {
      Result<size_t> added = builder.Append(m, node.transform);
      if (!added.ok()) return added.status().WithContext("scene " + path);
      n += added.value();
    }
    out.node_names.push_back(node.name);
    out.node_triangles.push_back(n);
  }
  out.mesh = std::move(builder.mesh);
  VOXPLAN_RETURN_IF_ERROR(internal::CheckMeshGeometry(path, out.mesh));
  return out;
}

std::string SiblingPath(const std::string& mesh_path, const std::string& suffix) {
  const fs::path p(mesh_path);
  return (p.parent_path() / (p.stem().string() + suffix)).string();
}

std::string FormatNumber(float v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string FormatMetres(float v) {
  std::ostringstream s;
  s.precision(v >= 1000.0f ? 0 : 2);
  s << std::fixed << v;
  return s.str();
}

}  // namespace

std::string ClassForModel(const std::string& model, const std::string& category) {
  const std::string l = Lower(model);
  if (category.empty()) return GuessClassFromName(model);
  if (category == "structure") {
    // Order matters: "RoomWindow" is a window, "FoldingDoor" a door, "HouseWall" a wall.
    for (const char* key : {"ceiling", "window", "door", "floor", "wall"})
      if (l.find(key) != std::string::npos) return key;
    return "structure";
  }
  if (category == "table/desk") return "desk";
  if (category == "floor covering") return "carpet";
  std::string out = category;
  std::replace(out.begin(), out.end(), ' ', '_');
  std::replace(out.begin(), out.end(), '/', '_');
  return out;
}

Result<std::vector<FurnitureModel>> ReadFurnitureIndex(const std::string& path) {
  Result<Tsv> tsv = ReadTsv(path);
  if (!tsv.ok()) return tsv.status();
  const int c_model = tsv->Column("model"), c_cat = tsv->Column("category"),
            c_kind = tsv->Column("mesh_kind"), c_path = tsv->Column("path_in_staging"),
            c_tri = tsv->Column("triangles"), c_x = tsv->Column("size_x_m"),
            c_y = tsv->Column("size_y_m"), c_z = tsv->Column("size_z_up_m");
  if (c_model < 0 || c_cat < 0 || c_kind < 0 || c_path < 0 || c_tri < 0 || c_x < 0 || c_y < 0 ||
      c_z < 0)
    return CorruptData(path +
                       ": not a furniture index (needs columns model, category, "
                       "mesh_kind, path_in_staging, triangles, size_x_m, size_y_m, size_z_up_m)");
  // Paths are relative to the index folder's parent (the shared data folder).
  const fs::path data_dir = fs::path(path).parent_path().parent_path();
  std::vector<FurnitureModel> out;
  for (size_t r = 0; r < tsv->rows.size(); ++r) {
    const auto& f = tsv->rows[r];
    FurnitureModel m;
    m.model = f[c_model];
    m.category = f[c_cat];
    m.mesh_kind = f[c_kind];
    m.path = (data_dir / f[c_path]).lexically_normal().string();
    long long tri = 0;
    if (!ParseLong(f[c_tri], &tri) || !ParseFloat(f[c_x], &m.size_m.x()) ||
        !ParseFloat(f[c_y], &m.size_m.y()) || !ParseFloat(f[c_z], &m.size_m.z()))
      return CorruptData(path + " line " + std::to_string(tsv->line_numbers[r]) + ": bad number");
    m.triangles = int(tri);
    out.push_back(std::move(m));
  }
  return out;
}

std::string FindFurnitureIndex(const std::string& path) {
  std::error_code ec;
  fs::path dir = fs::absolute(fs::path(path), ec).lexically_normal();
  if (ec) return {};
  if (!fs::is_directory(dir, ec)) dir = dir.parent_path();
  for (int depth = 0; depth < 8 && !dir.empty(); ++depth) {
    const fs::path candidate = dir / "objects" / "aws_furniture_index.tsv";
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
    if (dir == dir.parent_path()) break;
    dir = dir.parent_path();
  }
  return {};
}

void ComputeInstanceBounds(World* world) {
  std::map<uint32_t, Eigen::AlignedBox3f> boxes;
  const Mesh& mesh = world->mesh;
  for (size_t t = 0; t < mesh.triangles.size() && t < world->triangle_instance.size(); ++t) {
    const uint32_t id = world->triangle_instance[t];
    if (id == kNoInstance) continue;
    Eigen::AlignedBox3f& box = boxes[id];
    for (uint32_t v : mesh.triangles[t]) box.extend(mesh.positions[v]);
  }
  for (Instance& inst : world->instances) {
    auto it = boxes.find(inst.id);
    if (it != boxes.end()) inst.bounds_W = it->second;
  }
}

Result<World> LoadWorld(const std::string& path, const SceneLoadOptions& options) {
  // Refusals before any work.
  if (!(std::isfinite(options.scale) && options.scale > 0.0f))
    return InvalidArgument("scale must be a positive number, got " + FormatNumber(options.scale));
  if (!(options.min_extent_m > 0.0f && options.max_extent_m > options.min_extent_m))
    return InvalidArgument("scene extent limits must satisfy 0 < min < max");
  if (!(std::isfinite(options.floor_z_m) && std::abs(options.floor_z_m) <= options.max_extent_m))
    return InvalidArgument("floor height must be a number within +-" +
                           FormatMetres(options.max_extent_m) + " m, got " +
                           FormatNumber(options.floor_z_m));
  std::error_code ec;
  if (!fs::exists(path, ec)) return NotFound("no such scene file: " + path);
  if (!fs::is_regular_file(path, ec)) return InvalidArgument("not a file: " + path);
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) return IoError("cannot open scene file " + path);
  }
  if (!IsSupportedMeshExtension(path) && Lower(fs::path(path).extension().string()) != ".dae")
    return InvalidArgument("cannot read scene " + path +
                           ": unsupported extension (use .ply, .obj, .glb, .stl or .dae)");
  std::string table_path = options.instance_table;
  if (options.use_instance_table && table_path.empty()) {
    const std::string sibling = SiblingPath(path, "_instances.tsv");
    if (fs::is_regular_file(sibling, ec)) table_path = sibling;
  }
  if (options.use_instance_table && !table_path.empty() && !fs::is_regular_file(table_path, ec))
    return NotFound("no such instance table: " + table_path);
  std::vector<FurnitureModel> index;
  const std::string index_path =
      options.furniture_index.empty() ? FindFurnitureIndex(path) : options.furniture_index;
  if (!index_path.empty()) {
    Result<std::vector<FurnitureModel>> read = ReadFurnitureIndex(index_path);
    if (!read.ok()) {
      if (!options.furniture_index.empty()) return read.status();
    } else {
      index = std::move(read.value());
    }
  }
  InstanceTable table;
  const bool have_table = options.use_instance_table && !table_path.empty();
  if (have_table) {
    Result<InstanceTable> read = ReadInstanceTable(table_path, index);
    if (!read.ok()) return read.status();
    table = std::move(read.value());
  }

  Result<ImportedMesh> imported = ImportSceneMesh(path, options);
  if (!imported.ok()) return imported.status();
  World world;
  world.name = fs::path(path).stem().string();
  world.mesh = std::move(imported->mesh);
  const std::vector<std::string>& node_names = imported->node_names;
  const std::vector<size_t>& node_triangles = imported->node_triangles;

  // Absurd scale: the scene's horizontal size must look like a building.
  Eigen::AlignedBox3f box;
  for (const auto& p : world.mesh.positions) box.extend(p);
  const Eigen::Vector3f size = box.sizes();
  const float extent = std::max(size.x(), size.y());
  if (!std::isfinite(extent) || extent > options.max_extent_m || extent < options.min_extent_m)
    return InvalidArgument(
        "scene " + path + " is " + FormatMetres(size.x()) + " x " + FormatMetres(size.y()) + " x " +
        FormatMetres(size.z()) + " m after scaling (scale " + FormatNumber(options.scale) +
        "); a scene must be between " + FormatMetres(options.min_extent_m) + " and " +
        FormatMetres(options.max_extent_m) + " m across: wrong --scale or units" +
        (extent > options.max_extent_m ? " (a house 1 km wide?)" : " (a house 2 cm wide?)") +
        ", or wrong --up");
  float floor_z = options.floor_z_m;
  if (options.detect_floor) {
    Result<FloorDetection> found = DetectFloor(world.mesh, options.floor_detect);
    if (!found.ok())
      return Status(found.status().code(), "scene " + path + ": " + found.status().message() +
                                               "; give its floor height instead of detecting it");
    floor_z = found->z_m;
  }
  world.source_floor_z_m = floor_z;
  if (floor_z != 0.0f)
    for (Eigen::Vector3f& p : world.mesh.positions) p.z() -= floor_z;

  const size_t num_tri = world.mesh.triangles.size();
  world.triangle_instance.assign(num_tri, kNoInstance);
  if (have_table) {
    long long total = 0;
    for (const InstanceRow& row : table.rows) total += row.triangles;
    if (total > (long long)num_tri)
      return CorruptData("instance table " + table_path + " lists " + std::to_string(total) +
                         " triangles, the mesh " + path + " has " + std::to_string(num_tri) +
                         " (not the table of this mesh?)");
    size_t t = 0;
    uint32_t max_id = 0;
    for (const InstanceRow& row : table.rows) {
      Instance inst;
      inst.id = row.id;
      inst.class_name = row.class_name;
      inst.model = row.model;
      inst.bounds_W = row.bounds;  // as the table has it (ComputeInstanceBounds redoes most)
      if (!inst.bounds_W.isEmpty() && floor_z != 0.0f) {
        inst.bounds_W.min().z() -= floor_z;
        inst.bounds_W.max().z() -= floor_z;
      }
      for (long long k = 0; k < row.triangles; ++k) world.triangle_instance[t++] = row.id;
      world.instances.push_back(std::move(inst));
      max_id = std::max(max_id, row.id);
    }
    if (t < num_tri && !table.own_format) {
      Instance rest;
      rest.id = max_id + 1;
      rest.class_name = "structure";
      rest.model = "unlisted";
      for (; t < num_tri; ++t) world.triangle_instance[t] = rest.id;
      world.instances.push_back(std::move(rest));
    }
  } else if (node_names.size() > 1) {
    size_t t = 0;
    for (size_t n = 0; n < node_names.size(); ++n) {
      if (node_triangles[n] == 0) continue;
      Instance inst;
      inst.id = uint32_t(world.instances.size() + 1);
      inst.model = node_names[n].empty() ? "node_" + std::to_string(n) : node_names[n];
      std::string category;
      for (const FurnitureModel& m : index)
        if (m.model == StripAwsPrefix(inst.model)) category = m.category;
      inst.class_name = ClassForModel(inst.model, category);
      for (size_t k = 0; k < node_triangles[n]; ++k) world.triangle_instance[t++] = inst.id;
      world.instances.push_back(std::move(inst));
    }
  }
  std::sort(world.instances.begin(), world.instances.end(),
            [](const Instance& a, const Instance& b) { return a.id < b.id; });
  ComputeInstanceBounds(&world);

  const std::string rooms_path = SiblingPath(path, "_rooms.tsv");
  if (fs::is_regular_file(rooms_path, ec)) {
    Result<std::vector<Room>> rooms = ReadRoomTable(rooms_path);
    if (!rooms.ok()) return rooms.status();
    world.rooms = std::move(rooms.value());
    // Footprints are in the written world's frame: follow a rescale; a Y-up re-read has no
    // meaningful footprints.
    if (options.up != UpAxis::kZ) world.rooms.clear();
    for (Room& room : world.rooms)
      room.footprint_W = Eigen::AlignedBox2f(room.footprint_W.min() * options.scale,
                                             room.footprint_W.max() * options.scale);
  }
  return world;
}

}  // namespace voxplan
