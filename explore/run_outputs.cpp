// The artefacts of one exploration experiment (explore/run_outputs.h): the metrics object, the
// logs and tables, and the top-down picture. Moved out of `voxplan explore` as they were.
#include "explore/run_outputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "core/summary.h"
#include "eval/path_smoothness.h"
#include "explore/robot_config.h"
#include "io/file_util.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "viewer_offscreen/svg_plot.h"
#include "viewer_offscreen/top_down.h"

namespace voxplan {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string InFolder(const std::string& out_dir, const char* name) {
  return (fs::path(out_dir) / name).string();
}

Status WriteLines(const std::vector<std::string>& lines, const std::string& path) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return WriteFileAtomically(path, text);
}

// The call a planner crashed or hung in; elapsed_s is wall time.
json FaultObject(const PlannerFault& f) {
  json j;
  j["call"] = f.call;
  j["call_index"] = f.call_index;
  j["event"] = PlanEventName(f.event);
  j["signal"] = f.kind == PlannerFault::Kind::kCrashed ? json(f.signal_name) : json(nullptr);
  j["elapsed_s"] = RoundTo(f.elapsed_s, 3);
  j["hard_limit_s"] = RoundTo(f.limit_s, 3);
  return j;
}

json MetricsObject(const ExploreRunParams& params, const ExploreRunReport& report) {
  const ExploreResult& r = report.loop;
  const MeshEvalResult& quality = report.quality;
  const RunMetrics& metrics = report.metrics;
  std::vector<double> plan_ms;
  for (const PlanCallRecord& c : r.plan_calls) plan_ms.push_back(c.elapsed_ms);
  const TimingSummary plan_summary = Summarize(plan_ms);

  json m;
  m["scene"] = params.scene;
  // Only when the load was asked to move the floor, so other runs keep their bytes: the scene
  // file's z of the run's floor (a file point is a run point plus this in z; unrounded).
  if (params.scene_load.detect_floor || params.scene_load.floor_z_m != 0.f)
    m["scene_floor_z_m"] = double(report.scene_floor_z_m);
  m["world_fingerprint"] = report.world_fingerprint;
  m["planner"] = report.planner_name;
  m["robots"] = params.robots;
  m["seed"] = params.explore.seed;
  m["completeness"] = RoundTo(quality.completeness, 4);
  m["completeness_all"] = RoundTo(quality.completeness_all, 4);
  m["completeness_below_robot"] = RoundTo(report.completeness_below_robot, 4);
  m["completeness_reference"] =
      report.observable_reference
          ? "ground-truth surface observable from a sim tour of the reachable floor (" +
                Num(params.explore.robot.explorer.max_range_m) +
                " m range), samples within 5 cm of the final mesh"
          : "whole ground-truth surface, samples within 5 cm of the final mesh";
  m["accuracy_rms_m"] = RoundTo(quality.accuracy_rms_m, 4);
  m["accuracy_mean_m"] = RoundTo(quality.accuracy_mean_m, 4);
  // Only with the option, so runs without it keep their bytes: what the mesh was fused at.
  if (params.explore.recon_voxel_size_m > 0.f)
    m["mesh_voxel_size_m"] = RoundTo(params.explore.recon_voxel_size_m, 4);
  // Only with tracked poses, so runs at the true poses keep their bytes.
  if (params.explore.poses == ExploreParams::Poses::kTracked) {
    const TrackedPoseSummary t = SummarizeTrackedPoses(r.frames);
    m["poses"] = "tracked";
    m["frames_lost"] = r.frames_lost;
    m["frames_odometry"] = r.frames_odometry;
    m["registration_rms_m"] = RoundTo(t.residual_mean_m, 5);
    m["registration_rms_p90_m"] = RoundTo(t.residual_p90_m, 5);
    m["ate_rms_m"] = RoundTo(t.ate_rms_m, 5);
  }
  // Per object (Guo 2022 eq. 6 and 7), null without objects; rows in objects.csv.
  const std::optional<ObjectsEvalResult>& objects = report.objects;
  m["o_comp_2cm"] = objects ? json(RoundTo(objects->o_comp, 4)) : json();
  m["o_comp_5cm"] = objects ? json(RoundTo(objects->o_comp_extra.at(0), 4)) : json();
  m["o_rms_m"] = objects ? json(RoundTo(objects->o_rms_m, 5)) : json();
  m["objects_evaluated"] = objects ? objects->objects.size() : 0;
  m["objects_reconstructed"] = objects ? objects->objects_reconstructed : 0;
  json per_robot = json::array();
  for (const RobotRunMetrics& rm : metrics.robots) per_robot.push_back(RoundTo(rm.distance_m, 3));
  m["distance_per_robot_m"] = per_robot;
  m["distance_total_m"] = RoundTo(metrics.distance_total_m, 3);
  m["distance_per_area"] = RoundTo(metrics.distance_per_area, 4);
  m["scene_area_m2"] = RoundTo(report.scene_area_m2, 2);
  m["load_balance_cov"] = RoundTo(metrics.load_balance_cov, 4);
  m["time_s"] = RoundTo(r.time_s, 2);
  m["idle_time_s"] = RoundTo(metrics.idle_time_total_s, 2);
  m["time_load_balance"] = RoundTo(metrics.time_load_balance, 4);
  // Per scanning mode over all robots (Guo 2022's mode split), and how often a robot switched.
  json mode_time = json::object(), mode_distance = json::object();
  for (const auto& [mode, t] : metrics.mode_time_s) mode_time[mode] = RoundTo(t, 2);
  for (const auto& [mode, d] : metrics.mode_distance_m) mode_distance[mode] = RoundTo(d, 3);
  m["mode_time_s"] = mode_time;
  m["mode_distance_m"] = mode_distance;
  m["mode_switches"] = metrics.mode_switches;
  // Path smoothness of the team (Xu 2017 X§7), weighted by each robot's time and travel.
  PathSmoothness base, camera;
  for (const RobotTrack& track : r.tracks) {
    base = CombineSmoothness(base, BaseSmoothness(track));
    camera = CombineSmoothness(camera, CameraSmoothness(track));
  }
  m["base_ang_accel_radps2"] = RoundTo(base.mean_abs_angular_accel_radps2, 4);
  m["base_turning_per_m"] = RoundTo(base.turning_per_m, 4);
  m["base_sharp_turns_per_10m"] = RoundTo(base.sharp_turns_per_10m, 3);
  m["camera_ang_accel_radps2"] = RoundTo(camera.mean_abs_angular_accel_radps2, 4);
  m["camera_turning_per_m"] = RoundTo(camera.turning_per_m, 4);
  m["coverage"] = r.series.empty() ? 0.0 : RoundTo(r.series.back().coverage, 4);
  // The unobserved-volume curve (timeseries.csv): where it starts (after the start sweeps) and
  // ends, its area as a share of the start held to --max-time, the final surface uncertainty.
  const auto number = [](double v, int decimals) {
    return std::isfinite(v) ? json(RoundTo(v, decimals)) : json();
  };
  const RunTimePoint none;  // NaN throughout
  const RunTimePoint& first = r.series.empty() ? none : r.series.front();
  const RunTimePoint& last = r.series.empty() ? none : r.series.back();
  m["unobserved_m3_start"] = number(first.unobserved_m3, 3);
  m["unobserved_m3_final"] = number(last.unobserved_m3, 3);
  m["unobserved_area_fraction"] =
      number(UnobservedAreaFraction(r.series, params.explore.max_time_s), 4);
  m["mean_uncertainty_final"] = number(last.mean_uncertainty, 4);
  m["plan_calls"] = r.plan_calls.size();
  m["plan_ms_median"] = RoundTo(plan_summary.median, 3);  // wall time: varies run to run
  m["plan_ms_p90"] = RoundTo(plan_summary.p90, 3);
  m["plans_over_budget"] = r.over_budget_calls;
  m["rejected_tasks"] = r.rejected_tasks;
  m["failed_tasks"] = r.failed_tasks;
  m["failed_plan_calls"] = r.failed_plans;
  m["blocked_paths"] = r.blocked_paths;
  m["camera_position_clamped_workspace"] = r.camera_position_clamped_workspace;
  m["camera_position_clamped_speed"] = r.camera_position_clamped_speed;
  m["frames_fused"] = r.frames_fused;
  m["objects_detected"] = r.objects_detected;
  m["blocks_dropped_memory"] = r.blocks_dropped;
  m["terminated"] = r.terminated;
  m["done_reason"] = r.done_reason;
  if (r.planner_fault) m["planner_fault"] = FaultObject(*r.planner_fault);
  return m;
}

// A CSV field: quoted (quotes doubled) when it holds a comma, quote or line break, as a scene
// file's model names may.
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// objects.csv: one row per evaluated object, in the world's instance order.
std::vector<std::string> ObjectRows(const std::optional<ObjectsEvalResult>& objects) {
  std::vector<std::string> rows = {
      "id,class,model,area_m2,gt_samples,completeness_2cm,completeness_5cm,recon_samples,"
      "accuracy_mean_m,accuracy_rms_m"};
  if (!objects) return rows;
  for (const ObjectEvalResult& o : objects->objects) {
    std::ostringstream line;
    line << o.id << "," << CsvField(o.class_name) << "," << CsvField(o.model) << ","
         << RoundTo(o.ground_truth_area_m2, 4) << "," << o.ground_truth_samples << ","
         << RoundTo(o.completeness, 4) << "," << RoundTo(o.completeness_extra.at(0), 4) << ","
         << o.reconstruction_samples << "," << RoundTo(o.accuracy_mean_m, 5) << ","
         << RoundTo(o.accuracy_rms_m, 5);
    rows.push_back(line.str());
  }
  return rows;
}

// plan_calls.csv: one row per call; elapsed_ms and over_budget are wall time.
std::vector<std::string> PlanCallRows(const std::vector<PlanCallRecord>& plan_calls) {
  std::vector<std::string> calls = {
      "call,t,event,event_robot,tasks,rejections,done,elapsed_ms,"
      "over_budget,diagnostics"};
  for (const PlanCallRecord& c : plan_calls) {
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
  return calls;
}

// timeline.svg: per robot, when it was idle and in which mode it worked (Guo 2022 Fig. 9).
Status WriteTimeline(const ExploreResult& r, const std::string& path) {
  TimelineParams tp;
  tp.title = "Robot modes and idle time";
  tp.categories = {{"explorer", PackRgb(78, 121, 167)},
                   {"reconstructor", PackRgb(225, 87, 89)},
                   {"idle", PackRgb(200, 200, 200)}};
  std::vector<TimelineRow> rows;
  bool any = false;
  for (const RobotTrack& track : r.tracks) {
    TimelineRow row{track.robot, {}};
    for (size_t i = 0; i + 1 < track.samples.size(); ++i) {
      const RobotSample& s = track.samples[i];
      const int category = s.status == RobotStatus::kIdle ? 2 : s.mode == "reconstructor" ? 1 : 0;
      const double t1 = track.samples[i + 1].t_s;
      if (!row.spans.empty() && row.spans.back().category == category &&
          row.spans.back().t1_s == s.t_s) {
        row.spans.back().t1_s = t1;  // one span for a run of samples
      } else {
        row.spans.push_back({s.t_s, t1, category});
      }
      any = true;
    }
    rows.push_back(std::move(row));
  }
  if (!any) return Status();  // nothing happened: no picture
  Result<std::string> svg = SvgTimeline(rows, tp);
  if (!svg.ok()) return svg.status().Naming(path);
  return WriteFileAtomically(path, *svg);
}

// unobserved.svg: the unobserved-volume curve over time, from zero to its start.
Status WriteUnobservedPlot(const ExploreResult& r, const std::string& path) {
  PlotSeries curve{"unobserved interior", {}, {}};
  for (const RunTimePoint& p : r.series) {
    curve.x.push_back(p.t_s);
    curve.y.push_back(p.unobserved_m3);
  }
  if (std::none_of(curve.y.begin(), curve.y.end(), [](double v) { return std::isfinite(v); }))
    return Status();  // nothing measured: no picture
  PlotParams pp;
  pp.title = "Unobserved interior volume (floor to robot height)";
  pp.x_label = "time (s)";
  pp.y_label = "unobserved (m³)";
  pp.y_min = 0.0;
  pp.y_max = r.series.front().unobserved_m3;  // a flat zero gets the data's range
  Result<std::string> svg = SvgLinePlot({curve}, pp);
  if (!svg.ok()) return svg.status().Naming(path);
  return WriteFileAtomically(path, *svg);
}

// The planner's last debug drawings as an overlay: lines (layers in name order), then points over
// them.
TopDownOverlay PlannerOverlay(const ExploreResult& r) {
  TopDownOverlay overlay;
  for (const DebugDrawing::Kind kind : {DebugDrawing::Kind::kPolyline, DebugDrawing::Kind::kPoints})
    for (const auto& [layer, drawings] : r.planner_drawings)
      for (const DebugDrawing& d : drawings) {
        if (d.kind != kind) continue;  // labels: no text in the picture
        TopDownOverlay::Stroke stroke;
        stroke.polyline = d.kind == DebugDrawing::Kind::kPolyline;
        stroke.color = PackRgb(uint8_t(d.rgba >> 24), uint8_t(d.rgba >> 16), uint8_t(d.rgba >> 8));
        for (const Eigen::Vector3f& p : d.points) stroke.points_W.push_back(p.head<2>());
        overlay.strokes.push_back(std::move(stroke));
      }
  return overlay;
}

// Top-down picture: the final floor map, paths, start and end marks, task views (and, given one,
// an overlay under the paths).
Status WriteTopDown(const ExploreResult& r, const std::string& path,
                    const TopDownOverlay& overlay = {}) {
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
  if (g.width > 0) {
    Result<ColorImage> picture = RenderTopDown(raster, paths, {}, overlay);
    if (!picture.ok()) return picture.status();
    if (Status s = WriteColorPng(path, *picture); !s.ok()) return s.Naming(path);
  }
  return Status();
}

}  // namespace

Status WriteRunMesh(const Mesh& mesh, const std::string& out_dir) {
  const std::string mesh_path = InFolder(out_dir, "mesh.ply");
  if (Status s = WriteMesh(mesh, mesh_path); !s.ok()) return s.Naming(mesh_path);
  return Status();
}

std::string RunMetricsJson(const ExploreRunParams& params, const ExploreRunReport& report) {
  return MetricsObject(params, report).dump();
}

std::string RunSummaryJson(const ExploreRunParams& params, const ExploreRunReport& report) {
  json j = MetricsObject(params, report);
  const ExploreTimings& t = report.loop.timings;
  j["setup_ms"] = RoundTo(report.setup_ms, 1);
  j["tour_frames"] = report.tour_frames;
  j["render_ms"] = RoundTo(t.render_ms, 1);
  j["detect_ms"] = RoundTo(t.detect_ms, 1);
  j["noise_ms"] = RoundTo(t.noise_ms, 1);
  j["fuse_ms"] = RoundTo(t.fuse_ms, 1);
  j["floor_ms"] = RoundTo(t.floor_ms, 1);
  j["plan_ms_total"] = RoundTo(t.plan_ms, 1);
  j["series_ms"] = RoundTo(t.series_ms, 1);
  j["loop_ms"] = RoundTo(t.total_ms, 1);
  j["eval_ms"] = RoundTo(report.eval_ms, 1);
  return j.dump();
}

Status WriteRunOutputs(const ExploreRunParams& params, const ExploreRunReport& report) {
  const ExploreResult& r = report.loop;
  std::string path = InFolder(params.out_dir, "metrics.json");
  VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(path, MetricsObject(params, report).dump(2) + "\n"));

  path = InFolder(params.out_dir, "run_log.csv");
  if (Status s = WriteRunLog(r.tracks, path); !s.ok()) return s.Naming(path);
  std::vector<RunTimePoint> series = r.series;
  for (RunTimePoint& p : series) {
    // Distance from the log, so the series and the metrics agree.
    p.distance_total_m = DistanceUpTo(r.tracks, p.t_s);
  }
  path = InFolder(params.out_dir, "timeseries.csv");
  if (Status s = WriteRunTimeSeriesCsv(series, path); !s.ok()) return s.Naming(path);
  path = InFolder(params.out_dir, "plan_log.txt");
  if (Status s = WriteLines(r.plan_log, path); !s.ok()) return s.Naming(path);
  path = InFolder(params.out_dir, "plan_calls.csv");
  if (Status s = WriteLines(PlanCallRows(r.plan_calls), path); !s.ok()) return s.Naming(path);
  path = InFolder(params.out_dir, "robot.json");
  VOXPLAN_RETURN_IF_ERROR(WriteFileAtomically(path, RobotConfigJson(params.explore.robot)));
  path = InFolder(params.out_dir, "objects.csv");
  if (Status s = WriteLines(ObjectRows(report.objects), path); !s.ok()) return s.Naming(path);
  VOXPLAN_RETURN_IF_ERROR(WriteTimeline(r, InFolder(params.out_dir, "timeline.svg")));
  VOXPLAN_RETURN_IF_ERROR(WriteUnobservedPlot(r, InFolder(params.out_dir, "unobserved.svg")));
  VOXPLAN_RETURN_IF_ERROR(WriteTopDown(r, InFolder(params.out_dir, "topdown.png")));
  if (!params.explore.keep_planner_drawings) return Status();
  return WriteTopDown(r, InFolder(params.out_dir, "planner.png"), PlannerOverlay(r));
}

std::vector<std::string> RunOutputFiles(const std::string& out_dir) {
  std::vector<std::string> paths;
  for (const char* name : {"mesh.ply", "metrics.json", "run_log.csv", "timeseries.csv",
                           "plan_log.txt", "plan_calls.csv", "objects.csv", "robot.json",
                           "timeline.svg", "unobserved.svg", "topdown.png", "planner.png"})
    paths.push_back(InFolder(out_dir, name));
  for (const std::string& p : WorldFilePaths(out_dir, RunWorldFiles())) paths.push_back(p);
  return paths;
}

WorldWriteOptions RunWorldFiles() {
  WorldWriteOptions o;
  o.basename = "world";
  o.write_glb = false;  // world.ply holds the same mesh
  return o;
}

Status CheckRunWorld(const std::string& run_file, const World& world) {
  const fs::path metrics = fs::path(run_file).parent_path() / "metrics.json";
  std::error_code ec;
  if (!fs::is_regular_file(metrics, ec)) return Status::Ok();
  constexpr uintmax_t kMaxMetricsBytes = 16u << 20;  // a run's metrics.json is a few kB
  const uintmax_t bytes = fs::file_size(metrics, ec);
  if (ec || bytes > kMaxMetricsBytes)
    return InvalidArgument(metrics.string() + ": not a run's metrics.json (over 16 MiB)");
  Result<std::string> text = ReadFileToString(metrics.string());
  if (!text.ok()) return text.status();
  const json m = json::parse(*text, nullptr, /*allow_exceptions=*/false);
  if (!m.is_object()) return InvalidArgument("not a JSON object: " + metrics.string());
  const auto it = m.find("world_fingerprint");
  if (it == m.end() || !it->is_string())
    return NotFound(metrics.string() +
                    " records no world_fingerprint (a run from before it was"
                    " recorded): cannot check the world is the run's");
  const std::string ours = WorldFingerprintHex(world);
  if (it->get<std::string>() == ours) return Status::Ok();
  return InvalidArgument("the scene is not the world this run explored: world fingerprint " + ours +
                         ", " + metrics.string() + " has " + it->get<std::string>() +
                         " (score against " +
                         (fs::path(run_file).parent_path() / "world.ply").string() +
                         ", the world it wrote, or give the same --scene, seed and --floor-z)");
}

}  // namespace voxplan
