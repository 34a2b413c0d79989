// One exploration experiment through the library (explore/explore_run.h): a short greedy run on
// a small apartment writes every artefact (the world it ran in among them, with a fingerprint
// the evaluation commands check), and metrics.json agrees with the report and the logs;
// a bad request is refused before the output folder exists, a failing run is not a refusal.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "explore/explore_run.h"
#include "explore/robot_config.h"
#include "explore/run_outputs.h"
#include "sim/apartment.h"
#include "sim/scene_loader.h"
#include "sim/world_io.h"
#include "tests/explore/explore_test_runs.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

std::unique_ptr<LoadedPlanner> Greedy() { return test::GreedyPlanner(); }

// 60 simulated seconds, coarse, two robots: a few seconds of wall time.
ExploreRunParams ShortRun(const fs::path& out) {
  ExploreRunParams p = test::CoarseRun("apartment:size=S,seed=1", 2, 60.0, out);
  p.explore.progress_interval_s = 10.0;
  return p;
}

std::vector<std::string> Lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(ExploreRun, PlannerPictureDrawsTheLastDrawingsOfEachLayer) {
  // --planner-picture: greedy sends its view points and path as debug layers; planner.png is
  // topdown.png with them drawn in, so the two differ and the run's drawings are kept per layer.
  test::TempDir dir("explore_picture");
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  ExploreRunParams params = ShortRun(dir / "out");
  params.explore.max_time_s = 30.0;
  params.explore.keep_planner_drawings = true;
  bool refused = true;
  Result<ExploreRunReport> report = RunExploreExperiment(params, *planner, {}, &refused);
  ASSERT_TRUE(report.ok()) << report.status().message();
  ASSERT_FALSE(report->loop.planner_drawings.empty());
  for (const auto& [layer, drawings] : report->loop.planner_drawings)
    EXPECT_FALSE(drawings.empty());
  const fs::path picture = dir / "out" / "planner.png", plain = dir / "out" / "topdown.png";
  ASSERT_TRUE(fs::is_regular_file(picture));
  std::ifstream a(picture, std::ios::binary), b(plain, std::ios::binary);
  const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}),
      bytes_b((std::istreambuf_iterator<char>(b)), {});
  EXPECT_NE(bytes_a, bytes_b);
}

TEST(ExploreRun, ShortRunWritesEveryArtefactAndItsMetricsAgree) {
  test::TempDir dir("explore_run");
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  std::vector<std::string> started;
  size_t progress_calls = 0;
  ExploreRunObserver observer;
  observer.started = [&](const std::string& world_name) { started.push_back(world_name); };
  observer.progress = [&](const ExploreProgress&) { ++progress_calls; };
  bool refused = true;
  const ExploreRunParams params = ShortRun(dir / "out");
  Result<ExploreRunReport> report = RunExploreExperiment(params, *planner, observer, &refused);
  ASSERT_TRUE(report.ok()) << report.status().message();
  EXPECT_FALSE(refused);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0], report->world_name);
  EXPECT_GE(progress_calls, 1u);

  for (const char* f : {"mesh.ply", "metrics.json", "timeseries.csv", "run_log.csv", "topdown.png",
                        "plan_log.txt", "plan_calls.csv", "unobserved.svg"})
    EXPECT_TRUE(fs::is_regular_file(dir / "out" / f)) << f;
  EXPECT_GT(fs::file_size(dir / "out" / "mesh.ply"), 1000u);
  EXPECT_GT(fs::file_size(dir / "out" / "topdown.png"), 1000u);
  EXPECT_FALSE(fs::exists(dir / "out" / "planner.png"));  // only with keep_planner_drawings
  // The world as run, read back as a scene: the fingerprint metrics.json records, which
  // CheckRunWorld accepts for it and refuses for another seed's apartment.
  for (const std::string& f : WorldFilePaths((dir / "out").string(), RunWorldFiles()))
    EXPECT_TRUE(fs::is_regular_file(f)) << f;
  Result<World> written = LoadWorld((dir / "out" / "world.ply").string());
  ASSERT_TRUE(written.ok()) << written.status().message();
  EXPECT_EQ(report->world_fingerprint, WorldFingerprintHex(*written));
  EXPECT_TRUE(CheckRunWorld((dir / "out" / "run_log.csv").string(), *written).ok());
  ApartmentParams other;
  other.size = ApartmentSize::kS;
  other.seed = 2;
  Result<World> other_world = GenerateApartment(other);
  ASSERT_TRUE(other_world.ok());
  const Status refused_world = CheckRunWorld((dir / "out" / "mesh.ply").string(), *other_world);
  EXPECT_EQ(refused_world.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused_world.message().find("not the world this run explored"), std::string::npos)
      << refused_world.message();
  EXPECT_TRUE(CheckRunWorld((dir / "no_run" / "mesh.ply").string(), *other_world).ok());

  // The report: a reconstructed surface, judged against the tour-observable ground truth.
  const ExploreResult& loop = report->loop;
  EXPECT_EQ(report->planner_name, "greedy");
  EXPECT_GT(report->mesh.num_triangles(), 0u);
  EXPECT_TRUE(report->observable_reference);
  EXPECT_GT(report->tour_frames, 0u);
  EXPECT_GT(report->quality.completeness, 0.0);
  EXPECT_LE(report->quality.completeness, 1.0);
  ASSERT_EQ(report->metrics.robots.size(), 2u);
  EXPECT_GT(report->metrics.distance_total_m, 0.0);
  EXPECT_GT(report->scene_area_m2, 20.0);
  EXPECT_FALSE(loop.plan_calls.empty());
  EXPECT_LE(loop.time_s, 60.0 + 1.0);  // the last robot step may overrun

  // metrics.json holds the report's metrics object, and says what the report says; the summary
  // adds the wall-time breakdown.
  std::ifstream metrics_file(dir / "out" / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(metrics_file);
  EXPECT_EQ(m, nlohmann::json::parse(RunMetricsJson(params, *report)));
  nlohmann::json summary = nlohmann::json::parse(RunSummaryJson(params, *report));
  EXPECT_EQ(summary["tour_frames"], report->tour_frames);
  for (const char* key :
       {"setup_ms", "tour_frames", "render_ms", "detect_ms", "noise_ms", "fuse_ms", "floor_ms",
        "plan_ms_total", "series_ms", "loop_ms", "eval_ms"})
    EXPECT_EQ(summary.erase(key), 1u) << key;
  EXPECT_EQ(summary, m);
  EXPECT_EQ(m["scene"], "apartment:size=S,seed=1");
  EXPECT_EQ(m["world_fingerprint"], report->world_fingerprint);
  EXPECT_EQ(m["planner"], "greedy");
  EXPECT_EQ(m["robots"], 2);
  EXPECT_EQ(m["seed"], 5);
  EXPECT_EQ(m["plan_calls"], loop.plan_calls.size());
  EXPECT_EQ(m["frames_fused"], loop.frames_fused);
  EXPECT_EQ(m["blocks_dropped_memory"], 0);
  // Greedy drives in the explorer mode only: all of the time and distance is there.
  EXPECT_EQ(m["mode_switches"], 0);
  ASSERT_TRUE(m["mode_time_s"].contains("explorer")) << m["mode_time_s"];
  EXPECT_NEAR(m["mode_distance_m"]["explorer"].get<double>(), report->metrics.distance_total_m,
              5e-3);
  EXPECT_EQ(m["terminated"], loop.terminated);
  EXPECT_EQ(m["distance_per_robot_m"].size(), 2u);
  EXPECT_NEAR(m["completeness"].get<double>(), report->quality.completeness, 5e-5);
  EXPECT_NEAR(m["distance_total_m"].get<double>(), report->metrics.distance_total_m, 5e-4);
  EXPECT_NE(m["completeness_reference"].get<std::string>().find("sim tour"), std::string::npos);
  // Below the robot's height (Xu 2017's reference): a subset of the observable surface, so a
  // share of it; a short run sees the walls' lower parts better than the rest.
  EXPECT_GT(m["completeness_below_robot"].get<double>(), 0.0);
  EXPECT_LE(m["completeness_below_robot"].get<double>(), 1.0);
  EXPECT_NE(m["completeness_below_robot"].get<double>(), m["completeness"].get<double>());
  // Path smoothness: two robots that turned and drove.
  EXPECT_GT(m["base_ang_accel_radps2"].get<double>(), 0.0);
  EXPECT_GT(m["base_turning_per_m"].get<double>(), 0.0);
  EXPECT_GT(m["camera_ang_accel_radps2"].get<double>(), 0.0);
  EXPECT_EQ(m["blocked_paths"], loop.blocked_paths);
  // Per object (Guo 2022): the apartment's furniture, a looser threshold covers more.
  ASSERT_TRUE(report->objects.has_value());
  EXPECT_GT(m["objects_evaluated"].get<int>(), 5);
  EXPECT_LE(m["objects_reconstructed"].get<int>(), m["objects_evaluated"].get<int>());
  EXPECT_GT(m["o_comp_2cm"].get<double>(), 0.0);
  EXPECT_LT(m["o_comp_2cm"].get<double>(), m["o_comp_5cm"].get<double>());
  EXPECT_GT(m["o_rms_m"].get<double>(), 0.0);
  EXPECT_LT(m["o_rms_m"].get<double>(), 0.05);  // a 5 cm map's mesh, noisy depth
  EXPECT_GT(m["objects_detected"].get<int>(), 0);
  const std::vector<std::string> objects = Lines(dir / "out" / "objects.csv");
  ASSERT_EQ(objects.size(), m["objects_evaluated"].get<size_t>() + 1);
  EXPECT_EQ(objects[0].rfind("id,class,model,", 0), 0u);
  for (const ObjectEvalResult& o : report->objects->objects)
    EXPECT_NE(o.class_name, "wall");  // structure is not an object

  // The robot as run, and a timeline of the explorer mode (greedy's only) per robot.
  Result<RobotParams> robot = ReadRobotConfig((dir / "out" / "robot.json").string(), {});
  ASSERT_TRUE(robot.ok()) << robot.status().message();
  EXPECT_EQ(RobotConfigJson(*robot), RobotConfigJson(params.explore.robot));
  const std::vector<std::string> svg = Lines(dir / "out" / "timeline.svg");
  ASSERT_FALSE(svg.empty());
  EXPECT_EQ(svg[0].rfind("<svg", 0), 0u);

  // The tables: a header and one row per plan call; every robot's poses in the run log.
  EXPECT_EQ(Lines(dir / "out" / "plan_calls.csv").size(), loop.plan_calls.size() + 1);
  size_t samples = 0;
  for (const RobotTrack& t : loop.tracks) samples += t.samples.size();
  EXPECT_GT(Lines(dir / "out" / "run_log.csv").size(), samples / 2);
  EXPECT_GE(Lines(dir / "out" / "timeseries.csv").size(), 2u);
}

// Past --max-memory the map takes no new blocks: the run goes on, warns and counts them.
TEST(ExploreRun, AMapAtItsMemoryBudgetWarnsAndCountsWhatItDropped) {
  test::TempDir dir("explore_run");
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  ExploreRunParams params = ShortRun(dir / "out");
  params.explore.max_time_s = 20.0;
  params.explore.max_memory_bytes = 1u << 20;
  Result<ExploreRunReport> report = RunExploreExperiment(params, *planner, {}, nullptr);
  ASSERT_TRUE(report.ok()) << report.status().message();
  EXPECT_GT(report->loop.blocks_dropped, 0u);
  ASSERT_FALSE(report->warnings.empty());
  bool warned = false;
  for (const std::string& w : report->warnings) {
    warned = warned || (w.find("memory budget") != std::string::npos &&
                        w.find(std::to_string(report->loop.blocks_dropped)) != std::string::npos);
  }
  EXPECT_TRUE(warned);
  std::ifstream metrics_file(dir / "out" / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(metrics_file);
  EXPECT_EQ(m["blocks_dropped_memory"], report->loop.blocks_dropped);
}

// --recon-voxel-size: the mesh (and its metrics) come from a finer volume fused with the same
// frames; the planning map, the planner's view and the run itself stay as they were.
TEST(ExploreRun, AFinerReconstructionVolumeMakesTheMeshAndLeavesTheRunAlone) {
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  test::TempDir dir("explore_run");
  ExploreRunParams coarse = ShortRun(dir / "coarse");
  coarse.explore.max_time_s = 20.0;
  coarse.explore.noise = false;  // so both meshes see the same depth
  ExploreRunParams fine = coarse;
  fine.out_dir = (dir / "fine").string();
  fine.explore.recon_voxel_size_m = 0.05f;  // half the planning map's 0.1 m
  Result<ExploreRunReport> a = RunExploreExperiment(coarse, *planner);
  std::unique_ptr<LoadedPlanner> planner2 = Greedy();
  Result<ExploreRunReport> b = RunExploreExperiment(fine, *planner2);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->loop.recon_volume, nullptr);
  ASSERT_NE(b->loop.recon_volume, nullptr);
  EXPECT_FLOAT_EQ(b->loop.recon_volume->params().voxel_size_m, 0.05f);
  // The run is the same: same frames, same tracks, same planning map.
  EXPECT_EQ(a->loop.frames_fused, b->loop.frames_fused);
  EXPECT_EQ(a->loop.volume->num_blocks(), b->loop.volume->num_blocks());
  ASSERT_EQ(a->loop.tracks.size(), b->loop.tracks.size());
  EXPECT_EQ(a->loop.tracks[0].samples.size(), b->loop.tracks[0].samples.size());
  // The mesh is the finer one's: more triangles, closer to the true surface.
  EXPECT_GT(b->mesh.num_triangles(), 2 * a->mesh.num_triangles());
  EXPECT_LT(b->quality.accuracy_rms_m, a->quality.accuracy_rms_m);
  std::ifstream metrics_file(dir / "fine" / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(metrics_file);
  EXPECT_FLOAT_EQ(m["mesh_voxel_size_m"].get<float>(), 0.05f);
  std::ifstream coarse_metrics(dir / "coarse" / "metrics.json");
  EXPECT_FALSE(nlohmann::json::parse(coarse_metrics).contains("mesh_voxel_size_m"));
  ExploreParams bad = fine.explore;
  bad.recon_voxel_size_m = -1.f;
  EXPECT_FALSE(bad.Validate().ok());
}

TEST(ExploreRun, RefusesABadRequestBeforeTheOutputFolderExists) {
  test::TempDir dir("explore_run_refused");
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_NE(planner, nullptr);
  ExploreRunParams spec = ShortRun(dir / "spec");
  spec.scene = "apartment:size=X";
  ExploreRunParams missing = ShortRun(dir / "missing");
  missing.scene = (dir / "no_such_scene.ply").string();
  ExploreRunParams blocked = ShortRun(dir / "blocked");
  blocked.robots = 1;
  blocked.starts = {{-50.f, -50.f}};  // outside the apartment
  for (const ExploreRunParams& p : {spec, missing, blocked}) {
    bool refused = false;
    Result<ExploreRunReport> report = RunExploreExperiment(p, *planner, {}, &refused);
    ASSERT_FALSE(report.ok()) << p.out_dir;
    EXPECT_TRUE(refused) << report.status().message();
    EXPECT_FALSE(fs::exists(p.out_dir)) << p.out_dir;
  }

  // A scene where the robots do not fit is the run's failure, not a bad request.
  ExploreRunParams crowded = ShortRun(dir / "crowded");
  crowded.robots = 40;
  bool refused = true;
  Result<ExploreRunReport> report = RunExploreExperiment(crowded, *planner, {}, &refused);
  ASSERT_FALSE(report.ok());
  EXPECT_FALSE(refused);
  EXPECT_NE(report.status().message().find("apartment:size=S,seed=1"), std::string::npos)
      << report.status().message();
}

TEST(ExploreRun, ParsesApartmentSpecsAndStarts) {
  Result<ApartmentParams> a = ParseApartmentSpec("apartment:size=L,seed=7");
  ASSERT_TRUE(a.ok()) << a.status().message();
  EXPECT_EQ(a->size, ApartmentSize::kL);
  EXPECT_EQ(a->seed, 7u);
  Result<ApartmentParams> plain = ParseApartmentSpec("apartment");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->size, ApartmentSize::kM);
  EXPECT_EQ(ParseApartmentSpec("scene.ply").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(ParseApartmentSpec("apartments").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(ParseApartmentSpec("apartment:seed=-1x").status().code(), StatusCode::kInvalidArgument);

  Result<std::vector<Eigen::Vector2f>> s = ParseStarts("1,2;-3.5,4");
  ASSERT_TRUE(s.ok()) << s.status().message();
  ASSERT_EQ(s->size(), 2u);
  EXPECT_EQ((*s)[1], Eigen::Vector2f(-3.5f, 4.f));
  EXPECT_FALSE(ParseStarts("1,2;x").ok());
  EXPECT_FALSE(ParseStarts("1,2,3").ok());
}

}  // namespace
}  // namespace voxplan
