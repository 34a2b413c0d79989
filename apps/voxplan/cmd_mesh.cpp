// voxplan mesh: map file -> mesh file.
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "core/parallel.h"
#include "fusion/mesh_extract.h"
#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/sharded_map.h"

namespace voxplan::cli {

namespace {

struct MeshOptions {
  std::string map_path;
  std::string out_path;
  double min_weight = 0.5;
  bool no_color = false;
  int threads = 0;
};

int RunMesh(const MeshOptions& o) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(o.map_path, ec)) {
    return Fail("map file not found: " + o.map_path);
  }
  if (int code = RefusePathCollisions({{"--out", o.out_path}}, {{"the map", o.map_path}});
      code != kExitOk)
    return code;
  ThreadLimit thread_limit(o.threads);
  const Stopwatch load_clock;
  Result<TsdfVolume> volume = LoadAnyMap(o.map_path);  // plain or sharded
  if (!volume.ok()) return Fail(MessageNaming(volume.status(), o.map_path));
  const double load_ms = load_clock.ElapsedMs();

  MeshParams params;
  params.min_weight = float(o.min_weight);
  params.with_color = !o.no_color;
  const Stopwatch mesh_clock;
  const Mesh mesh = ExtractMesh(*volume, params);
  const double mesh_ms = mesh_clock.ElapsedMs();
  if (mesh.empty())
    return Fail("the map holds no surface at --min-weight " + std::to_string(o.min_weight) + ": " +
                o.map_path);
  if (Status s = WriteMesh(mesh, o.out_path); !s.ok()) return Fail(MessageNaming(s, o.out_path));

  nlohmann::json j;
  j["command"] = "mesh";
  j["map"] = o.map_path;
  j["out"] = o.out_path;
  j["voxel_size_m"] = ShortestDouble(volume->voxel_size_m());
  j["trunc_m"] = ShortestDouble(volume->trunc_m());
  j["min_weight"] = o.min_weight;
  j["threads"] = MaxThreads();
  j["load_ms"] = RoundTo(load_ms, 3);
  AddMapStats(j, *volume);
  AddMeshStats(j, mesh, mesh_ms);
  std::cerr << "mesh: " << o.out_path << " (" << mesh.num_vertices() << " vertices, "
            << mesh.num_triangles() << " triangles) from " << volume->num_blocks() << " blocks in "
            << j["mesh_ms"] << " ms\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddMeshCommand(CLI::App& app) {
  auto o = std::make_shared<MeshOptions>();
  CLI::App* sub = app.add_subcommand("mesh", "Extract a mesh from a map file");
  sub->add_option("map", o->map_path, "Map file (.vpmap)")->required();
  sub->add_option("--out,-o", o->out_path, "Mesh to write (.ply .obj .glb .stl)")
      ->required()
      ->check(MeshOutputValidator());
  sub->add_option("--min-weight", o->min_weight, "Voxels with less weight count as unobserved")
      ->check(InRange(0.0, kMaxWeight))
      ->capture_default_str();
  sub->add_flag("--no-color", o->no_color, "Leave vertex colours out");
  sub->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(ThreadCount())
      ->capture_default_str();
  return {sub, [o] { return RunMesh(*o); }};
}

}  // namespace voxplan::cli
