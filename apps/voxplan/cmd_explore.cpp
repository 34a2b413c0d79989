// voxplan explore: one exploration experiment (explore/explore_run.h) with a planner plugin,
// its artefacts in --out (explore/run_outputs.h). Here: the options, the refusals that come
// before any work (exit 2), the planner loading, progress on stderr and the summary JSON line.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "apps/voxplan/signals.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "explore/explore_run.h"
#include "explore/robot_config.h"
#include "explore/run_outputs.h"
#include "io/file_util.h"

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

// Options of the library's own types bind into `run` (its defaults are the CLI's); the rest
// convert in RunParams.
struct ExploreOptions {
  ExploreRunParams run;
  SceneFrameOptions frame;
  std::string planner;
  std::string planner_config;
  std::string start;
  double voxel_size = 0.05;
  double recon_voxel_size = 0.0;  // 0: the mesh comes from the planning map
  // The explorer camera (the mode every planner drives in); defaults are ModeParams' own.
  double fov_deg = DefaultModeParams(RobotMode::kExplorer).horizontal_fov_deg;
  double max_range_m = DefaultModeParams(RobotMode::kExplorer).max_range_m;
  bool no_noise = false;
  bool no_labels = false;
  bool no_detector_noise = false;
  std::string poses = "truth";        // --poses
  std::vector<float> odometry_noise;  // --odometry-noise T,R: per metre, per radian
  bool no_color = false;
  bool no_clear = false;
  double fuse_step_m = 0.25, fuse_step_deg = 15.0;
  double capture_hz = 0.0;        // both modes; 0: the displacement trigger
  std::string profile;            // ApplyExploreProfile; "" none
  std::string robot_config;       // over the profile's robot
  const CLI::App* app = nullptr;  // which options were given (they override profile and file)
  int threads = 0;
  MemoryBudgetOptions memory;
  PlannerLimits limits;  // --planner-hard-limit, --planner-hard-limit-min
};

// After a planner fault its thread may still run (hung) and its library's state be anything:
// exit() would run static destructors (the plugin's among them) beside it, so the process ends
// here, streams flushed, outputs already written.
[[noreturn]] void ExitAfterPlannerFault() {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(kExitPlannerFault);
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "(none)" : out;
}

// The usage checks that need no planner and no scene; kExitOk when they pass, else the exit code
// after printing why. Fills *starts from --start.
int CheckUsage(const ExploreOptions& o, std::vector<Eigen::Vector2f>* starts) {
  if (o.run.robots < 1) return Fail("--robots must be at least 1", kExitUsage);
  if (!(o.run.explore.max_time_s > 0.0)) return Fail("--max-time must be > 0", kExitUsage);
  if (!(o.fov_deg > kMinFovDeg && o.fov_deg < kMaxFovDeg))
    return Fail("--fov-deg must lie strictly between " + Num(kMinFovDeg) + " and " +
                    Num(kMaxFovDeg) + " degrees, got " + Num(o.fov_deg),
                kExitUsage);
  if (!(o.limits.budget_factor >= 1.0 && std::isfinite(o.limits.budget_factor)))
    return Fail("--planner-hard-limit must be a factor >= 1 of --plan-budget, got " +
                    Num(o.limits.budget_factor),
                kExitUsage);
  if (!(o.limits.min_s > 0.0 && std::isfinite(o.limits.min_s)))
    return Fail("--planner-hard-limit-min must be a finite number of seconds > 0, got " +
                    Num(o.limits.min_s),
                kExitUsage);
  if (!(o.recon_voxel_size == 0.0 || (o.recon_voxel_size >= bounds::kVoxelSizeMinM &&
                                      o.recon_voxel_size <= bounds::kVoxelSizeMaxM)))
    return Fail("--recon-voxel-size must be 0 (none) or between " + Num(bounds::kVoxelSizeMinM) +
                    " and " + Num(bounds::kVoxelSizeMaxM) + " m, got " + Num(o.recon_voxel_size),
                kExitUsage);
  if (!(o.capture_hz >= 0.0 && o.capture_hz <= kMaxCaptureHz))
    return Fail("--capture-hz must be 0 (capture by displacement) or a rate up to " +
                    Num(kMaxCaptureHz) + " frames per second, got " + Num(o.capture_hz),
                kExitUsage);
  if (!(o.max_range_m > kMinRangeM && o.max_range_m <= bounds::kDepthMaxM))
    return Fail("--max-range-m must be a finite number of metres above " + Num(kMinRangeM) +
                    " and at most " + Num(bounds::kDepthMaxM) + ", got " + Num(o.max_range_m),
                kExitUsage);
  std::error_code ec;
  const fs::path out(o.run.out_dir);
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return Fail("--out " + o.run.out_dir + " is not a folder", kExitUsage);
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec))
    return Fail("output folder's parent does not exist: " + parent.string(), kExitUsage);
  if (!o.start.empty()) {
    Result<std::vector<Eigen::Vector2f>> s = ParseStarts(o.start);
    if (!s.ok()) return Fail(s.status().message(), kExitUsage);
    if (int(s->size()) != o.run.robots)
      return Fail("--start gives " + std::to_string(s->size()) + " positions for " +
                      std::to_string(o.run.robots) + " robots",
                  kExitUsage);
    *starts = *s;
  }
  return kExitOk;
}

// --planner by name (refused with the list of available ones when unknown) or by path, with
// --planner-config. Returns kExitOk and fills *out, or the exit code after printing why.
int LoadPlannerOption(const ExploreOptions& o, std::unique_ptr<LoadedPlanner>* out) {
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
  PlannerFault fault;  // its call stays empty unless the plugin crashed or hung loading
  Result<std::unique_ptr<LoadedPlanner>> planner = LoadPlanner(o.planner,
                                                               {.config_json = config_json,
                                                                .seed = o.run.explore.seed,
                                                                .search_path = {},
                                                                .limits = o.limits},
                                                               &fault);
  if (!planner.ok() && !fault.call.empty()) {
    Fail(planner.status().message() + "; nothing was run", kExitPlannerFault);
    ExitAfterPlannerFault();
  }
  if (!planner.ok()) return Fail(planner.status().message(), kExitUsage);
  *out = std::move(planner).value();
  return kExitOk;
}

// Whether the user gave an option (so it overrides the profile's and the robot file's value).
bool Given(const ExploreOptions& o, const char* name) {
  return o.app != nullptr && o.app->count(name) > 0;
}

// The experiment the options ask for; a bad profile or robot file is refused (usage).
Result<ExploreRunParams> RunParams(const ExploreOptions& o, std::vector<Eigen::Vector2f> starts) {
  ExploreRunParams run = o.run;
  run.scene_load = SceneLoad(o.frame);
  run.starts = std::move(starts);
  ExploreParams& params = run.explore;
  if (!o.profile.empty()) VOXPLAN_RETURN_IF_ERROR(ApplyExploreProfile(o.profile, &params));
  if (!o.robot_config.empty()) {
    Result<RobotParams> robot = ReadRobotConfig(o.robot_config, params.robot);
    if (!robot.ok()) return robot.status();
    params.robot = *robot;
  }
  params.voxel_size_m = float(o.voxel_size);
  if (o.profile.empty() || Given(o, "--recon-voxel-size"))
    params.recon_voxel_size_m = float(o.recon_voxel_size);
  params.max_memory_bytes = MemoryBudgetBytes(o.memory);
  params.noise = !o.no_noise;
  params.fuse_labels = !o.no_labels;
  params.detector.noise = !o.no_detector_noise;
  if (o.profile.empty() || Given(o, "--poses"))
    params.poses =
        o.poses == "tracked" ? ExploreParams::Poses::kTracked : ExploreParams::Poses::kTruth;
  if (o.odometry_noise.size() == 2) {
    params.odometry.translation_per_m = o.odometry_noise[0];
    params.odometry.rotation_per_rad = o.odometry_noise[1];
  }
  params.fuse_color = !o.no_color;
  params.clear_beyond_range = !o.no_clear;
  params.trigger = {float(o.fuse_step_m), float(o.fuse_step_deg)};
  // The camera options: always without a profile or robot file (their defaults are the
  // robot's), else only when given.
  const bool plain = o.profile.empty() && o.robot_config.empty();
  if (plain || Given(o, "--fov-deg")) params.robot.explorer.horizontal_fov_deg = float(o.fov_deg);
  if (plain || Given(o, "--max-range-m")) params.robot.explorer.max_range_m = float(o.max_range_m);
  if (plain || Given(o, "--capture-hz"))
    params.robot.explorer.capture_hz = params.robot.reconstructor.capture_hz = float(o.capture_hz);
  return run;
}

int RunExploreCommand(const ExploreOptions& o) {
  std::vector<Eigen::Vector2f> starts;
  if (int code = CheckUsage(o, &starts); code != kExitOk) return code;
  std::vector<PathUse> outputs;
  for (const std::string& path : RunOutputFiles(o.run.out_dir)) outputs.push_back({"--out", path});
  const bool planner_file = o.planner.find('/') != std::string::npos;
  if (int code = RefusePathCollisions(outputs, {{"--scene", o.run.scene},
                                                {"--planner", planner_file ? o.planner : ""},
                                                {"--planner-config", o.planner_config},
                                                {"--robot-config", o.robot_config}});
      code != kExitOk)
    return code;
  std::unique_ptr<LoadedPlanner> planner;
  if (int code = LoadPlannerOption(o, &planner); code != kExitOk) return code;

  ThreadLimit limit(o.threads);
  const Stopwatch clock;
  ExploreRunObserver observer;
  observer.started = [&](const std::string& world_name) {
    std::cerr << "explore: " << world_name << ", " << o.run.robots << " robots, planner "
              << planner->name() << " " << planner->version() << ", max "
              << o.run.explore.max_time_s << " s simulated" << std::endl;
  };
  observer.progress = [](const ExploreProgress& p) {
    std::cerr << "explore: t=" << RoundTo(p.t_s, 1) << " s, " << p.frames_fused
              << " frames, coverage " << RoundTo(100.0 * p.coverage, 1) << "%, distance "
              << RoundTo(p.distance_total_m, 1) << " m, " << p.plan_calls << " plan calls"
              << std::endl;
  };
  Result<ExploreRunParams> asked = RunParams(o, std::move(starts));
  if (!asked.ok()) return Fail(asked.status().message(), kExitUsage);
  const ExploreRunParams& run = *asked;
  bool refused = false;
  OutputTransaction transaction;  // every file lands, or none (and no folder it made)
  transaction.WatchFolder(run.out_dir);
  Result<ExploreRunReport> report = RunExploreExperiment(run, *planner, observer, &refused);
  if (!report.ok()) return Fail(report.status().message(), refused ? kExitUsage : kExitFailure);
  if (int code = CommitOutputs(transaction); code != kExitOk) return code;
  const ExploreResult& r = report->loop;
  for (const std::string& w : report->warnings) Warn(w);
  json j = json::parse(RunSummaryJson(run, *report));
  j["command"] = "explore";
  j["out"] = run.out_dir;
  j["wall_s"] = RoundTo(clock.ElapsedMs() / 1e3, 2);
  std::cerr << "explore: " << r.terminated
            << (r.done_reason.empty() ? "" : " (" + r.done_reason + ")")
            << " at t=" << RoundTo(r.time_s, 1) << " s, completeness "
            << RoundTo(100.0 * report->quality.completeness, 1) << "%, distance "
            << RoundTo(report->metrics.distance_total_m, 1) << " m, " << r.plan_calls.size()
            << " plan calls -> " << run.out_dir << std::endl;
  PrintJsonLine(j);
  if (r.planner_fault) {
    Fail(r.planner_fault->Describe(planner->name()) +
             "; the run ended at t=" + Num(RoundTo(r.time_s, 1)) + " s with " + r.terminated +
             ", its outputs are in " + run.out_dir,
         kExitPlannerFault);
    ExitAfterPlannerFault();
  }
  return kExitOk;
}

}  // namespace

Command AddExploreCommand(CLI::App& app) {
  auto o = std::make_shared<ExploreOptions>();
  ExploreRunParams& run = o->run;
  CLI::App* sub = app.add_subcommand(
      "explore", "Closed-loop multi-robot exploration of a simulated scene with a planner plugin");
  auto positive = [sub](const char* name, double& value, const char* help) {
    sub->add_option(name, value, help)->check(InRange(1e-6, 1e6))->capture_default_str();
  };
  sub->add_option(
         "--scene", run.scene,
         "apartment:size=S|M|L|XL|R,seed=N, or a scene file (.ply .glb .obj .dae), Z-up metres "
         "by default")
      ->required();
  AddSceneFrameOptions(sub, o->frame);
  sub->add_option("--robots", run.robots, "Number of robots")
      ->check(IntInRange(1, 64))
      ->capture_default_str();
  sub->add_option("--planner", o->planner, "Planner name (libvoxplan_planner_<name>.so) or path")
      ->required();
  sub->add_option("--planner-config", o->planner_config, "JSON file handed to the planner");
  sub->add_option("--profile", o->profile,
                  std::string("Simulator settings of a paper's experiments (") +
                      ExploreProfileNames() +
                      "): guo2022 = Guo 2022's robot (head explorer, arm reconstructor, 2 Hz "
                      "capture, 2 s mode switch; explore/robot_config.h), a 2 cm reconstruction "
                      "volume, detector noise on; xu2017 = Xu 2017's robot (0.3 m/s, a Kinect's "
                      "58 deg and 0.5-4 m, 5 Hz capture, camera joints at 40 deg/s), a 2 cm "
                      "reconstruction volume, a 0.1 s loop step. Options given "
                      "beside it win");
  sub->add_option("--robot-config", o->robot_config,
                  "JSON file of the robot and both modes (speeds, fields of view, ranges, "
                  "mounts, capture, switch time; explore/robot_config.h), over --profile's; "
                  "every run writes the robot it used to robot.json in --out");
  sub->add_option("--seed", run.explore.seed, "Seed of the planner and the sensor noise")
      ->capture_default_str();
  sub->add_option("--max-time", run.explore.max_time_s, "Simulated seconds before the run stops")
      ->check(InRange(0.001, 1e6, "s"))
      ->capture_default_str();
  sub->add_option("--start", o->start,
                  "Start positions \"x,y;x,y;...\" in metres, one per robot (default: side by "
                  "side in the largest room)");
  sub->add_option("--out,-o", run.out_dir, "Output folder (created)")->required();
  sub->add_option("--voxel-size", o->voxel_size, "Voxel size of the fused map, metres")
      ->check(VoxelSize())
      ->capture_default_str();
  sub->add_option("--recon-voxel-size", o->recon_voxel_size,
                  "Voxel size of a second, finer map fused with the same frames for mesh.ply and "
                  "the mesh metrics (e.g. 0.02); 0: the mesh comes from the planning map")
      ->capture_default_str();
  sub->add_option("--width", run.explore.image_width, "Rendered image width, pixels")
      ->check(ImageSide())
      ->capture_default_str();
  sub->add_option("--height", run.explore.image_height, "Rendered image height, pixels")
      ->check(ImageSide())
      ->capture_default_str();
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
  sub->add_flag("--no-detector-noise", o->no_detector_noise,
                "Fuse the simulator's instance labels as they are (by default a detector model "
                "drops, erodes, merges and size-filters them per frame: sim/detector.h)");
  sub->add_option("--poses", o->poses,
                  "Where frames are fused: truth (the true camera poses) or tracked (poses the "
                  "frame-to-model tracker estimates from a noisy odometry prior; lost frames are "
                  "skipped; registration residual, ATE and frames lost go in metrics.json)")
      ->check(CLI::IsMember({"truth", "tracked"}))
      ->capture_default_str();
  sub->add_option("--odometry-noise", o->odometry_noise,
                  "With --poses tracked: odometry noise, 1 sigma per axis, as T,R: metres per "
                  "metre moved and radians per radian turned (default 0.02,0.01)")
      ->delimiter(',')
      ->expected(2)
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("--planner-picture", run.explore.keep_planner_drawings,
                "Also write planner.png: topdown.png with the planner's debug drawings over the "
                "floor, each layer as the last plan call that sent it drew it (a tensor field's "
                "glyphs, degenerate points and skeleton)");
  sub->add_flag("--no-color", o->no_color,
                "Render and fuse no colour (a grey mesh.ply; the metrics do not change)");
  positive("--planning-interval", run.explore.planning_interval_s,
           "Simulated seconds between re-planning calls");
  positive("--plan-budget", run.explore.plan_time_budget_s,
           "Wall seconds a plan call should take at most");
  sub->add_option("--planner-hard-limit", o->limits.budget_factor,
                  "A plan call running this many times --plan-budget (but at least "
                  "--planner-hard-limit-min) is given up: the run ends as planner_hung, exit 3")
      ->capture_default_str();
  sub->add_option("--planner-hard-limit-min", o->limits.min_s,
                  "Seconds: the least hard limit of a plan call")
      ->capture_default_str();
  positive("--eval-samples", run.eval_samples_per_m2,
           "Ground-truth samples per m² for completeness and accuracy");
  positive("--fuse-step", o->fuse_step_m, "Metres of camera travel between fused frames");
  positive("--fuse-step-deg", o->fuse_step_deg, "Degrees of camera turn between fused frames");
  sub->add_option("--capture-hz", o->capture_hz,
                  "Frames per second on the run clock, in both modes, while driving and dwelling "
                  "(a view's dwell gives floor(dwell x rate) frames); 0: by --fuse-step")
      ->capture_default_str();
  positive("--progress-interval", run.explore.progress_interval_s,
           "Simulated seconds between progress lines on stderr");
  sub->add_option("--threads", o->threads, "Worker threads (0: all)")->check(ThreadCount());
  AddMemoryBudgetOptions(sub, o->memory, /*with_on_limit=*/false);
  o->app = sub;
  return {sub, [o] { return RunExploreCommand(*o); }};
}

}  // namespace voxplan::cli
