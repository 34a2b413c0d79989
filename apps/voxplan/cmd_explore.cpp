// voxplan explore: the closed exploration loop (explore/explore.h) on a generated apartment or a
// scene file, with a planner plugin. Writes to --out:
//   mesh.ply        the final mesh of the fused map
//   metrics.json    completeness (see completeness_reference), accuracy, distances, balance,
//                   times, plan calls, termination; all but plan_ms_* repeat for a seed
//   timeseries.csv  coverage, completeness (every 30 s, volume estimate), distance vs time
//   run_log.csv     every robot's poses and status (eval/eval_run.h format)
//   topdown.png     the final floor map, each robot's path, start / end marks, reached views
//   plan_log.txt    rejected tasks, failed tasks and plans, the plugin's messages
//   plan_calls.csv  one row per plan call with its wall time and the plugin's diagnostics
// Apartments use parametric furniture (no shared data needed); the summary JSON (with the
// wall-time breakdown) is the last line of stdout, progress goes to stderr.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "core/parallel.h"
#include "eval/eval_mesh.h"
#include "eval/visibility.h"
#include "explore/explore.h"
#include "fusion/mesh_extract.h"
#include "io/file_util.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "sim/apartment.h"
#include "sim/floor_plan.h"
#include "sim/raycaster.h"
#include "sim/scene_loader.h"
#include "sim/tour.h"
#include "viewer_offscreen/top_down.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The camera options' limits (exclusive): RobotParams' field-of-view bounds, and the near depth
// frames are fused from (explore/explore.cpp), below which a range would fuse nothing.
constexpr double kMinFovDeg = 1.0, kMaxFovDeg = 179.0;
constexpr double kMinRangeM = 0.1;

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

struct ExploreOptions {
  std::string scene;
  SceneFrameOptions frame;
  int robots = 3;
  std::string planner;
  std::string planner_config;
  uint64_t seed = 1;
  double max_time = 1800.0;
  std::string start;
  std::string out_dir;
  double voxel_size = 0.05;
  int width = 320, height = 240;
  // The explorer camera (the mode every planner drives in); defaults are ModeParams' own.
  double fov_deg = DefaultModeParams(RobotMode::kExplorer).horizontal_fov_deg;
  double max_range_m = DefaultModeParams(RobotMode::kExplorer).max_range_m;
  bool no_noise = false;
  bool no_labels = false;
  bool no_color = false;
  bool no_clear = false;
  double planning_interval = 15.0;
  double plan_budget = 1.0;
  double eval_samples_per_m2 = 100.0;
  double progress_interval = 30.0;
  double fuse_step_m = 0.25, fuse_step_deg = 15.0;
  int threads = 0;
};

// "apartment:size=M,seed=3" -> params; nullopt-like NotFound when `spec` is not an apartment.
Result<ApartmentParams> ParseApartmentSpec(const std::string& spec) {
  const std::string prefix = "apartment";
  if (spec.rfind(prefix, 0) != 0 || (spec.size() > prefix.size() && spec[prefix.size()] != ':'))
    return NotFound("not an apartment");
  ApartmentParams params;
  params.size = ApartmentSize::kM;
  std::stringstream rest(spec.size() > prefix.size() ? spec.substr(prefix.size() + 1) : "");
  std::string item;
  while (std::getline(rest, item, ',')) {
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq),
                      value = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (key == "size") {
      Result<ApartmentSize> size = ParseApartmentSize(value);
      if (!size.ok()) return InvalidArgument("--scene " + spec + ": " + size.status().message());
      params.size = *size;
    } else if (key == "seed") {
      char* end = nullptr;
      params.seed = std::strtoull(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0')
        return InvalidArgument("--scene " + spec + ": seed wants a non-negative integer");
    } else {
      return InvalidArgument("--scene " + spec + ": unknown key '" + key +
                             "' (apartment:size=S|M|L,seed=N)");
    }
  }
  return params;
}

// "x,y;x,y;..." in metres.
Result<std::vector<Eigen::Vector2f>> ParseStarts(const std::string& text) {
  std::vector<Eigen::Vector2f> starts;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ';')) {
    float x = 0.f, y = 0.f;
    int consumed = 0;
    if (std::sscanf(item.c_str(), "%f,%f%n", &x, &y, &consumed) != 2 ||
        consumed != int(item.size()) || !std::isfinite(x) || !std::isfinite(y))
      return InvalidArgument("--start wants \"x,y;x,y;...\" in metres, got '" + text + "'");
    starts.emplace_back(x, y);
  }
  return starts;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "(none)" : out;
}

Status WriteLines(const std::vector<std::string>& lines, const std::string& path) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return WriteAtomically(path,
                         [&](const std::string& tmp) { return WriteStringToFile(tmp, text); });
}

// The reference surface for completeness: ground-truth samples a camera could see from the
// scene's reachable floor, judged from a sim tour (a viewpoint cover with 360° spins); empty
// filter (every sample) when no tour can be planned.
Result<PointSetFilter> TourFilter(const World& world, const FloorPlan& plan,
                                  const MeshRaycaster& raycaster, const ExploreParams& params,
                                  size_t* tour_frames) {
  TourParams tp;
  tp.robot = params.robot;
  tp.view_range_m = params.robot.explorer.max_range_m;
  tp.frame_step_m = 0.5f;
  tp.frame_step_deg = 20.f;
  Result<Tour> tour = PlanTour(plan, world.rooms, tp);
  if (!tour.ok() || tour->T_W_C.empty()) return PointSetFilter{};
  std::vector<Pose3d> poses;
  for (const Pose3f& T : tour->T_W_C) poses.push_back(T.cast<double>());
  *tour_frames = poses.size();
  VisibilityParams vp;
  vp.max_depth_m = params.robot.explorer.max_range_m;
  vp.depth_tolerance_m = 0.03f;
  // Every other spin frame (40° apart) while that stays inside the field of view.
  vp.pose_stride = params.robot.explorer.horizontal_fov_deg > 2.f * tp.frame_step_deg ? 2 : 1;
  const PinholeCamera camera = CameraWithFov(params.image_width, params.image_height,
                                             params.robot.explorer.horizontal_fov_deg);
  return ObservableSurfaceFilter(raycaster, camera, poses, vp);
}

int RunExploreCommand(const ExploreOptions& o) {
  // Usage checks, before any work.
  if (o.robots < 1) return Fail("--robots must be at least 1", kExitUsage);
  if (!(o.max_time > 0.0)) return Fail("--max-time must be > 0", kExitUsage);
  if (!(o.fov_deg > kMinFovDeg && o.fov_deg < kMaxFovDeg))
    return Fail("--fov-deg must lie strictly between " + Num(kMinFovDeg) + " and " +
                    Num(kMaxFovDeg) + " degrees, got " + Num(o.fov_deg),
                kExitUsage);
  if (!(o.max_range_m > kMinRangeM && std::isfinite(o.max_range_m)))
    return Fail("--max-range-m must be a finite number of metres above " + Num(kMinRangeM) +
                    ", got " + Num(o.max_range_m),
                kExitUsage);
  std::error_code ec;
  const fs::path out(o.out_dir);
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return Fail("--out " + o.out_dir + " is not a folder", kExitUsage);
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec))
    return Fail("output folder's parent does not exist: " + parent.string(), kExitUsage);
  std::vector<Eigen::Vector2f> starts;
  if (!o.start.empty()) {
    Result<std::vector<Eigen::Vector2f>> s = ParseStarts(o.start);
    if (!s.ok()) return Fail(s.status().message(), kExitUsage);
    if (int(s->size()) != o.robots)
      return Fail("--start gives " + std::to_string(s->size()) + " positions for " +
                      std::to_string(o.robots) + " robots",
                  kExitUsage);
    starts = *s;
  }
  std::string config_json = "{}";
  if (!o.planner_config.empty()) {
    Result<std::string> text = ReadFileToString(o.planner_config);
    if (!text.ok()) return Fail(MessageNaming(text.status(), o.planner_config), kExitUsage);
    if (!json::accept(*text))
      return Fail("planner config " + o.planner_config + " is not valid JSON", kExitUsage);
    config_json = *text;
  }
  const bool by_path = o.planner.find('/') != std::string::npos ||
                       (o.planner.size() > 3 && o.planner.ends_with(".so"));
  if (!by_path) {
    const std::vector<std::string> available = AvailablePlanners(DefaultPlannerSearchPath());
    if (std::find(available.begin(), available.end(), o.planner) == available.end())
      return Fail("unknown planner '" + o.planner + "'; available: " + Join(available), kExitUsage);
  }
  Result<std::unique_ptr<LoadedPlanner>> planner =
      LoadPlanner(o.planner, {.config_json = config_json, .seed = o.seed, .search_path = {}});
  if (!planner.ok()) return Fail(planner.status().message(), kExitUsage);

  ThreadLimit limit(o.threads);
  const Stopwatch clock;
  Result<World> world = Status(StatusCode::kInternal, "no world");
  Result<ApartmentParams> apartment = ParseApartmentSpec(o.scene);
  if (apartment.ok()) {
    world = GenerateApartment(*apartment);  // parametric furniture: needs no shared data
  } else if (apartment.status().code() != StatusCode::kNotFound) {
    return Fail(apartment.status().message(), kExitUsage);
  } else {
    if (!fs::is_regular_file(o.scene, ec))
      return Fail("scene file not found: " + o.scene, kExitUsage);
    world = LoadWorld(o.scene, SceneLoad(o.frame));
  }
  if (!world.ok()) return Fail(MessageNaming(world.status(), o.scene));
  Result<FloorPlan> plan = RasterizeFloorPlan(*world);
  if (!plan.ok()) return Fail(MessageNaming(plan.status(), o.scene));

  ExploreParams params;
  params.voxel_size_m = float(o.voxel_size);
  params.image_width = o.width;
  params.image_height = o.height;
  params.noise = !o.no_noise;
  params.fuse_labels = !o.no_labels;
  params.fuse_color = !o.no_color;
  params.clear_beyond_range = !o.no_clear;
  params.planning_interval_s = o.planning_interval;
  params.plan_time_budget_s = o.plan_budget;
  params.max_time_s = o.max_time;
  params.seed = o.seed;
  params.progress_interval_s = o.progress_interval;
  params.trigger = {float(o.fuse_step_m), float(o.fuse_step_deg)};
  params.robot.explorer.horizontal_fov_deg = float(o.fov_deg);
  params.robot.explorer.max_range_m = float(o.max_range_m);
  if (Status s = params.Validate(); !s.ok()) return Fail(s.message(), kExitUsage);
  if (starts.empty()) {
    Result<std::vector<Eigen::Vector2f>> chosen =
        ChooseStarts(*plan, world->rooms, o.robots, params.robot.radius_m);
    if (!chosen.ok()) return Fail(MessageNaming(chosen.status(), o.scene));
    starts = *chosen;
  } else if (Status s = CheckStarts(*plan, starts, params.robot.radius_m); !s.ok()) {
    return Fail(s.message(), kExitUsage);
  }
  fs::create_directories(out, ec);
  if (ec) return Fail("cannot create output folder " + o.out_dir + ": " + ec.message());

  // Ground truth for completeness: the observable surface, sampled once for the time series.
  Result<std::unique_ptr<MeshRaycaster>> gt_raycaster = MeshRaycaster::Create(*world);
  if (!gt_raycaster.ok()) return Fail(MessageNaming(gt_raycaster.status(), o.scene));
  size_t tour_frames = 0;
  Result<PointSetFilter> filter = TourFilter(*world, *plan, **gt_raycaster, params, &tour_frames);
  if (!filter.ok()) return Fail(MessageNaming(filter.status(), o.scene));
  Result<SurfaceSamples> gt_samples = SampleSurface(world->mesh, 100.0, o.seed);
  if (!gt_samples.ok()) return Fail(MessageNaming(gt_samples.status(), o.scene));
  std::vector<Eigen::Vector3f> probe_points;
  for (const Eigen::Vector3d& p : gt_samples->points) probe_points.push_back(p.cast<float>());
  if (*filter) {
    const std::vector<uint8_t> observable = (*filter)(probe_points);
    size_t kept = 0;
    for (size_t i = 0; i < probe_points.size(); ++i)
      if (observable[i]) probe_points[kept++] = probe_points[i];
    probe_points.resize(kept);
  }
  const double setup_ms = clock.ElapsedMs();

  std::cerr << "explore: " << world->name << ", " << o.robots << " robots, planner "
            << (*planner)->name() << " " << (*planner)->version() << ", max " << o.max_time
            << " s simulated" << std::endl;
  auto progress = [](const ExploreProgress& p) {
    std::cerr << "explore: t=" << RoundTo(p.t_s, 1) << " s, " << p.frames_fused
              << " frames, coverage " << RoundTo(100.0 * p.coverage, 1) << "%, distance "
              << RoundTo(p.distance_total_m, 1) << " m, " << p.plan_calls << " plan calls"
              << std::endl;
  };
  Result<ExploreResult> run = RunExplore(
      *world, *plan, starts, **planner, params,
      [&](const TsdfVolume& v) { return VolumeCompleteness(v, probe_points); }, progress);
  if (!run.ok()) return Fail(run.status().message());
  ExploreResult& r = *run;

  // Outputs.
  const Stopwatch eval_clock;
  const Mesh mesh = ExtractMesh(*r.volume);
  const std::string mesh_path = (out / "mesh.ply").string();
  if (Status s = WriteMesh(mesh, mesh_path); !s.ok()) return Fail(MessageNaming(s, mesh_path));
  MeshEvalParams ep;
  ep.threshold_m = 0.05f;
  ep.samples_per_m2 = float(o.eval_samples_per_m2);
  ep.seed = o.seed;
  if (*filter) ep.ground_truth_filter = *filter;
  MeshEvalResult quality;
  if (mesh.num_triangles() > 0) {
    Result<MeshEvalResult> q = EvaluateMesh(mesh, world->mesh, ep);
    if (!q.ok()) return Fail(MessageNaming(q.status(), o.scene));
    quality = *q;
  }
  Result<RunMetrics> metrics = EvaluateRun(r.tracks, {.scene_area_m2 = FloorArea(*plan)});
  if (!metrics.ok()) return Fail(metrics.status().message());
  const double eval_ms = eval_clock.ElapsedMs();

  std::vector<double> plan_ms;
  for (const PlanCallRecord& c : r.plan_calls) plan_ms.push_back(c.elapsed_ms);
  const TimingSummary plan_summary = Summarize(plan_ms);

  json m;
  m["scene"] = o.scene;
  m["planner"] = (*planner)->name();
  m["robots"] = o.robots;
  m["seed"] = o.seed;
  m["completeness"] = RoundTo(quality.completeness, 4);
  m["completeness_all"] = RoundTo(quality.completeness_all, 4);
  m["completeness_reference"] =
      *filter ? "ground-truth surface observable from a sim tour of the reachable floor (" +
                    Num(params.robot.explorer.max_range_m) +
                    " m range), samples within 5 cm of the final mesh"
              : "whole ground-truth surface, samples within 5 cm of the final mesh";
  m["accuracy_rms_m"] = RoundTo(quality.accuracy_rms_m, 4);
  m["accuracy_mean_m"] = RoundTo(quality.accuracy_mean_m, 4);
  json per_robot = json::array();
  for (const RobotRunMetrics& rm : metrics->robots) per_robot.push_back(RoundTo(rm.distance_m, 3));
  m["distance_per_robot_m"] = per_robot;
  m["distance_total_m"] = RoundTo(metrics->distance_total_m, 3);
  m["distance_per_area"] = RoundTo(metrics->distance_per_area, 4);
  m["scene_area_m2"] = RoundTo(FloorArea(*plan), 2);
  m["load_balance_cov"] = RoundTo(metrics->load_balance_cov, 4);
  m["time_s"] = RoundTo(r.time_s, 2);
  m["idle_time_s"] = RoundTo(metrics->idle_time_total_s, 2);
  m["time_load_balance"] = RoundTo(metrics->time_load_balance, 4);
  m["coverage"] = r.series.empty() ? 0.0 : RoundTo(r.series.back().coverage, 4);
  m["plan_calls"] = r.plan_calls.size();
  m["plan_ms_median"] = RoundTo(plan_summary.median, 3);  // wall time: varies run to run
  m["plan_ms_p90"] = RoundTo(plan_summary.p90, 3);
  m["plans_over_budget"] = r.over_budget_calls;
  m["rejected_tasks"] = r.rejected_tasks;
  m["failed_tasks"] = r.failed_tasks;
  m["failed_plan_calls"] = r.failed_plans;
  m["frames_fused"] = r.frames_fused;
  m["terminated"] = r.terminated;
  m["done_reason"] = r.done_reason;
  std::string path = (out / "metrics.json").string();
  if (Status s = WriteJsonFile(m, path); !s.ok()) return Fail(s.message());

  path = (out / "run_log.csv").string();
  if (Status s = WriteRunLog(r.tracks, path); !s.ok()) return Fail(MessageNaming(s, path));
  for (RunTimePoint& p : r.series) {
    // Distance from the log, so the series and the metrics agree.
    p.distance_total_m = DistanceUpTo(r.tracks, p.t_s);
  }
  path = (out / "timeseries.csv").string();
  if (Status s = WriteRunTimeSeriesCsv(r.series, path); !s.ok())
    return Fail(MessageNaming(s, path));
  std::vector<std::string> log = r.plan_log;
  path = (out / "plan_log.txt").string();
  if (Status s = WriteLines(log, path); !s.ok()) return Fail(MessageNaming(s, path));
  std::vector<std::string> calls = {
      "call,t,event,event_robot,tasks,rejections,done,elapsed_ms,"
      "over_budget,diagnostics"};
  for (const PlanCallRecord& c : r.plan_calls) {
    size_t tasks = 0;
    for (size_t n : c.tasks_per_robot) tasks += n;
    std::ostringstream line;
    line << c.call_index << "," << c.t_s << "," << PlanEventName(c.event) << "," << c.event_robot
         << "," << tasks << "," << c.rejections << "," << (c.done ? 1 : 0) << ","
         << RoundTo(c.elapsed_ms, 3) << "," << (c.over_budget ? 1 : 0) << ",";
    for (size_t k = 0; k < c.diagnostics.size(); ++k)
      line << (k ? ";" : "") << c.diagnostics[k].first << "=" << c.diagnostics[k].second;
    calls.push_back(line.str());
  }
  path = (out / "plan_calls.csv").string();
  if (Status s = WriteLines(calls, path); !s.ok()) return Fail(MessageNaming(s, path));

  // Top-down picture: the final floor map, paths, start and end marks, task views.
  TopDownRaster raster;
  const FloorGeometry& g = r.floor->geometry();
  raster.origin_W = g.origin_cell.cast<float>() * g.cell_size_m;
  raster.resolution_m = g.cell_size_m;
  raster.classes = Image<uint8_t>(g.width, g.height);
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const FloorCell c = r.floor->At(x, y);
      raster.classes.at(x, y) = uint8_t(c == FloorCell::kFree       ? TopDownClass::kFree
                                        : c == FloorCell::kObstacle ? TopDownClass::kObstacle
                                        : c == FloorCell::kFrontier ? TopDownClass::kFrontier
                                                                    : TopDownClass::kUnknown);
    }
  std::vector<TopDownPath> paths;
  for (size_t i = 0; i < r.tracks.size(); ++i) {
    TopDownPath tp;
    for (const RobotSample& s : r.tracks[i].samples) {
      const Eigen::Vector2f p(float(s.x_m), float(s.y_m));
      if (tp.points_W.empty() || (tp.points_W.back() - p).norm() > 1e-3f) tp.points_W.push_back(p);
    }
    for (const PlannerTask& t : r.task_views[i])
      tp.views.push_back({t.position_m, t.theta_rad + t.camera_yaw_rad});
    paths.push_back(std::move(tp));
  }
  path = (out / "topdown.png").string();
  if (g.width > 0) {
    Result<ColorImage> picture = RenderTopDown(raster, paths);
    if (!picture.ok()) return Fail(picture.status().message());
    if (Status s = WriteColorPng(path, *picture); !s.ok()) return Fail(MessageNaming(s, path));
  }

  if (r.over_budget_calls > 0)
    Warn(std::to_string(r.over_budget_calls) + " of " + std::to_string(r.plan_calls.size()) +
         " plan calls took longer than the budget of " + std::to_string(o.plan_budget) +
         " s (plan_calls.csv, plan_log.txt)");
  if (r.failed_plans > 0)
    Warn(std::to_string(r.failed_plans) + " plan calls failed (messages in plan_log.txt)");
  if (r.rejected_tasks > 0)
    Warn("the planner's output was rejected " + std::to_string(r.rejected_tasks) +
         " times (reasons in plan_log.txt)");
  json j = m;
  j["command"] = "explore";
  j["out"] = o.out_dir;
  j["wall_s"] = RoundTo(clock.ElapsedMs() / 1e3, 2);
  j["setup_ms"] = RoundTo(setup_ms, 1);
  j["tour_frames"] = tour_frames;
  j["render_ms"] = RoundTo(r.timings.render_ms, 1);
  j["noise_ms"] = RoundTo(r.timings.noise_ms, 1);
  j["fuse_ms"] = RoundTo(r.timings.fuse_ms, 1);
  j["floor_ms"] = RoundTo(r.timings.floor_ms, 1);
  j["plan_ms_total"] = RoundTo(r.timings.plan_ms, 1);
  j["series_ms"] = RoundTo(r.timings.series_ms, 1);
  j["loop_ms"] = RoundTo(r.timings.total_ms, 1);
  j["eval_ms"] = RoundTo(eval_ms, 1);
  std::cerr << "explore: " << r.terminated
            << (r.done_reason.empty() ? "" : " (" + r.done_reason + ")")
            << " at t=" << RoundTo(r.time_s, 1) << " s, completeness "
            << RoundTo(100.0 * quality.completeness, 1) << "%, distance "
            << RoundTo(metrics->distance_total_m, 1) << " m, " << r.plan_calls.size()
            << " plan calls -> " << o.out_dir << std::endl;
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddExploreCommand(CLI::App& app) {
  auto o = std::make_shared<ExploreOptions>();
  CLI::App* sub = app.add_subcommand(
      "explore", "Closed-loop multi-robot exploration of a simulated scene with a planner plugin");
  sub->add_option("--scene", o->scene,
                  "apartment:size=S|M|L,seed=N, or a scene file (.ply .glb .obj .dae), Z-up metres "
                  "by default")
      ->required();
  AddSceneFrameOptions(sub, o->frame);
  sub->add_option("--robots", o->robots, "Number of robots")->capture_default_str();
  sub->add_option("--planner", o->planner, "Planner name (libvoxplan_planner_<name>.so) or path")
      ->required();
  sub->add_option("--planner-config", o->planner_config, "JSON file handed to the planner");
  sub->add_option("--seed", o->seed, "Seed of the planner and the sensor noise")
      ->capture_default_str();
  sub->add_option("--max-time", o->max_time, "Simulated seconds before the run stops")
      ->capture_default_str();
  sub->add_option("--start", o->start,
                  "Start positions \"x,y;x,y;...\" in metres, one per robot (default: side by "
                  "side in the largest room)");
  sub->add_option("--out,-o", o->out_dir, "Output folder (created)")->required();
  sub->add_option("--voxel-size", o->voxel_size, "Voxel size of the fused map, metres")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--width", o->width, "Rendered image width, pixels")->capture_default_str();
  sub->add_option("--height", o->height, "Rendered image height, pixels")->capture_default_str();
  sub->add_option(
         "--fov-deg", o->fov_deg,
         "Horizontal field of view of the explorer camera, degrees (the paper's Xtion: 58)")
      ->capture_default_str();
  sub->add_option("--max-range-m", o->max_range_m,
                  "Depth range of the explorer camera, metres (the paper's Xtion: 3)")
      ->capture_default_str();
  sub->add_flag("--no-noise", o->no_noise, "Fuse clean rendered depth (no Kinect noise)");
  sub->add_flag("--no-clear-beyond-range", o->no_clear,
                "Depth beyond --max-range-m clears nothing (by default it clears the free space in "
                "front of the range, as a real sensor's far returns show it)");
  sub->add_flag("--no-labels", o->no_labels, "Fuse no instance labels (no object map)");
  sub->add_flag("--no-color", o->no_color,
                "Render and fuse no colour (a grey mesh.ply; the metrics do not change)");
  sub->add_option("--planning-interval", o->planning_interval,
                  "Simulated seconds between re-planning calls")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--plan-budget", o->plan_budget, "Wall seconds a plan call should take at most")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--eval-samples", o->eval_samples_per_m2,
                  "Ground-truth samples per m² for completeness and accuracy")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--fuse-step", o->fuse_step_m, "Metres of camera travel between fused frames")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--fuse-step-deg", o->fuse_step_deg,
                  "Degrees of camera turn between fused frames")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--progress-interval", o->progress_interval,
                  "Simulated seconds between progress lines on stderr")
      ->check(Positive())
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0: all)")->check(NonNegative());
  return {sub, [o] { return RunExploreCommand(*o); }};
}

}  // namespace voxplan::cli
