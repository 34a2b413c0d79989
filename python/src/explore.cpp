// voxplan.explore: one exploration experiment (explore/explore_run.h, what `voxplan explore`
// runs) with a planner plugin, its artefacts in an output folder, its metrics as a dict; and
// voxplan.planners, the plugins it can load.
#include <dlfcn.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/bounds.h"
#include "core/parallel.h"
#include "explore/explore_run.h"
#include "explore/robot_config.h"
#include "explore/run_outputs.h"
#include "io/output_transaction.h"
#include "plugins/host/plugin_host.h"
#include "python/src/objects.h"

namespace voxplan::python {

namespace {

namespace fs = std::filesystem;

std::string PathString(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

// The folder this extension module was loaded from.
fs::path ModuleDir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&ModuleDir), &info) == 0 || !info.dli_fname) return {};
  std::error_code ec;
  const fs::path file = fs::canonical(info.dli_fname, ec);
  return ec ? fs::path() : file.parent_path();
}

// $VOXPLAN_PLANNER_PATH, then the installed planners relative to an installed module (the
// module never looks into the build tree then), else the build's planner folder.
std::vector<fs::path> PlannerSearchPath() {
  std::vector<fs::path> path;
  if (const char* env = std::getenv("VOXPLAN_PLANNER_PATH")) {
    const std::string s = env;
    size_t begin = 0;
    while (begin <= s.size()) {
      const size_t end = std::min(s.find(':', begin), s.size());
      if (end > begin) path.emplace_back(s.substr(begin, end - begin));
      begin = end + 1;
    }
  }
  std::error_code ec;
  const fs::path installed = ModuleDir() / VOXPLAN_PYTHON_PLANNER_INSTALL_REL;
  if (!ModuleDir().empty() && fs::is_directory(installed, ec)) {
    path.push_back(installed.lexically_normal());
  } else {
    path.emplace_back(VOXPLAN_PYTHON_PLANNER_BUILD_DIR);
  }
  return path;
}

struct PyExploreResult {
  py::dict metrics, summary;
  py::object mesh;    // voxplan.Mesh
  py::object volume;  // voxplan.Volume: the planning map
  py::object recon_volume;
  py::object out_dir;  // str, or None for a temporary folder (removed)
  std::string terminated, done_reason, world_name, planner;
  std::vector<std::string> warnings;
  py::object planner_fault;  // str or None
};

ExploreParams::Poses ParsePoses(const std::string& poses) {
  if (poses == "truth") return ExploreParams::Poses::kTruth;
  if (poses == "tracked") return ExploreParams::Poses::kTracked;
  throw py::value_error("poses must be 'truth' or 'tracked', got '" + poses + "'");
}

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// `value` within [lo, hi] (the CLI's bounds, apps/voxplan/cmd_explore.cpp), else ValueError
// naming the argument and the range.
void CheckIn(const char* name, double value, double lo, double hi, const char* unit = "") {
  if (Status s = bounds::CheckRange(name, value, lo, hi, unit); !s.ok())
    throw py::value_error(s.message());
}

// The camera options' limits, as `voxplan explore` checks them (exclusive): RobotParams' field-
// of-view bounds, and the near depth frames are fused from.
constexpr double kMinFovDeg = 1.0, kMaxFovDeg = 179.0;
constexpr double kMinRangeM = 0.1;
// The CLI's positive options (planning interval, fuse steps, ...).
constexpr double kPositiveMin = 1e-6, kPositiveMax = 1e6;
// --floor-z's bound (apps/voxplan/cli_common.h kMaxFloorZ_m).
constexpr double kMaxFloorZ_m = 100.0;

// The scene frame options of `voxplan explore` (--up, --scale, --floor-z: apps/voxplan/
// cli_common.cpp SceneLoad), for scene files.
SceneLoadOptions SceneFrame(const std::string& up, double scale, const py::object& floor_z) {
  SceneLoadOptions load;
  if (up == "z" || up == "Z") {
    load.up = UpAxis::kZ;
  } else if (up == "y" || up == "Y") {
    load.up = UpAxis::kY;  // a Y-up file rotated into the Z-up world
  } else {
    throw py::value_error("up must be 'z' or 'y', got '" + up + "'");
  }
  CheckIn("scale", scale, kPositiveMin, kPositiveMax);
  load.scale = float(scale);
  if (py::isinstance<py::str>(floor_z)) {
    const std::string text = floor_z.cast<std::string>();
    if (text != "auto")
      throw py::value_error("floor_z must be 'auto' or a height in metres within +-" +
                            Num(kMaxFloorZ_m) + ", got '" + text + "'");
    load.detect_floor = true;
  } else {
    const double z = floor_z.cast<double>();
    if (!(std::abs(z) <= kMaxFloorZ_m))
      throw py::value_error("floor_z must be 'auto' or a height in metres within +-" +
                            Num(kMaxFloorZ_m) + ", got " + Num(z));
    load.floor_z_m = float(z);
  }
  return load;
}

std::unique_ptr<PyExploreResult> Explore(
    const std::string& scene, const std::string& planner_name, const py::object& planner_config,
    int robots, uint64_t seed, double max_time, const py::object& out_dir_in,
    const py::object& starts_in, double voxel_size, std::optional<double> recon_voxel_size,
    int width, int height, bool noise, bool labels, bool detector_noise, bool color,
    const std::string& poses, const py::object& profile, double planning_interval,
    double plan_budget, double eval_samples, std::optional<int> threads,
    std::optional<uint64_t> max_memory, const py::object& progress, const py::object& robot_config,
    std::optional<double> fov_deg, std::optional<double> max_range, bool clear_beyond_range,
    const py::object& odometry_noise, bool planner_picture, double planner_hard_limit,
    double planner_hard_limit_min, std::optional<double> capture_hz, double fuse_step,
    double fuse_step_deg, double progress_interval, const std::string& up, double scale,
    const py::object& floor_z) {
  const py::module_ json = py::module_::import("json");
  std::string config_json = "{}";
  if (py::isinstance<py::str>(planner_config)) {
    config_json = planner_config.cast<std::string>();
    try {
      json.attr("loads")(config_json);
    } catch (const py::error_already_set&) {
      throw py::value_error("planner_config is not valid JSON");
    }
  } else if (!planner_config.is_none()) {
    config_json = json.attr("dumps")(planner_config).cast<std::string>();
  }
  if (robots < 1 || robots > 64) throw py::value_error("robots must be in [1, 64]");
  if (!(max_time > 0.0)) throw py::value_error("max_time must be > 0 seconds");
  if (threads) CheckThreads(*threads);
  // The CLI's refusals before any work (apps/voxplan/cmd_explore.cpp CheckUsage), by argument.
  if (fov_deg && !(*fov_deg > kMinFovDeg && *fov_deg < kMaxFovDeg))
    throw py::value_error("fov_deg must lie strictly between " + Num(kMinFovDeg) + " and " +
                          Num(kMaxFovDeg) + " degrees, got " + Num(*fov_deg));
  if (max_range && !(*max_range > kMinRangeM && *max_range <= bounds::kDepthMaxM))
    throw py::value_error("max_range must be a finite number of metres above " + Num(kMinRangeM) +
                          " and at most " + Num(bounds::kDepthMaxM) + ", got " + Num(*max_range));
  if (capture_hz && !(*capture_hz >= 0.0 && *capture_hz <= kMaxCaptureHz))
    throw py::value_error("capture_hz must be 0 (capture by displacement) or a rate up to " +
                          Num(kMaxCaptureHz) + " frames per second, got " + Num(*capture_hz));
  if (!(planner_hard_limit >= 1.0 && std::isfinite(planner_hard_limit)))
    throw py::value_error("planner_hard_limit must be a factor >= 1 of plan_budget, got " +
                          Num(planner_hard_limit));
  if (!(planner_hard_limit_min > 0.0 && std::isfinite(planner_hard_limit_min)))
    throw py::value_error("planner_hard_limit_min must be a finite number of seconds > 0, got " +
                          Num(planner_hard_limit_min));
  std::optional<std::pair<double, double>> odometry;
  if (!odometry_noise.is_none()) {
    const auto tr = odometry_noise.cast<std::vector<double>>();
    if (tr.size() != 2)
      throw py::value_error("odometry_noise must be (translation per metre, rotation per radian)");
    CheckIn("odometry_noise translation (per metre moved)", tr[0], 0.0, 1.0);
    CheckIn("odometry_noise rotation (per radian turned)", tr[1], 0.0, 1.0);
    odometry.emplace(tr[0], tr[1]);
  }
  CheckIn("planning_interval", planning_interval, kPositiveMin, kPositiveMax, "s");
  CheckIn("plan_budget", plan_budget, kPositiveMin, kPositiveMax, "s");
  CheckIn("eval_samples", eval_samples, kPositiveMin, kPositiveMax, "per m^2");
  CheckIn("fuse_step", fuse_step, kPositiveMin, kPositiveMax, "m");
  CheckIn("fuse_step_deg", fuse_step_deg, kPositiveMin, kPositiveMax, "degrees");
  CheckIn("progress_interval", progress_interval, kPositiveMin, kPositiveMax, "s");
  const PlannerLimits limits{.budget_factor = planner_hard_limit,
                             .min_s = planner_hard_limit_min,
                             .unbudgeted_s = PlannerLimits{}.unbudgeted_s};

  ExploreRunParams run;
  run.scene = scene;
  run.scene_load = SceneFrame(up, scale, floor_z);
  run.robots = robots;
  ExploreParams& params = run.explore;
  // As `voxplan explore` orders them (cmd_explore.cpp RunParams): the profile, then the robot
  // file over its robot, then the arguments; the camera ones only when given (None keeps the
  // profile's, the file's, or the built-in robot's).
  if (!profile.is_none()) ThrowIfError(ApplyExploreProfile(profile.cast<std::string>(), &params));
  if (!robot_config.is_none())
    params.robot = ValueOrThrow(ReadRobotConfig(PathString(robot_config), params.robot));
  if (fov_deg) params.robot.explorer.horizontal_fov_deg = float(*fov_deg);
  if (max_range) params.robot.explorer.max_range_m = float(*max_range);
  if (capture_hz)
    params.robot.explorer.capture_hz = params.robot.reconstructor.capture_hz = float(*capture_hz);
  if (odometry) {
    params.odometry.translation_per_m = float(odometry->first);
    params.odometry.rotation_per_rad = float(odometry->second);
  }
  params.clear_beyond_range = clear_beyond_range;
  params.keep_planner_drawings = planner_picture;
  params.trigger = {float(fuse_step), float(fuse_step_deg)};
  params.progress_interval_s = progress_interval;
  params.seed = seed;
  params.max_time_s = max_time;
  params.voxel_size_m = float(voxel_size);
  if (recon_voxel_size) {
    if (!(*recon_voxel_size == 0.0 || (*recon_voxel_size >= bounds::kVoxelSizeMinM &&
                                       *recon_voxel_size <= bounds::kVoxelSizeMaxM)))
      throw py::value_error("recon_voxel_size must be 0 (none) or within " +
                            bounds::RangeText(bounds::kVoxelSizeMinM, bounds::kVoxelSizeMaxM, "m"));
    params.recon_voxel_size_m = float(*recon_voxel_size);
  }
  params.image_width = width;
  params.image_height = height;
  params.noise = noise;
  params.fuse_labels = labels;
  params.detector.noise = detector_noise;
  params.fuse_color = color;
  params.poses = ParsePoses(poses);
  params.planning_interval_s = planning_interval;
  params.plan_time_budget_s = plan_budget;
  params.max_memory_bytes = max_memory ? *max_memory : DefaultMemoryBudgetBytes();
  run.eval_samples_per_m2 = eval_samples;
  if (!starts_in.is_none()) {
    for (const py::handle& s : starts_in) {
      const auto xy = s.cast<std::vector<float>>();
      if (xy.size() != 2) throw py::value_error("starts must be (x, y) pairs in metres");
      run.starts.emplace_back(xy[0], xy[1]);
    }
    if (int(run.starts.size()) != robots)
      throw py::value_error("starts gives " + std::to_string(run.starts.size()) +
                            " positions for " + std::to_string(robots) + " robots");
  }

  // The output folder: the caller's (its parent must exist), or a temporary one.
  const bool temporary = out_dir_in.is_none();
  if (temporary) {
    std::string tmpl = (fs::temp_directory_path() / "voxplan-explore-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw StatusError(IoError("cannot create a temporary folder"));
    run.out_dir = tmpl;
  } else {
    run.out_dir = PathString(out_dir_in);
    const fs::path out(run.out_dir);
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(parent, ec))
      throw StatusError(NotFound("output folder's parent does not exist: " + parent.string()));
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
      throw py::value_error("out_dir " + run.out_dir + " is not a folder");
  }
  struct RemoveTemporary {
    bool active;
    std::string dir;
    ~RemoveTemporary() {
      std::error_code ec;
      if (active) fs::remove_all(dir, ec);
    }
  } remove_temporary{temporary, run.out_dir};

  PlannerFault load_fault;
  std::unique_ptr<LoadedPlanner> planner;
  {
    py::gil_scoped_release release;
    Result<std::unique_ptr<LoadedPlanner>> loaded = LoadPlanner(planner_name,
                                                                {.config_json = config_json,
                                                                 .seed = seed,
                                                                 .search_path = PlannerSearchPath(),
                                                                 .limits = limits},
                                                                &load_fault);
    if (!loaded.ok()) {
      if (!load_fault.call.empty())
        throw StatusError(
            Status(StatusCode::kInternal, loaded.status().message() + "; nothing was run"));
      throw StatusError(loaded.status());
    }
    planner = std::move(loaded).value();
  }

  std::optional<py::error_already_set> progress_error;
  ExploreRunObserver observer;
  if (!progress.is_none()) {
    observer.progress = [&](const ExploreProgress& p) {
      py::gil_scoped_acquire gil;
      if (progress_error) return;
      try {
        py::dict d;
        d["t_s"] = p.t_s;
        d["frames_fused"] = p.frames_fused;
        d["coverage"] = p.coverage;
        d["distance_total_m"] = p.distance_total_m;
        d["plan_calls"] = p.plan_calls;
        progress(d);
      } catch (py::error_already_set& e) {
        progress_error.emplace(std::move(e));
      }
    };
  }
  std::optional<ExploreRunReport> report;
  {
    py::gil_scoped_release release;
    std::lock_guard write_lock(WriteMutex());
    std::optional<ThreadLimit> limit;
    if (threads) limit.emplace(*threads);
    OutputTransaction transaction;  // every file lands, or none (and no folder it made)
    transaction.WatchFolder(run.out_dir);
    report.emplace(ValueOrThrow(RunExploreExperiment(run, *planner, observer)));
    ThrowIfError(transaction.Commit());
  }
  if (progress_error) {
    py::error_already_set e = std::move(*progress_error);
    progress_error.reset();
    throw e;
  }

  auto out = std::make_unique<PyExploreResult>();
  out->metrics = json.attr("loads")(RunMetricsJson(run, *report)).cast<py::dict>();
  out->summary = json.attr("loads")(RunSummaryJson(run, *report)).cast<py::dict>();
  auto mesh = std::make_unique<PyMesh>();
  mesh->mesh = std::move(report->mesh);
  out->mesh = py::cast(std::move(mesh));
  ExploreResult& loop = report->loop;
  // Explored worlds are sim's, z-up.
  out->volume = loop.volume
                    ? WrapVolume(std::move(*loop.volume), IntegrateParams{}, WorldUp::kPlusZ)
                    : py::none();
  out->recon_volume = loop.recon_volume ? WrapVolume(std::move(*loop.recon_volume),
                                                     IntegrateParams{}, WorldUp::kPlusZ)
                                        : py::none();
  out->out_dir = temporary ? py::object(py::none()) : py::object(py::str(run.out_dir));
  out->terminated = loop.terminated;
  out->done_reason = loop.done_reason;
  out->world_name = report->world_name;
  out->planner = planner->name();
  out->warnings = report->warnings;
  out->planner_fault = py::none();
  for (const std::string& w : out->warnings) Warn(w);
  if (loop.planner_fault) {
    const std::string why = loop.planner_fault->Describe(planner->name());
    out->planner_fault = py::str(why);
    Warn(why + "; the run ended at t=" + std::to_string(loop.time_s) + " s with " +
         loop.terminated);
  }
  return out;
}

}  // namespace

void BindExplore(py::module_& m) {
  py::class_<PyExploreResult>(m, "ExploreResult", R"doc(
What voxplan.explore returns: metrics (metrics.json as a dict: completeness, accuracy,
distances, times, plan calls, termination), summary (the same plus the wall-time breakdown:
`voxplan explore`'s JSON line), the final mesh, the fused planning map (and the finer
reconstruction map when one was asked for), and the output folder.
)doc")
      .def_readonly("metrics", &PyExploreResult::metrics)
      .def_readonly("summary", &PyExploreResult::summary)
      .def_readonly("mesh", &PyExploreResult::mesh)
      .def_readonly("volume", &PyExploreResult::volume)
      .def_readonly("recon_volume", &PyExploreResult::recon_volume)
      .def_readonly("out_dir", &PyExploreResult::out_dir,
                    "the folder with the run's artefacts, or None (a temporary one, removed)")
      .def_readonly("terminated", &PyExploreResult::terminated,
                    "'done', 'time_limit', 'planner_crashed' or 'planner_hung'")
      .def_readonly("done_reason", &PyExploreResult::done_reason)
      .def_readonly("world_name", &PyExploreResult::world_name)
      .def_readonly("planner", &PyExploreResult::planner)
      .def_readonly("warnings", &PyExploreResult::warnings)
      .def_readonly("planner_fault", &PyExploreResult::planner_fault,
                    "how the planner crashed or hung, or None")
      .def("__repr__", [](const PyExploreResult& r) {
        return "<voxplan.ExploreResult " + r.world_name + " " + r.planner + ": " + r.terminated +
               ">";
      });

  m.def("explore", &Explore, py::arg("scene"), py::arg("planner"), py::kw_only(),
        py::arg("planner_config") = py::none(), py::arg("robots") = 3, py::arg("seed") = 1,
        py::arg("max_time") = 1800.0, py::arg("out_dir") = py::none(),
        py::arg("starts") = py::none(), py::arg("voxel_size") = 0.05,
        py::arg("recon_voxel_size") = py::none(), py::arg("width") = 320, py::arg("height") = 240,
        py::arg("noise") = true, py::arg("labels") = true, py::arg("detector_noise") = true,
        py::arg("color") = true, py::arg("poses") = "truth", py::arg("profile") = py::none(),
        py::arg("planning_interval") = 15.0, py::arg("plan_budget") = 1.0,
        py::arg("eval_samples") = 100.0, py::arg("threads") = py::none(),
        py::arg("max_memory") = py::none(), py::arg("progress") = py::none(),
        py::arg("robot_config") = py::none(), py::arg("fov_deg") = py::none(),
        py::arg("max_range") = py::none(), py::arg("clear_beyond_range") = true,
        py::arg("odometry_noise") = py::none(), py::arg("planner_picture") = false,
        py::arg("planner_hard_limit") = PlannerLimits{}.budget_factor,
        py::arg("planner_hard_limit_min") = PlannerLimits{}.min_s,
        py::arg("capture_hz") = py::none(), py::arg("fuse_step") = 0.25,
        py::arg("fuse_step_deg") = 15.0,
        py::arg("progress_interval") = ExploreParams{}.progress_interval_s, py::arg("up") = "z",
        py::arg("scale") = 1.0, py::arg("floor_z") = 0.0, R"doc(
Runs one exploration experiment as `voxplan explore` does: scene 'apartment:size=S|M|L|XL|R,
seed=N' (generated) or a scene file; planner a plugin name (see planners()) or a path to a .so,
with planner_config a dict or JSON text; simulated robots drive the planner's tasks for at most
max_time simulated seconds, their frames fused into a voxel_size map; then the mesh is scored.
Every option of `voxplan explore` is an argument here, with its default and bounds (a value out
of them raises ValueError naming the argument and the range):
  scene files: up 'z' or 'y' (a Y-up file), scale to metres, floor_z the file's floor height
  (metres after up and scale; 'auto': detected) the world is moved down by;
  profile ('guo2022', 'xu2017'), then robot_config (a robot JSON file, explore/robot_config.h)
  over its robot, then fov_deg, max_range (metres) and capture_hz (frames per second; 0: by
  displacement) of the explorer camera: None keeps the profile's, the file's or the built-in
  robot's (90 degrees, 5 m, 0);
  clear_beyond_range: depth past max_range clears the free space in front of it;
  odometry_noise (T, R): with poses='tracked', 1 sigma per metre moved and per radian turned
  (default 0.02, 0.01);
  fuse_step (m), fuse_step_deg: camera travel and turn between fused frames;
  planner_picture: also write planner.png (the planner's debug drawings over the floor);
  planner_hard_limit, planner_hard_limit_min: a plan call running that many times plan_budget
  (at least that many seconds) is given up, the run ending as 'planner_hung';
  progress_interval: simulated seconds between progress(dict) calls.
The artefacts (mesh.ply, metrics.json, run_log.csv, robot.json, ...) go to out_dir (created; its
parent must exist), or to a temporary folder removed afterwards. progress(dict) gets t_s,
frames_fused, coverage, distance_total_m, plan_calls; an exception it raises is raised when the
run ends. The GIL is released while the run goes on. A planner that crashes or hangs ends the
run (terminated, planner_fault) with a warning.)doc");

  m.def(
      "planners", [] { return AvailablePlanners(PlannerSearchPath()); },
      "The planner plugins explore finds by name ($VOXPLAN_PLANNER_PATH first).");
  m.def(
      "planner_search_path",
      [] {
        std::vector<std::string> out;
        for (const fs::path& p : PlannerSearchPath()) out.push_back(p.string());
        return out;
      },
      "The folders explore looks for planners in, in order: $VOXPLAN_PLANNER_PATH's, then the "
      "installed planners beside an installed module (lib/voxplan/planners), else the build's.");
}

}  // namespace voxplan::python
