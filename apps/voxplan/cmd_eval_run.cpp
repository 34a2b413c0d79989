// voxplan eval run: distance, load balance and idle time of a multi-robot run from its run log.
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "eval/eval_run.h"
#include "sim/floor_plan.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct EvalRunOptions {
  std::string run_log;
  double floor_area_m2 = 0.0;
  SceneOptions scene;
  double resolution_m = 0.05;
  std::string csv;
  bool any_world = false;
};

int RunEvalRun(const EvalRunOptions& o) {
  std::error_code ec;
  if (!fs::is_regular_file(o.run_log, ec)) return Fail("run log not found: " + o.run_log);
  if (int code = RefusePathCollisions({{"--csv", o.csv}}, {{"the run log", o.run_log},
                                                           {"--scene", o.scene.scene},
                                                           {"--instances", o.scene.instances}});
      code != kExitOk)
    return code;
  Result<std::vector<RobotTrack>> tracks = ReadRunLog(o.run_log);
  if (!tracks.ok()) return Fail(MessageNaming(tracks.status(), o.run_log));

  RunEvalParams params;
  params.scene_area_m2 = o.floor_area_m2;
  if (!o.scene.scene.empty()) {
    Result<World> world = LoadScene(o.scene);
    if (!world.ok()) return Fail(world.status().message());
    if (int code = CheckSceneIsRunWorld(o.run_log, *world, o.any_world); code != kExitOk)
      return code;
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

Command AddEvalRunCommand(CLI::App& eval) {
  auto r = std::make_shared<EvalRunOptions>();
  CLI::App* run = eval.add_subcommand("run", "Distance, load balance and idle time of a run log");
  run->add_option("run-log", r->run_log,
                  "Run log CSV (t,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode)")
      ->required();
  CLI::Option* area = run->add_option("--floor-area", r->floor_area_m2,
                                      "Scene floor area (m²) for distance per area")
                          ->check(InRange(0.01, 1e6, "m²"));
  AddSceneOptions(run, &r->scene, /*required=*/false);
  run->get_option("--scene")->excludes(area);
  run->add_flag("--any-world", r->any_world,
                "Score against --scene even when it is not the world the run's metrics.json names");
  run->add_option("--resolution", r->resolution_m, "Floor plan cell size with --scene (m)")
      ->check(InRange(0.01, 1.0, "m"))
      ->capture_default_str();
  run->add_option("--csv", r->csv, "Write distance and busy robots over time here")
      ->check(OutputFileValidator());
  return {run, [r] { return RunEvalRun(*r); }};
}

}  // namespace voxplan::cli
