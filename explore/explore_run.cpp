// One exploration experiment: scene and starts, the completeness probe, RunExplore, the final
// evaluation and the artefacts (explore/explore_run.h). Moved out of `voxplan explore` as it was.
#include "explore/explore_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>

#include "core/stopwatch.h"
#include "eval/visibility.h"
#include "explore/run_outputs.h"
#include "fusion/mesh_extract.h"
#include "sim/floor_plan.h"
#include "sim/raycaster.h"
#include "sim/robot.h"
#include "sim/tour.h"
#include "sim/world_io.h"

namespace voxplan {

namespace {

namespace fs = std::filesystem;

// The world params.scene names; *refused for a malformed apartment spec or a missing file.
Result<World> LoadScene(const ExploreRunParams& params, bool* refused) {
  std::error_code ec;
  Result<World> world = Status(StatusCode::kInternal, "no world");
  Result<ApartmentParams> apartment = ParseApartmentSpec(params.scene);
  if (apartment.ok()) {
    world = GenerateApartment(*apartment);  // parametric furniture: needs no shared data
  } else if (apartment.status().code() != StatusCode::kNotFound) {
    *refused = true;
    return apartment.status();
  } else {
    if (!fs::is_regular_file(params.scene, ec)) {
      *refused = true;
      return InvalidArgument("scene file not found: " + params.scene);
    }
    world = LoadWorld(params.scene, params.scene_load);
  }
  if (!world.ok()) return world.status().Naming(params.scene);
  return world;
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

// Ground truth for the time series' completeness: the surface sampled once, kept where `filter`
// (when set) says a camera could see it.
Result<std::vector<Eigen::Vector3f>> ProbePoints(const Mesh& ground_truth,
                                                 const PointSetFilter& filter, uint64_t seed) {
  Result<SurfaceSamples> gt_samples = SampleSurface(ground_truth, 100.0, seed);
  if (!gt_samples.ok()) return gt_samples.status();
  std::vector<Eigen::Vector3f> probe_points;
  for (const Eigen::Vector3d& p : gt_samples->points) probe_points.push_back(p.cast<float>());
  if (filter) {
    const std::vector<uint8_t> observable = filter(probe_points);
    size_t kept = 0;
    for (size_t i = 0; i < probe_points.size(); ++i)
      if (observable[i]) probe_points[kept++] = probe_points[i];
    probe_points.resize(kept);
  }
  return probe_points;
}

// Whether EvaluateObjects has anything to judge: an instance beside the structure classes.
bool HasObjects(const World& world) {
  if (world.triangle_instance.size() != world.mesh.num_triangles()) return false;
  const std::vector<std::string> structure = ObjectEvalParams{}.excluded_classes;
  for (const Instance& instance : world.instances)
    if (std::find(structure.begin(), structure.end(), instance.class_name) == structure.end())
      return true;
  return false;
}

// The final mesh (written at once), its quality against the ground truth and the run metrics.
Status Evaluate(const ExploreRunParams& params, const World& world, const FloorPlan& plan,
                const PointSetFilter& filter, ExploreRunReport& report) {
  const Stopwatch eval_clock;
  // The finer reconstruction volume when the run kept one, else the planning map.
  // Depth-weighted, one observation at the farthest range weighs 1 / range²: it still counts as
  // observed, as one observation does at constant weight (MeshParams::min_weight 0.5).
  MeshParams mp;
  if (report.loop.recon_volume && params.explore.recon_weighting == Weighting::kDepthDependent) {
    const RobotParams& robot = params.explore.robot;
    const float range = std::max(robot.explorer.max_range_m, robot.reconstructor.max_range_m);
    mp.min_weight = 0.5f / (range * range);
  }
  report.mesh =
      ExtractMesh(report.loop.recon_volume ? *report.loop.recon_volume : *report.loop.volume, mp);
  VOXPLAN_RETURN_IF_ERROR(WriteRunMesh(report.mesh, params.out_dir));
  MeshEvalParams ep;
  ep.threshold_m = 0.05f;
  ep.samples_per_m2 = float(params.eval_samples_per_m2);
  ep.seed = params.explore.seed;
  if (filter) ep.ground_truth_filter = filter;
  // Xu 2017's reference (X L381): the observable surface below the robot's height, the floor
  // map's band top; what lies above it, ceilings included, is left out.
  ep.below_z_m = params.explore.floor.band_max_m;
  if (report.mesh.num_triangles() > 0) {
    Result<MeshEvalResult> q = EvaluateMesh(report.mesh, world.mesh, ep);
    if (!q.ok()) return q.status().Naming(params.scene);
    report.quality = *q;
    report.completeness_below_robot = q->completeness_below;
    if (HasObjects(world)) {
      ObjectEvalParams op;
      op.threshold_m = kObjectThreshold_m;
      op.extra_thresholds_m = {kObjectExtraThreshold_m};
      op.samples_per_m2 = float(params.eval_samples_per_m2);
      op.seed = params.explore.seed;
      Result<ObjectsEvalResult> objects = EvaluateObjects(report.mesh, world, op);
      if (!objects.ok()) return objects.status().Naming(params.scene);
      report.objects = std::move(*objects);
    }
  }
  Result<RunMetrics> metrics = EvaluateRun(report.loop.tracks, {.scene_area_m2 = FloorArea(plan)});
  if (!metrics.ok()) return metrics.status();
  report.metrics = *metrics;
  report.eval_ms = eval_clock.ElapsedMs();
  return Status();
}

std::vector<std::string> Warnings(const ExploreResult& r, double plan_budget_s) {
  std::vector<std::string> warnings;
  if (r.over_budget_calls > 0)
    warnings.push_back(std::to_string(r.over_budget_calls) + " of " +
                       std::to_string(r.plan_calls.size()) +
                       " plan calls took longer than the budget of " +
                       std::to_string(plan_budget_s) + " s (plan_calls.csv, plan_log.txt)");
  if (r.failed_plans > 0)
    warnings.push_back(std::to_string(r.failed_plans) +
                       " plan calls failed (messages in plan_log.txt)");
  if (r.blocks_dropped > 0)
    warnings.push_back(
        "the map reached its memory budget (--max-memory): " + std::to_string(r.blocks_dropped) +
        " new blocks were not allocated, so what they saw is missing from the map");
  if (r.rejected_tasks > 0)
    warnings.push_back("the planner's output was rejected " + std::to_string(r.rejected_tasks) +
                       " times (reasons in plan_log.txt)");
  if (r.camera_position_clamped_workspace + r.camera_position_clamped_speed > 0)
    warnings.push_back("the arm camera's trajectory positions were moved into its workspace " +
                       std::to_string(r.camera_position_clamped_workspace) +
                       " times and held back by its speed " +
                       std::to_string(r.camera_position_clamped_speed) +
                       " times (the first of each in plan_log.txt)");
  return warnings;
}

}  // namespace

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
                             "' (apartment:size=S|M|L|XL|R,seed=N)");
    }
  }
  return params;
}

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

Result<ExploreRunReport> RunExploreExperiment(const ExploreRunParams& params,
                                              LoadedPlanner& planner,
                                              const ExploreRunObserver& observer, bool* refused) {
  bool refused_here = false;
  if (refused == nullptr) refused = &refused_here;
  *refused = false;
  const Stopwatch clock;
  Result<World> world = LoadScene(params, refused);
  if (!world.ok()) return world.status();
  Result<FloorPlan> plan = RasterizeFloorPlan(*world);
  if (!plan.ok()) return plan.status().Naming(params.scene);

  const ExploreParams& explore = params.explore;
  if (Status s = explore.Validate(); !s.ok()) {
    *refused = true;
    return s;
  }
  std::vector<Eigen::Vector2f> starts = params.starts;
  if (starts.empty()) {
    Result<std::vector<Eigen::Vector2f>> chosen =
        ChooseStarts(*plan, world->rooms, params.robots, explore.robot.radius_m);
    if (!chosen.ok()) return chosen.status().Naming(params.scene);
    starts = *chosen;
  } else if (Status s = CheckStarts(*plan, starts, explore.robot.radius_m); !s.ok()) {
    *refused = true;
    return s;
  }
  std::error_code ec;
  fs::create_directories(fs::path(params.out_dir), ec);
  if (ec) return IoError("cannot create output folder " + params.out_dir + ": " + ec.message());
  // The world as run, first: the evaluation commands score against it (and check they do).
  Result<WrittenWorld> written = WriteWorld(*world, params.out_dir, RunWorldFiles());
  if (!written.ok()) return written.status();

  // Ground truth for completeness: the observable surface, sampled once for the time series.
  ExploreRunReport report;
  Result<std::unique_ptr<MeshRaycaster>> gt_raycaster = MeshRaycaster::Create(*world);
  if (!gt_raycaster.ok()) return gt_raycaster.status().Naming(params.scene);
  Result<PointSetFilter> filter =
      TourFilter(*world, *plan, **gt_raycaster, explore, &report.tour_frames);
  if (!filter.ok()) return filter.status().Naming(params.scene);
  Result<std::vector<Eigen::Vector3f>> probe_points =
      ProbePoints(world->mesh, *filter, explore.seed);
  if (!probe_points.ok()) return probe_points.status().Naming(params.scene);
  report.setup_ms = clock.ElapsedMs();
  report.world_name = world->name;
  report.scene_floor_z_m = world->source_floor_z_m;
  report.world_fingerprint = WorldFingerprintHex(*world);
  report.planner_name = planner.name();

  if (observer.started) observer.started(world->name);
  Result<ExploreResult> run = RunExplore(
      *world, *plan, starts, planner, explore,
      [&](const TsdfVolume& v) { return VolumeCompleteness(v, *probe_points); }, observer.progress);
  if (!run.ok()) return run.status();
  report.loop = std::move(*run);

  VOXPLAN_RETURN_IF_ERROR(Evaluate(params, *world, *plan, *filter, report));
  report.scene_area_m2 = FloorArea(*plan);
  report.observable_reference = bool(*filter);
  VOXPLAN_RETURN_IF_ERROR(WriteRunOutputs(params, report));
  report.warnings = Warnings(report.loop, explore.plan_time_budget_s);
  return report;
}

}  // namespace voxplan
