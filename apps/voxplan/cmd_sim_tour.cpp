// voxplan sim tour: plan a deterministic camera tour that sees every room of a scene (floor plan,
// viewpoint cover, ordered visits, 360° spins level, up and down at each) and write it as a TUM
// trajectory.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/voxplan/cli_common.h"
#include "apps/voxplan/path_check.h"
#include "core/bounds.h"
#include "core/parallel.h"
#include "io/tum_trajectory.h"
#include "sim/floor_plan.h"
#include "sim/scene_loader.h"
#include "sim/tour.h"

namespace voxplan::cli {

namespace {

namespace fs = std::filesystem;

struct SimTourOptions {
  std::string scene;
  std::string out;
  SceneFrameOptions frame;
  std::string mode = "explorer";
  double radius = 0.2;
  double camera_height = 1.2;
  double pitch_deg = 0.0;
  std::vector<double> spin_pitches_deg = {0.0, 45.0, -45.0};
  double view_range = 2.0;
  double resolution = 0.05;
  double frame_step = 0.1;
  double frame_step_deg = 10.0;
  std::string start;  // "x,y"
  int threads = 0;
};

int RunSimTour(const SimTourOptions& o) {
  if (o.mode != "explorer" && o.mode != "reconstructor")
    return Fail("--mode must be explorer or reconstructor, got '" + o.mode + "'", kExitUsage);
  std::error_code ec;
  if (!fs::is_regular_file(o.scene, ec))
    return Fail("scene file not found: " + o.scene, kExitUsage);
  if (const std::string why = CheckOutputFile(o.out); !why.empty()) return Fail(why, kExitUsage);
  if (int code = RefusePathCollisions({{"--out", o.out}}, {{"--scene", o.scene}}); code != kExitOk)
    return code;
  TourParams params;
  params.mode = o.mode == "explorer" ? RobotMode::kExplorer : RobotMode::kReconstructor;
  params.robot.radius_m = float(o.radius);
  params.robot.camera_height_m = float(o.camera_height);
  params.camera_pitch_deg = float(o.pitch_deg);
  params.spin_pitches_deg.assign(o.spin_pitches_deg.begin(), o.spin_pitches_deg.end());
  params.view_range_m = float(o.view_range);
  params.frame_step_m = float(o.frame_step);
  params.frame_step_deg = float(o.frame_step_deg);
  if (!o.start.empty()) {
    float x = 0.f, y = 0.f;
    int consumed = 0;
    if (std::sscanf(o.start.c_str(), "%f,%f%n", &x, &y, &consumed) != 2 ||
        consumed != int(o.start.size()) || !std::isfinite(x) || !std::isfinite(y))
      return Fail("--start wants x,y in metres (finite), got '" + o.start + "'", kExitUsage);
    params.start_W = Eigen::Vector2f(x, y);
  }
  if (Status s = params.Validate(); !s.ok()) return Fail(s.message(), kExitUsage);

  ThreadLimit limit(o.threads);
  const Stopwatch clock;
  Result<World> world = LoadWorld(o.scene, SceneLoad(o.frame));
  if (!world.ok()) {
    const bool usage = world.status().code() == StatusCode::kInvalidArgument;
    return Fail(MessageNaming(world.status(), o.scene), usage ? kExitUsage : kExitFailure);
  }
  FloorPlanParams plan_params;
  plan_params.resolution_m = float(o.resolution);
  Result<FloorPlan> plan = RasterizeFloorPlan(*world, plan_params);
  if (!plan.ok()) return Fail(MessageNaming(plan.status(), o.scene));
  Result<Tour> tour = PlanTour(*plan, world->rooms, params);
  if (!tour.ok()) return Fail(MessageNaming(tour.status(), o.scene));
  const double plan_ms = clock.ElapsedMs();
  if (Status s = WriteTumTrajectory(o.out, tour->timestamps_s, tour->T_W_C); !s.ok())
    return Fail(s.message());
  for (int r : tour->unreachable_rooms)
    Warn("room '" + world->rooms[size_t(r)].name +
         "' has no cell the robot can reach; not visited");

  nlohmann::json j;
  j["command"] = "sim tour";
  j["scene"] = o.scene;
  j["out"] = o.out;
  j["mode"] = o.mode;
  j["frames"] = tour->T_W_C.size();
  j["viewpoints"] = tour->viewpoints_W.size();
  j["spin_pitches_deg"] = o.spin_pitches_deg;
  j["rooms"] = world->rooms.size();
  nlohmann::json unreachable = nlohmann::json::array();
  for (int r : tour->unreachable_rooms) unreachable.push_back(world->rooms[size_t(r)].name);
  j["unreachable_rooms"] = unreachable;
  j["length_m"] = RoundTo(tour->length_m, 2);
  j["duration_s"] = RoundTo(tour->duration_s, 2);
  j["coverage"] = RoundTo(tour->coverage, 4);
  j["reachable_area_m2"] =
      RoundTo(double(tour->reachable_cells) * plan->resolution_m * plan->resolution_m, 2);
  j["plan_ms"] = RoundTo(plan_ms, 1);
  std::cerr << "sim tour: " << world->name << ": " << tour->viewpoints_W.size() << " viewpoints, "
            << tour->T_W_C.size() << " frames, " << RoundTo(tour->length_m, 1) << " m, "
            << RoundTo(tour->duration_s, 1) << " s, coverage " << RoundTo(100.0 * tour->coverage, 1)
            << "% -> " << o.out << "\n";
  PrintJsonLine(j);
  return kExitOk;
}

}  // namespace

Command AddSimTourCommand(CLI::App& sim) {
  auto o = std::make_shared<SimTourOptions>();
  CLI::App* sub = sim.add_subcommand(
      "tour", "Plan a camera tour that sees every room of a scene; write a TUM trajectory");
  sub->add_option("--scene", o->scene, "Scene file (.ply .glb .obj .dae), Z-up metres by default")
      ->required();
  sub->add_option("--out,-o", o->out, "Trajectory file to write (TUM, camera-to-world)")
      ->required();
  AddSceneFrameOptions(sub, o->frame);
  sub->add_option("--mode", o->mode, "Robot mode: explorer or reconstructor (speed, field of view)")
      ->capture_default_str();
  sub->add_option("--radius", o->radius, "Robot footprint radius, metres")
      ->check(InRange(0.01, 5.0, "m"))
      ->capture_default_str();
  sub->add_option("--camera-height", o->camera_height, "Camera height above the floor, metres")
      ->check(InRange(0.01, 10.0, "m"))
      ->capture_default_str();
  sub->add_option("--pitch", o->pitch_deg,
                  "Camera pitch while driving, degrees (positive looks up)")
      ->check(InRange(-90.0, 90.0, "degrees"))
      ->capture_default_str();
  sub->add_option("--spin-pitches", o->spin_pitches_deg,
                  "Camera pitch of each 360° spin at a viewpoint, degrees, comma-separated")
      ->delimiter(',')
      ->check(InRange(-90.0, 90.0, "degrees"))
      ->capture_default_str();
  sub->add_option("--view-range", o->view_range, "Range a viewpoint covers, metres")
      ->check(InRange(0.1, bounds::kDepthMaxM, "m"))
      ->capture_default_str();
  sub->add_option("--resolution", o->resolution, "Floor plan cell size, metres")
      ->check(InRange(0.01, 1.0, "m"))
      ->capture_default_str();
  sub->add_option("--frame-step", o->frame_step, "Metres of travel between frames")
      ->check(InRange(0.01, 10.0, "m"))
      ->capture_default_str();
  sub->add_option("--frame-step-deg", o->frame_step_deg, "Degrees of turning between frames")
      ->check(InRange(0.1, 360.0, "degrees"))
      ->capture_default_str();
  sub->add_option("--start", o->start, "Start position x,y in metres (default: first viewpoint)");
  sub->add_option("--threads", o->threads, "Worker threads (0: all)")->check(ThreadCount());
  return {sub, [o] { return RunSimTour(*o); }};
}

}  // namespace voxplan::cli
