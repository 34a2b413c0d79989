// voxplan eval objects / eval run: per-object quality of a reconstruction against a world with
// instances (Guo 2022 O-Comp, O-RMS), and the metrics of a multi-robot run from its run log.
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "eval/eval_objects.h"
#include "eval/eval_run.h"
#include "io/mesh_io.h"
#include "sim/floor_plan.h"
#include "sim/scene_loader.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

// The world of --scene: the mesh and its instance table (`<stem>_instances.tsv` beside it unless
// given), as `voxplan sim scene` writes them.
struct SceneOptions {
  std::string scene;
  std::string instances;
  SceneFrameOptions frame;
};

void AddSceneOptions(CLI::App* sub, SceneOptions* s, bool required) {
  CLI::Option* scene = sub->add_option(
      "--scene", s->scene, "Ground-truth world mesh; its instance table is <stem>_instances.tsv");
  if (required) scene->required();
  sub->add_option("--instances", s->instances, "Instance table of the world (default: beside it)");
  AddSceneFrameOptions(sub, s->frame);
}

Result<World> LoadScene(const SceneOptions& s) {
  std::error_code ec;
  if (!fs::is_regular_file(s.scene, ec)) return NotFound("scene file not found: " + s.scene);
  if (!s.instances.empty() && !fs::is_regular_file(s.instances, ec))
    return NotFound("instance table not found: " + s.instances);
  SceneLoadOptions load = SceneLoad(s.frame);
  load.instance_table = s.instances;
  Result<World> world = LoadWorld(s.scene, load);
  if (!world.ok()) return world.status().WithContext(s.scene);
  return world;
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

struct EvalObjectsOptions {
  std::string reconstruction;
  SceneOptions scene;
  double threshold_m = 0.05;
  double samples_per_m2 = 10000.0;
  size_t min_samples = 200;
  uint64_t seed = 1;
  double max_attribution_m = 0.0;  // 0: no limit
  std::string exclude = "wall,floor,ceiling,door,window,structure";
  int threads = 0;
};

int RunEvalObjects(const EvalObjectsOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.reconstruction, ec))
    return Fail("mesh file not found: " + o.reconstruction);
  ThreadLimit thread_limit(o.threads);
  Result<Mesh> reconstruction = ReadMesh(o.reconstruction);
  if (!reconstruction.ok()) return Fail(MessageNaming(reconstruction.status(), o.reconstruction));
  Result<World> world = LoadScene(o.scene);
  if (!world.ok()) return Fail(world.status().message());
  if (world->instances.empty())
    return Fail(o.scene.scene + ": the world has no instances (no instance table beside it?)");

  ObjectEvalParams params;
  params.threshold_m = float(o.threshold_m);
  params.samples_per_m2 = float(o.samples_per_m2);
  params.min_samples_per_object = o.min_samples;
  params.seed = o.seed;
  if (o.max_attribution_m > 0.0) params.max_attribution_distance_m = float(o.max_attribution_m);
  params.excluded_classes = SplitList(o.exclude);
  const Stopwatch clock;
  Result<ObjectsEvalResult> result = EvaluateObjects(*reconstruction, *world, params);
  if (!result.ok()) return Fail("evaluation failed: " + result.status().message());
  const ObjectsEvalResult& r = *result;

  nlohmann::json objects = nlohmann::json::array();
  for (const ObjectEvalResult& object : r.objects) {
    std::cerr << "  " << object.id << " " << object.class_name << " (" << object.model
              << "): completeness " << RoundTo(100.0 * object.completeness, 1) << " %";
    if (object.reconstruction_samples > 0)
      std::cerr << ", accuracy " << RoundTo(object.accuracy_mean_m * 1000, 2) << " mm";
    std::cerr << "\n";
    nlohmann::json j;
    j["id"] = object.id;
    j["class"] = object.class_name;
    j["model"] = object.model;
    j["ground_truth_area_m2"] = object.ground_truth_area_m2;
    j["ground_truth_samples"] = object.ground_truth_samples;
    j["completeness"] = object.completeness;
    j["reconstruction_samples"] = object.reconstruction_samples;
    // No reconstruction, no accuracy: null rather than a misleading 0.
    j["accuracy_mean_m"] =
        object.reconstruction_samples > 0 ? nlohmann::json(object.accuracy_mean_m) : nullptr;
    j["accuracy_rms_m"] =
        object.reconstruction_samples > 0 ? nlohmann::json(object.accuracy_rms_m) : nullptr;
    objects.push_back(j);
  }
  std::cerr << r.objects.size() << " objects (" << r.objects_reconstructed
            << " reconstructed): O-Comp " << RoundTo(100.0 * r.o_comp, 2) << " % within "
            << o.threshold_m << " m, O-RMS " << RoundTo(r.o_rms_m * 1000, 2) << " mm\n";
  if (!r.skipped.empty())
    Warn(std::to_string(r.skipped.size()) + " instances have no surface and were skipped");

  nlohmann::json j;
  j["command"] = "eval objects";
  j["reconstruction"] = o.reconstruction;
  j["scene"] = o.scene.scene;
  j["objects_evaluated"] = r.objects.size();
  j["objects_reconstructed"] = r.objects_reconstructed;
  j["o_comp"] = r.o_comp;
  j["o_comp_percent"] = RoundTo(100.0 * r.o_comp, 3);
  j["o_rms_m"] = r.o_rms_m;
  j["mean_object_rms_m"] = r.mean_object_rms_m;
  j["completeness_all_objects"] = r.completeness_all_objects;
  j["reconstruction_samples"] = r.reconstruction_samples;
  j["reconstruction_samples_unattributed"] = r.reconstruction_samples_unattributed;
  j["skipped_instances"] = r.skipped;
  j["excluded_classes"] = params.excluded_classes;
  j["threshold_m"] = o.threshold_m;
  j["samples_per_m2"] = o.samples_per_m2;
  j["seed"] = o.seed;
  j["objects"] = objects;
  j["eval_ms"] = RoundTo(clock.ElapsedMs(), 3);
  PrintJsonLine(j);
  return kExitOk;
}

struct EvalRunOptions {
  std::string run_log;
  double floor_area_m2 = 0.0;
  SceneOptions scene;
  double resolution_m = 0.05;
  std::string csv;
};

int RunEvalRun(const EvalRunOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.run_log, ec)) return Fail("run log not found: " + o.run_log);
  Result<std::vector<RobotTrack>> tracks = ReadRunLog(o.run_log);
  if (!tracks.ok()) return Fail(MessageNaming(tracks.status(), o.run_log));

  RunEvalParams params;
  params.scene_area_m2 = o.floor_area_m2;
  if (!o.scene.scene.empty()) {
    Result<World> world = LoadScene(o.scene);
    if (!world.ok()) return Fail(world.status().message());
    FloorPlanParams plan_params;
    plan_params.resolution_m = float(o.resolution_m);
    Result<FloorPlan> plan = RasterizeFloorPlan(*world, plan_params);
    if (!plan.ok()) return Fail(MessageNaming(plan.status(), o.scene.scene));
    params.scene_area_m2 = FloorArea(*plan);
    std::cerr << "scene floor area " << RoundTo(params.scene_area_m2, 2) << " m² (" << o.scene.scene
              << ")\n";
  }
  Result<RunMetrics> run = EvaluateRun(*tracks, params);
  if (!run.ok()) return Fail(MessageNaming(run.status(), o.run_log));
  const RunMetrics& m = *run;

  nlohmann::json robots = nlohmann::json::array();
  nlohmann::json distance = nlohmann::json::object(), idle = nlohmann::json::object(),
                 busy = nlohmann::json::object();
  for (const RobotRunMetrics& r : m.robots) {
    std::cerr << "  " << r.robot << ": " << RoundTo(r.distance_m, 2) << " m, busy "
              << RoundTo(r.busy_time_s, 1) << " s, idle " << RoundTo(r.idle_time_s, 1) << " s\n";
    nlohmann::json j;
    j["robot"] = r.robot;
    j["samples"] = r.samples;
    j["distance_m"] = r.distance_m;
    j["start_s"] = r.start_s;
    j["end_s"] = r.end_s;
    j["busy_time_s"] = r.busy_time_s;
    j["idle_time_s"] = r.idle_time_s;
    j["idle_fraction"] = r.idle_fraction;
    j["mode_time_s"] = r.mode_time_s;
    j["mode_distance_m"] = r.mode_distance_m;
    robots.push_back(j);
    distance[r.robot] = r.distance_m;
    idle[r.robot] = r.idle_time_s;
    busy[r.robot] = r.busy_time_s;
  }
  std::cerr << m.robots.size() << " robots, " << RoundTo(m.time_s, 2) << " s: distance "
            << RoundTo(m.distance_total_m, 2) << " m";
  if (params.scene_area_m2 > 0.0)
    std::cerr << " (" << RoundTo(m.distance_per_area, 4) << " m per m² of "
              << RoundTo(params.scene_area_m2, 2) << " m²)";
  std::cerr << ", D-LB (COV) " << RoundTo(m.load_balance_cov, 4) << ", T-LB "
            << RoundTo(m.time_load_balance, 4) << "\n";

  if (!o.csv.empty()) {
    const Status written = WriteRunTimeSeriesCsv(RunTimeSeries(*tracks), o.csv);
    if (!written.ok()) return Fail(MessageNaming(written, o.csv));
    std::cerr << "time series: " << o.csv << "\n";
  }

  nlohmann::json j;
  j["command"] = "eval run";
  j["run_log"] = o.run_log;
  j["robots"] = robots;
  j["distance_per_robot_m"] = distance;
  j["busy_time_s"] = busy;
  j["idle_time_s"] = idle;
  j["distance_total_m"] = m.distance_total_m;
  j["distance_mean_m"] = m.distance_mean_m;
  j["scene_area_m2"] = params.scene_area_m2 > 0.0 ? nlohmann::json(params.scene_area_m2) : nullptr;
  j["distance_per_area"] =
      params.scene_area_m2 > 0.0 ? nlohmann::json(m.distance_per_area) : nullptr;
  j["load_balance_cov"] = m.load_balance_cov;
  j["time_s"] = m.time_s;
  j["start_s"] = m.start_s;
  j["end_s"] = m.end_s;
  j["idle_time_total_s"] = m.idle_time_total_s;
  j["time_load_balance"] = m.time_load_balance;
  if (!o.csv.empty()) j["csv"] = o.csv;
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

std::vector<Command> AddEvalSimCommands(CLI::App& eval) {
  auto o = std::make_shared<EvalObjectsOptions>();
  CLI::App* objects = eval.add_subcommand(
      "objects", "Per-object completeness and accuracy against a world with instances");
  objects->add_option("reconstruction", o->reconstruction, "Reconstructed mesh")->required();
  AddSceneOptions(objects, &o->scene, /*required=*/true);
  objects->add_option("--threshold", o->threshold_m, "Completeness distance threshold (m)")
      ->check(Positive())
      ->capture_default_str();
  objects->add_option("--samples-per-m2", o->samples_per_m2, "Surface samples per square metre")
      ->check(Positive())
      ->capture_default_str();
  objects->add_option("--min-samples", o->min_samples, "Fewest ground-truth samples per object")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  objects->add_option("--seed", o->seed, "Sampling seed")->capture_default_str();
  objects
      ->add_option("--max-attribution", o->max_attribution_m,
                   "Reconstruction farther than this (m) from all ground truth belongs to no "
                   "object (0: no limit)")
      ->check(NonNegative())
      ->capture_default_str();
  objects
      ->add_option("--exclude-classes", o->exclude,
                   "Comma-separated instance classes that are not objects (empty: none)")
      ->capture_default_str();
  objects->add_option("--threads", o->threads, "Worker threads (0: all hardware threads)")
      ->check(NonNegative())
      ->capture_default_str();

  auto r = std::make_shared<EvalRunOptions>();
  CLI::App* run = eval.add_subcommand("run", "Distance, load balance and idle time of a run log");
  run->add_option("run-log", r->run_log,
                  "Run log CSV (t,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode)")
      ->required();
  CLI::Option* area = run->add_option("--floor-area", r->floor_area_m2,
                                      "Scene floor area (m²) for distance per area")
                          ->check(Positive());
  AddSceneOptions(run, &r->scene, /*required=*/false);
  run->get_option("--scene")->excludes(area);
  run->add_option("--resolution", r->resolution_m, "Floor plan cell size with --scene (m)")
      ->check(Positive())
      ->capture_default_str();
  run->add_option("--csv", r->csv, "Write distance and busy robots over time here")
      ->check(OutputFileValidator());

  return {{objects, [o] { return RunEvalObjects(*o); }}, {run, [r] { return RunEvalRun(*r); }}};
}

}  // namespace voxplan::cli
