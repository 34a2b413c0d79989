#pragma once
// One exploration experiment, as `voxplan explore` and scripts/explore-suite define it: the
// scene (a generated apartment or a scene file), the robots' starts, the ground-truth surface
// completeness is judged against, the closed loop (RunExplore) and its final evaluation, with
// the artefacts written into an output folder (explore/run_outputs.h). It lives here, not in the
// CLI, so the experiment is one library call that tests and other front ends share.
//
// Completeness reference: the ground-truth samples a camera could see from the scene's
// reachable floor, judged from a sim tour (a viewpoint cover with 360° spins) at the explorer
// camera's range and field of view; the whole ground-truth surface when no tour can be planned.
#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/status.h"
#include "eval/eval_mesh.h"
#include "eval/eval_objects.h"
#include "eval/eval_run.h"
#include "explore/explore.h"
#include "plugins/host/plugin_host.h"
#include "sim/apartment.h"
#include "sim/scene_loader.h"

namespace voxplan {

struct ExploreRunParams {
  // "apartment:size=S|M|L|XL|R,seed=N" (parametric furniture: needs no shared data) or a scene
  // file.
  std::string scene;
  SceneLoadOptions scene_load;  // how a scene file loads
  int robots = 3;
  // One position per robot in metres, checked against the true floor plan; empty: ChooseStarts.
  std::vector<Eigen::Vector2f> starts;
  // The loop; its seed also seeds the ground-truth samples and the final evaluation.
  ExploreParams explore;
  double eval_samples_per_m2 = 100.0;  // ground-truth samples for completeness and accuracy
  std::string out_dir;                 // created (its parent must exist)
};

// Set-up and the loop's progress, for a front end to show; the library prints nothing.
struct ExploreRunObserver {
  std::function<void(const std::string& world_name)> started;  // set-up done, the loop begins
  ExploreProgressFn progress;                                  // RunExplore's progress
};

// Guo 2022 gives no O-Comp threshold: 2 cm (with a 2 cm reconstruction volume) is the primary,
// 5 cm (the planning voxel) the second (metrics.json's o_comp_2cm, o_comp_5cm).
inline constexpr float kObjectThreshold_m = 0.02f;
inline constexpr float kObjectExtraThreshold_m = 0.05f;

struct ExploreRunReport {
  std::string world_name;
  std::string planner_name;
  // The scene file's z of the run's floor (World::source_floor_z_m): every position of the run
  // (mesh.ply, run_log.csv, the maps) is the file's moved down by it. 0 unless the load was
  // asked to move the floor (SceneLoadOptions::floor_z_m, detect_floor).
  float scene_floor_z_m = 0.0f;
  // The world as run (WorldFingerprintHex, sim/world_io.h): metrics.json's world_fingerprint,
  // which `eval run` and `eval objects` check a --scene against.
  std::string world_fingerprint;
  ExploreResult loop;      // the loop's result, final maps included
  Mesh mesh;               // the fused map's final mesh (mesh.ply)
  MeshEvalResult quality;  // all zero when the mesh is empty
  // Completeness over the observable surface below the robot's height (floor map band top),
  // Xu 2017's reference; 0 when the mesh is empty.
  double completeness_below_robot = 0.0;
  // Per object (Guo 2022's O-Comp at 2 cm, extra threshold 5 cm, and O-RMS) on the same mesh;
  // empty when the mesh is or the world has no object beside its structure.
  std::optional<ObjectsEvalResult> objects;
  RunMetrics metrics;
  double scene_area_m2 = 0.0;
  bool observable_reference = false;  // completeness over the tour-observable surface, else all
  size_t tour_frames = 0;             // frames of the completeness tour
  double setup_ms = 0.0;              // wall time: scene, starts, completeness probe
  double eval_ms = 0.0;               // wall time: mesh, its file, evaluation
  // Plan calls over budget, failed plan calls, rejected outputs, map blocks dropped at the
  // memory budget, in words; for the caller to show (the counts are in `loop`).
  std::vector<std::string> warnings;
};

// Runs one experiment and writes its artefacts into params.out_dir. Refusals of the request
// itself (a malformed apartment spec, no such scene file, parameters ExploreParams::Validate
// refuses, explicit starts off the free floor) set *refused; they come before the output folder
// is created. Every other failure (loading, the loop, evaluation, writing) leaves it false.
Result<ExploreRunReport> RunExploreExperiment(const ExploreRunParams& params,
                                              LoadedPlanner& planner,
                                              const ExploreRunObserver& observer = {},
                                              bool* refused = nullptr);

// "apartment:size=M,seed=3" -> params (size M and seed 0 unless given); NotFound when `spec`
// is not an apartment, InvalidArgument when it is a malformed one.
Result<ApartmentParams> ParseApartmentSpec(const std::string& spec);

// "x,y;x,y;..." in metres -> positions; InvalidArgument naming --start otherwise.
Result<std::vector<Eigen::Vector2f>> ParseStarts(const std::string& text);

}  // namespace voxplan
