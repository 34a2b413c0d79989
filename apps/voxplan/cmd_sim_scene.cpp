// voxplan sim scene: generate an apartment, or load a scene file, and write the world (mesh,
// instance table, rooms, floor plan) to a folder.
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "apps/voxplan/signals.h"
#include "sim/apartment.h"
#include "sim/floor_plan.h"
#include "sim/scene_loader.h"
#include "sim/world_io.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct SimSceneOptions {
  std::string generate;
  std::string scene;
  std::string size = "M";
  uint64_t seed = 0;
  SceneFrameOptions frame;
  std::string out_dir;
  std::string name = "world";
  std::string furniture_index;
  bool no_furniture_meshes = false;
  bool no_ceiling = false;
  double resolution = 0.05;
  bool no_ply = false, no_glb = false;
};

// The shared data's furniture index: $VOXPLAN_SHARED_DATA, else ../shared/data beside the
// source tree, else ../shared/data from the working folder.
std::string DefaultFurnitureIndex() {
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("VOXPLAN_SHARED_DATA")) roots.emplace_back(env);
  roots.push_back(fs::path(VOXPLAN_SOURCE_DIR) / ".." / "shared" / "data");
  roots.push_back(fs::path("..") / "shared" / "data");
  std::error_code ec;
  for (const fs::path& root : roots) {
    const fs::path p = root / "objects" / "aws_furniture_index.tsv";
    if (fs::is_regular_file(p, ec)) return p.lexically_normal().string();
  }
  return {};
}

int RunSimScene(const SimSceneOptions& o) {
  // Usage checks, before any work.
  if (o.generate.empty() == o.scene.empty())
    return Fail("give exactly one of --generate apartment or --scene FILE", kExitUsage);
  if (!o.generate.empty() && o.generate != "apartment")
    return Fail("--generate knows only 'apartment', got '" + o.generate + "'", kExitUsage);
  Result<ApartmentSize> size = ParseApartmentSize(o.size);
  if (!size.ok()) return Fail(size.status().message(), kExitUsage);
  if (o.no_ply && o.no_glb && o.scene.empty())
    return Fail("--no-ply with --no-glb would write no mesh", kExitUsage);
  std::error_code ec;
  const fs::path out(o.out_dir);
  const bool create_out = !fs::is_directory(out, ec);
  if (create_out) {
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (fs::exists(out, ec)) return Fail("--out " + o.out_dir + " is not a folder", kExitUsage);
    if (!fs::is_directory(parent, ec))
      return Fail("output folder's parent does not exist: " + parent.string(), kExitUsage);
  }
  if (!o.scene.empty() && !fs::is_regular_file(o.scene, ec))
    return Fail("scene file not found: " + o.scene);
  WorldWriteOptions write;
  write.basename = o.name;
  write.write_ply = !o.no_ply;
  write.write_glb = !o.no_glb;
  write.floor_plan.resolution_m = float(o.resolution);
  std::vector<PathUse> outputs;
  for (const std::string& path : WorldFilePaths(o.out_dir, write))
    outputs.push_back({"--out", path});
  if (int code = RefusePathCollisions(
          outputs, {{"--scene", o.scene}, {"--furniture-index", o.furniture_index}});
      code != kExitOk)
    return code;

  const Stopwatch clock;
  Result<World> world = Status(StatusCode::kInternal, "no world");
  std::string furniture_index;
  if (!o.generate.empty()) {
    ApartmentParams params;
    params.size = size.value();
    params.seed = o.seed;
    params.ceiling = !o.no_ceiling;
    if (!o.no_furniture_meshes) {
      furniture_index = o.furniture_index.empty() ? DefaultFurnitureIndex() : o.furniture_index;
      if (!o.furniture_index.empty() && !fs::is_regular_file(o.furniture_index, ec))
        return Fail("furniture index not found: " + o.furniture_index);
      if (furniture_index.empty())
        Warn("no furniture index found (--furniture-index): parametric furniture only");
    }
    params.furniture_index = furniture_index;
    world = GenerateApartment(params);
    if (!world.ok()) return Fail(world.status().message());
  } else {
    SceneLoadOptions load = SceneLoad(o.frame);
    load.furniture_index = o.furniture_index;
    world = LoadWorld(o.scene, load);
    if (!world.ok()) {
      const bool usage = world.status().code() == StatusCode::kInvalidArgument;
      return Fail(MessageNaming(world.status(), o.scene), usage ? kExitUsage : kExitFailure);
    }
  }
  const double build_ms = clock.ElapsedMs();
  // The folder is made only once there is a world to write into it; every file lands, or none.
  OutputTransaction transaction;
  transaction.WatchFolder(o.out_dir);
  if (create_out && !fs::create_directory(out, ec))
    return Fail("cannot create output folder " + o.out_dir + ": " + ec.message());
  const Stopwatch write_clock;
  Result<WrittenWorld> written = WriteWorld(world.value(), o.out_dir, write);
  if (!written.ok()) return Fail(written.status().message());
  if (int code = CommitOutputs(transaction); code != kExitOk) return code;
  const double write_ms = write_clock.ElapsedMs();

  const FloorPlan& plan = written->floor_plan;
  size_t free_cells = 0, inside_cells = 0;
  for (PlanCell c : plan.cells) {
    free_cells += c == PlanCell::kFree;
    inside_cells += c != PlanCell::kOutside;
  }
  const double cell_area = double(plan.resolution_m) * plan.resolution_m;
  double room_area = 0.0;
  for (const Room& r : world->rooms) room_area += r.footprint_W.volume();

  nlohmann::json j;
  j["command"] = "sim scene";
  if (!o.generate.empty()) {
    j["generate"] = o.generate;
    j["size"] = ApartmentSizeName(size.value());
    j["seed"] = o.seed;
    j["furniture_index"] = furniture_index;
  } else {
    j["scene"] = o.scene;
    j["scale"] = o.frame.scale;
    j["up"] = o.frame.up;
    // The file's floor height the world was moved down by; only with --floor-z, as asked.
    if (o.frame.floor_z != "0") j["floor_z_m"] = double(world->source_floor_z_m);
  }
  j["out"] = o.out_dir;
  j["area_m2"] = RoundTo(inside_cells * cell_area, 2);  // floor plan: everything not outside
  j["free_area_m2"] = RoundTo(free_cells * cell_area, 2);
  j["room_area_m2"] = RoundTo(room_area, 2);
  j["rooms"] = world->rooms.size();
  j["instances"] = world->instances.size();
  j["triangles"] = world->mesh.num_triangles();
  j["vertices"] = world->mesh.num_vertices();
  j["floor_plan"] = {
      {"width", plan.width},
      {"height", plan.height},
      {"resolution_m", ShortestDouble(plan.resolution_m)},
      {"origin", {ShortestDouble(plan.origin_W.x()), ShortestDouble(plan.origin_W.y())}}};
  j["paths"] = written->paths;
  j["build_ms"] = RoundTo(build_ms, 1);
  j["write_ms"] = RoundTo(write_ms, 1);
  std::cerr << "sim scene: " << world->name << ": " << world->instances.size() << " instances, "
            << world->rooms.size() << " rooms, " << world->mesh.num_triangles()
            << " triangles, floor plan " << plan.width << "x" << plan.height << " ("
            << RoundTo(free_cells * cell_area, 1) << " m² free) -> " << o.out_dir << "\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddSimSceneCommand(CLI::App& sim) {
  auto o = std::make_shared<SimSceneOptions>();
  CLI::App* sub = sim.add_subcommand(
      "scene", "Generate an apartment or load a scene; write mesh, instances, rooms, floor plan");
  sub->add_option("--generate", o->generate, "What to generate: apartment");
  sub->add_option("--scene", o->scene, "Scene file to load (.ply .glb .obj .stl .dae)");
  sub->add_option(
         "--size", o->size,
         "Apartment size class: S (60-110 m²), M (110-200), L (200-350), XL (300-450), R (one "
         "room, 20-70)")
      ->capture_default_str();
  sub->add_option("--seed", o->seed, "Generator seed (same seed, same files)")
      ->capture_default_str();
  AddSceneFrameOptions(sub, o->frame);
  sub->add_option("--out,-o", o->out_dir, "Output folder (created if its parent exists)")
      ->required();
  sub->add_option("--name", o->name, "File name stem of the outputs")->capture_default_str();
  sub->add_option("--furniture-index", o->furniture_index,
                  "objects/aws_furniture_index.tsv (default: found under ../shared/data)");
  sub->add_flag("--no-furniture-meshes", o->no_furniture_meshes,
                "Generate parametric furniture only");
  sub->add_flag("--no-ceiling", o->no_ceiling, "Generate no ceiling");
  sub->add_option("--resolution", o->resolution, "Floor plan cell size, metres")
      ->check(InRange(0.01, 1.0, "m"))
      ->capture_default_str();
  sub->add_flag("--no-ply", o->no_ply, "Do not write <name>.ply");
  sub->add_flag("--no-glb", o->no_glb, "Do not write <name>.glb");
  return {sub, [o] { return RunSimScene(*o); }};
}

}  // namespace voxplan::cli
