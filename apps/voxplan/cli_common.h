#pragma once
// Helpers every voxplan subcommand shares: exit codes, error printing, output-path checks,
// timing summaries, progress reporting and the one-line JSON result.
#include <CLI/CLI.hpp>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/voxplan/cli_bounds.h"
#include "apps/voxplan/progress.h"
#include "core/camera.h"
#include "core/mesh.h"
#include "core/status.h"
#include "core/stopwatch.h"
#include "core/summary.h"
#include "core/volume.h"
#include "fusion/integrate.h"
#include "io/dataset.h"
#include "io/text_file.h"
#include "sim/scene_loader.h"

namespace voxplan::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;       // I/O, data or library failures
inline constexpr int kExitUsage = 2;         // bad arguments, refused before any work
inline constexpr int kExitPlannerFault = 3;  // explore: the planner crashed or hung

// A parsed subcommand and the function that runs it once CLI11 is done.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command AddFuseCommand(CLI::App& app);
Command AddFarmCommand(CLI::App& app);
Command AddMeshCommand(CLI::App& app);
Command AddInfoCommand(CLI::App& app);
Command AddEvalCommand(CLI::App& app);
Command AddDemoCommand(CLI::App& app);
Command AddRenderCommand(CLI::App& app);
Command AddBenchCommand(CLI::App& app);
Command AddSimCommand(CLI::App& app);
Command AddExploreCommand(CLI::App& app);  // explore (cmd_explore.cpp)
// Subcommands that live in their own files, added to a parent command above.
Command AddSimSceneCommand(CLI::App& sim);         // sim scene       (cmd_sim_scene.cpp)
Command AddSimRenderCommand(CLI::App& sim);        // sim render      (cmd_sim_render.cpp)
Command AddSimTourCommand(CLI::App& sim);          // sim tour        (cmd_sim_tour.cpp)
Command AddBenchMapsCommand(CLI::App& bench);      // bench maps      (cmd_bench_maps.cpp)
Command AddEvalMeshCommand(CLI::App& eval);        // eval mesh       (cmd_eval_mesh.cpp)
Command AddEvalTrajectoryCommand(CLI::App& eval);  // eval trajectory (cmd_eval_trajectory.cpp)
Command AddEvalObjectsCommand(CLI::App& eval);     // eval objects    (cmd_eval_objects.cpp)
Command AddEvalRunCommand(CLI::App& eval);         // eval run        (cmd_eval_run.cpp)
// Runs the parsed one of `commands`; fails with a usage error when none was.
int RunParsed(const std::vector<Command>& commands);

// Prints `error: <message>` on stderr and returns exit_code, so callers can `return Fail(...)`.
int Fail(const std::string& message, int exit_code = kExitFailure);
void Warn(const std::string& message);
// The library's message, with `path` in front unless it already names it.
std::string MessageNaming(const Status& status, const std::string& path);

// Empty when `path` can be written: its folder exists and it is not itself a folder.
std::string CheckOutputFile(const std::string& path);
// CLI11 validators built on CheckOutputFile; the mesh one also checks the extension.
CLI::Validator OutputFileValidator();
CLI::Validator MeshOutputValidator();
// An output whose extension must be `extension` (".ply", ".bt"), `what` naming it in the error.
CLI::Validator OutputWithExtensionValidator(const std::string& extension, const std::string& what);
// Numeric checks with short messages (CLI11 2.1's own print the whole double range).
CLI::Validator Positive();
CLI::Validator NonNegative();

// --up, --scale and --floor-z of a scene file: worlds are Z-up metres with the floor at z = 0
// unless these say otherwise. --floor-z is the file's floor height (metres after up and scale)
// or "auto" (DetectFloor, sim/floor_detect.h); the world is moved down by it (SceneLoadOptions).
struct SceneFrameOptions {
  std::string up = "z";
  double scale = 1.0;
  std::string floor_z = "0";  // "auto" or metres within +-kMaxFloorZ_m
};
inline constexpr double kMaxFloorZ_m = 100.0;
void AddSceneFrameOptions(CLI::App* sub, SceneFrameOptions& frame);
// The load options they ask for (the rest at their defaults).
SceneLoadOptions SceneLoad(const SceneFrameOptions& frame);

// The world of --scene: the mesh and its instance table (`<stem>_instances.tsv` beside it unless
// given), as `voxplan sim scene` writes them; eval objects and eval run read it.
struct SceneOptions {
  std::string scene;
  std::string instances;
  SceneFrameOptions frame;
};
void AddSceneOptions(CLI::App* sub, SceneOptions* s, bool required);
// Refuses a missing scene file or instance table, then loads the world; errors name the scene.
Result<World> LoadScene(const SceneOptions& s);
// eval run / eval objects: refuses (prints and returns kExitFailure) a --scene that is not the
// world of the explore run that wrote run_file (explore/run_outputs.h CheckRunWorld); with
// any_world (--any-world), or for a run that recorded no fingerprint, warns instead. kExitOk: go
// on.
int CheckSceneIsRunWorld(const std::string& run_file, const World& world, bool any_world);

// The dataset a command reads and which of its frames: the positional folder, --format,
// --min-depth, --max-depth, --frames, --stride (and --start where asked for).
struct DatasetInput {
  std::string dataset;
  std::string format = "auto";
  double min_depth_m = 0.1;
  double max_depth_m = 3.0;
  int64_t frames = 0;  // 0: all; signed so CLI11 refuses negative values instead of wrapping
  int64_t start = 0;
  int64_t stride = 1;
  std::string topics;  // ROS bags: "depth=...,color=...,info=...,pose=..."
};
void AddDatasetInputOptions(CLI::App* sub, DatasetInput& in, bool with_start = false);
// --topics of the commands that read datasets (ROS bags' topics, io/dataset.h RosBagTopics).
void AddTopicsOption(CLI::App* sub, std::string& topics);

struct OpenedDataset {
  std::unique_ptr<Dataset> dataset;
  std::vector<size_t> indices;  // the selected frames: start, start + stride, ... (at most frames)
};
// Refuses a bad depth range, format or folder, opens the dataset (its warnings to stderr),
// refuses (usage error) intrinsics outside core/bounds.h's ranges and selects the frames. Returns
// kExitOk and fills *out, or the exit code after printing why. `options` carries any intrinsics or
// depth-scale override; its format is set from `in`.
int OpenDatasetInput(const DatasetInput& in, DatasetOptions options, OpenedDataset* out);

// --kernel of fuse and bench: the integration kernel by name.
inline const std::map<std::string, Kernel> kIntegrationKernels = {
    {"auto", Kernel::kAuto}, {"scalar", Kernel::kScalar}, {"simd", Kernel::kSimd}};

// "fx,fy,cx,cy" -> camera with width/height 0 (the dataset's images give the size).
Result<PinholeCamera> ParseIntrinsics(const std::string& text);

// The map's size keys (blocks, voxels, bytes_per_voxel, map_mb) and the mesh keys
// (mesh_vertices, mesh_triangles, mesh_ms) every command that builds them reports alike.
void AddMapStats(nlohmann::json& j, const TsdfVolume& volume);
void AddMeshStats(nlohmann::json& j, const Mesh& mesh, double mesh_ms);

// The camera as every command reports it: size and intrinsics.
nlohmann::json CameraJson(const PinholeCamera& camera);

// Writes JSON (pretty) through WriteAtomically; the error names the file.
Status WriteJsonFile(const nlohmann::json& json, const std::string& path);
// The machine-readable result: one JSON object as the last line of stdout.
void PrintJsonLine(const nlohmann::json& json);

}  // namespace voxplan::cli
