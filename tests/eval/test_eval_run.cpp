// Run metrics, floor coverage and the run-log file, on hand-made tracks with exact answers.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "eval/eval_run.h"
#include "io/file_util.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

constexpr double kExact = 1e-12;  // sums of a few exact steps

RobotSample Sample(double t, double x, double y, RobotStatus status = RobotStatus::kBusy,
                   std::string mode = "") {
  RobotSample s;
  s.t_s = t;
  s.x_m = x;
  s.y_m = y;
  s.status = status;
  s.mode = std::move(mode);
  return s;
}

// r0 drives 10 m along x in 10 s; r1 drives 4 m along y in 4 s, then waits 6 s in place.
std::vector<RobotTrack> TwoRobots() {
  RobotTrack r0{"r0", {}}, r1{"r1", {}};
  for (int t = 0; t <= 10; ++t)
    r0.samples.push_back(Sample(t, t, 0.0, RobotStatus::kBusy, "explorer"));
  for (int t = 0; t <= 4; ++t) r1.samples.push_back(Sample(t, 0.0, 1.0 + t));
  for (int t = 5; t <= 10; ++t) r1.samples.push_back(Sample(t, 0.0, 5.0, RobotStatus::kIdle));
  // r1 was idle from t = 4 on: its sample at 4 already says so.
  r1.samples[4].status = RobotStatus::kIdle;
  return {r0, r1};
}

TEST(EvaluateRun, StraightTracksGiveExactDistancesBalanceAndIdleTime) {
  RunEvalParams params;
  params.scene_area_m2 = 7.0;
  auto run = EvaluateRun(TwoRobots(), params);
  ASSERT_TRUE(run.ok()) << run.status().message();
  ASSERT_EQ(run->robots.size(), 2u);
  EXPECT_NEAR(run->robots[0].distance_m, 10.0, kExact);
  EXPECT_NEAR(run->robots[1].distance_m, 4.0, kExact);
  EXPECT_NEAR(run->distance_total_m, 14.0, kExact);
  EXPECT_NEAR(run->distance_mean_m, 7.0, kExact);
  EXPECT_NEAR(run->distance_per_area, 2.0, kExact);
  EXPECT_NEAR(run->load_balance_cov, 3.0 / 7.0, kExact);  // population std 3, mean 7
  EXPECT_NEAR(run->time_s, 10.0, kExact);
  EXPECT_NEAR(run->robots[0].busy_time_s, 10.0, kExact);
  EXPECT_NEAR(run->robots[0].idle_time_s, 0.0, kExact);
  EXPECT_NEAR(run->robots[1].busy_time_s, 4.0, kExact);
  EXPECT_NEAR(run->robots[1].idle_time_s, 6.0, kExact);
  EXPECT_NEAR(run->robots[1].idle_fraction, 0.6, kExact);
  EXPECT_NEAR(run->idle_time_total_s, 6.0, kExact);
  EXPECT_NEAR(run->time_load_balance, 0.3, kExact);  // 6 s of 2 x 10 s
  EXPECT_NEAR(run->robots[0].mode_time_s.at("explorer"), 10.0, kExact);
  EXPECT_NEAR(run->robots[0].mode_distance_m.at("explorer"), 10.0, kExact);
  EXPECT_TRUE(run->robots[1].mode_time_s.empty());
  EXPECT_EQ(run->robots[1].samples, 11u);
  EXPECT_EQ(run->mode_switches, 0u);
  EXPECT_NEAR(run->mode_time_s.at("explorer"), 10.0, kExact);
}

TEST(EvaluateRun, ModeTimesDistancesAndSwitchesAddUpOverRobots) {
  std::vector<RobotTrack> tracks = TwoRobots();
  // r0: explorer 0-4 s, reconstructor 4-7 s, explorer again 7-10 s: two switches.
  for (int t = 4; t < 7; ++t) tracks[0].samples[size_t(t)].mode = "reconstructor";
  // r1: reconstructor throughout, one robot-second of it driving per sample up to 4 s.
  for (RobotSample& s : tracks[1].samples) s.mode = "reconstructor";
  auto run = EvaluateRun(tracks);
  ASSERT_TRUE(run.ok()) << run.status().message();
  EXPECT_EQ(run->robots[0].mode_switches, 2u);
  EXPECT_EQ(run->robots[1].mode_switches, 0u);
  EXPECT_EQ(run->mode_switches, 2u);
  EXPECT_NEAR(run->robots[0].mode_time_s.at("explorer"), 7.0, kExact);
  EXPECT_NEAR(run->robots[0].mode_time_s.at("reconstructor"), 3.0, kExact);
  EXPECT_NEAR(run->mode_time_s.at("reconstructor"), 3.0 + 10.0, kExact);
  EXPECT_NEAR(run->mode_distance_m.at("reconstructor"), 3.0 + 4.0, kExact);
  EXPECT_NEAR(run->mode_distance_m.at("explorer"), 7.0, kExact);
}

TEST(EvaluateRun, ARobotWhoseLogEndsEarlyWaitsForTheRest) {
  std::vector<RobotTrack> tracks = TwoRobots();
  tracks[1].samples.resize(5);  // r1's log stops at t = 4
  auto run = EvaluateRun(tracks);
  ASSERT_TRUE(run.ok()) << run.status().message();
  EXPECT_NEAR(run->robots[1].end_s, 4.0, kExact);
  EXPECT_NEAR(run->robots[1].idle_time_s, 6.0, kExact);
  EXPECT_NEAR(run->time_load_balance, 0.3, kExact);
  EXPECT_DOUBLE_EQ(run->distance_per_area, 0.0);  // no area given
}

TEST(EvaluateRun, OneRobotIsBalancedAndRefusesBadTracks) {
  auto one = EvaluateRun({TwoRobots()[0]});
  ASSERT_TRUE(one.ok());
  EXPECT_DOUBLE_EQ(one->load_balance_cov, 0.0);
  EXPECT_DOUBLE_EQ(one->time_load_balance, 0.0);

  EXPECT_FALSE(EvaluateRun({}).ok());
  std::vector<RobotTrack> twice = TwoRobots();
  twice[1].robot = "r0";
  EXPECT_FALSE(EvaluateRun(twice).ok());
  std::vector<RobotTrack> backwards = TwoRobots();
  backwards[0].samples[3].t_s = 1.0;
  auto r = EvaluateRun(backwards);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("not after"), std::string::npos);
  std::vector<RobotTrack> empty = TwoRobots();
  empty[1].samples.clear();
  EXPECT_FALSE(EvaluateRun(empty).ok());
  RunEvalParams negative;
  negative.scene_area_m2 = -1.0;
  EXPECT_FALSE(EvaluateRun(TwoRobots(), negative).ok());
}

TEST(RunTimeSeries, DistanceAndBusyRobotsOverTime) {
  const std::vector<RobotTrack> tracks = TwoRobots();
  EXPECT_NEAR(DistanceUpTo(tracks, 2.5), 5.0, kExact);  // 2.5 m each, moving straight
  EXPECT_NEAR(DistanceUpTo(tracks, 7.0), 11.0, kExact);
  EXPECT_NEAR(DistanceUpTo(tracks, 100.0), 14.0, kExact);
  EXPECT_DOUBLE_EQ(DistanceUpTo(tracks, -1.0), 0.0);
  const std::vector<RunTimePoint> series = RunTimeSeries(tracks);
  ASSERT_EQ(series.size(), 11u);  // distinct times 0..10
  EXPECT_EQ(series[3].busy_robots, 2);
  EXPECT_EQ(series[4].busy_robots, 1);
  EXPECT_NEAR(series[10].distance_total_m, 14.0, kExact);
  EXPECT_TRUE(std::isnan(series[0].coverage));

  test::TempDir dir("eval_run");
  std::vector<RunTimePoint> with_coverage(series.begin(), series.begin() + 2);
  with_coverage[1].coverage = 0.25;
  const std::string path = (dir / "series.csv").string();
  ASSERT_TRUE(WriteRunTimeSeriesCsv(with_coverage, path).ok());
  auto text = ReadFileToString(path);
  ASSERT_TRUE(text.ok());
  EXPECT_EQ(*text,
            "t,distance_total_m,busy_robots,coverage,completeness,unobserved_m3,mean_uncertainty\n"
            "0,0,2,,,,\n"
            "1,2,2,0.25,,,\n");
}

TEST(RunTimeSeries, UnobservedAreaFractionHoldsTheLastValueToTheHorizon) {
  std::vector<RunTimePoint> series(4);
  const double t[] = {0.0, 10.0, 20.0, 30.0}, u[] = {std::nan(""), 100.0, 50.0, 50.0};
  for (size_t i = 0; i < series.size(); ++i) {
    series[i].t_s = t[i];
    series[i].unobserved_m3 = u[i];
  }
  // From t = 10 (the first value) to 30: 750 + 500 over 100 x 20.
  EXPECT_DOUBLE_EQ(UnobservedAreaFraction(series, 0.0), 1250.0 / 2000.0);
  // To a horizon of 50: the last 50 m3 held for 20 s more.
  EXPECT_DOUBLE_EQ(UnobservedAreaFraction(series, 50.0), 2250.0 / 4000.0);
  // Nothing observed after the start: 1.
  for (RunTimePoint& p : series)
    p.unobserved_m3 = std::isnan(p.unobserved_m3) ? p.unobserved_m3 : 8.0;
  EXPECT_DOUBLE_EQ(UnobservedAreaFraction(series, 40.0), 1.0);
  EXPECT_TRUE(std::isnan(UnobservedAreaFraction({}, 10.0)));
  EXPECT_TRUE(std::isnan(UnobservedAreaFraction({series[1]}, 0.0)));  // no span
  series[1].unobserved_m3 = 0.0;
  EXPECT_TRUE(std::isnan(UnobservedAreaFraction(series, 40.0)));  // nothing to observe
}

TEST(RunLog, RoundTripKeepsEveryValue) {
  std::vector<RobotTrack> tracks = TwoRobots();
  tracks[0].samples[1].yaw_rad = 1.0 / 3.0;
  tracks[0].samples[1].cam_yaw_rad = -0.1;
  tracks[0].samples[1].cam_pitch_rad = 1e-7;
  tracks[1].samples[2].x_m = 0.1 + 0.2;
  tracks[1].samples[2].mode = "reconstructor";
  tracks[1].robot = "robot_1";
  test::TempDir dir("eval_run");
  const std::string path = (dir / "run.csv").string();
  ASSERT_TRUE(WriteRunLog(tracks, path).ok());
  auto read = ReadRunLog(path);
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->size(), tracks.size());
  for (size_t r = 0; r < tracks.size(); ++r) {
    EXPECT_EQ((*read)[r].robot, tracks[r].robot);
    ASSERT_EQ((*read)[r].samples.size(), tracks[r].samples.size());
    for (size_t i = 0; i < tracks[r].samples.size(); ++i) {
      const RobotSample& a = tracks[r].samples[i];
      const RobotSample& b = (*read)[r].samples[i];
      EXPECT_EQ(a.t_s, b.t_s);
      EXPECT_EQ(a.x_m, b.x_m);
      EXPECT_EQ(a.y_m, b.y_m);
      EXPECT_EQ(a.yaw_rad, b.yaw_rad);
      EXPECT_EQ(a.cam_yaw_rad, b.cam_yaw_rad);
      EXPECT_EQ(a.cam_pitch_rad, b.cam_pitch_rad);
      EXPECT_EQ(a.status, b.status);
      EXPECT_EQ(a.mode, b.mode);
    }
  }
  // Metrics read back equal.
  auto before = EvaluateRun(tracks);
  auto after = EvaluateRun(*read);
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_EQ(before->distance_total_m, after->distance_total_m);

  // Names and modes the format cannot hold are refused.
  std::vector<RobotTrack> bad = tracks;
  bad[0].robot = "r 0";
  EXPECT_FALSE(WriteRunLog(bad, path).ok());
  bad = tracks;
  bad[0].samples[0].mode = "a,b";
  EXPECT_FALSE(WriteRunLog(bad, path).ok());
}

// Writes `body` after the header and returns ReadRunLog's error message ("" when it reads).
std::string ReadError(const test::TempDir& dir, const std::string& body, bool with_header = true) {
  const std::string path = (dir / "log.csv").string();
  std::ofstream(path) << "# comment\n"
                      << (with_header ? "t,robot,x,y,yaw,cam_yaw,cam_pitch,status,mode\n" : "")
                      << body;
  auto read = ReadRunLog(path);
  return read.ok() ? "" : read.status().message();
}

TEST(RunLog, BadLinesAreRefusedWithFileAndLine) {
  test::TempDir dir("eval_run");
  const std::string log = (dir / "log.csv").string();
  EXPECT_EQ(ReadError(dir, "0,r0,0,0,0,0,0,busy,\n\n1,r0,1,0,0,0,0,idle,explorer\n"), "");
  std::string m = ReadError(dir, "0,r0,0,0,0,0,0,busy\n");
  EXPECT_NE(m.find(log + ":3:"), std::string::npos) << m;
  EXPECT_NE(m.find("got 8"), std::string::npos) << m;
  m = ReadError(dir, "0,r0,0,0,0,0,0,busy,\n0.5,r0,abc,0,0,0,0,busy,\n");
  EXPECT_NE(m.find(log + ":4:"), std::string::npos) << m;
  EXPECT_NE(m.find("'x'"), std::string::npos) << m;
  m = ReadError(dir, "0,r0,0,0,0,0,0,sleeping,\n");
  EXPECT_NE(m.find(log + ":3:"), std::string::npos) << m;
  m = ReadError(dir, "0,r0,0,0,0,0,0,busy,\n0,r1,0,0,0,0,0,busy,\n-1,r0,0,0,0,0,0,busy,\n");
  EXPECT_NE(m.find(log + ":5:"), std::string::npos) << m;
  EXPECT_NE(m.find("line 3"), std::string::npos) << m;
  m = ReadError(dir, "0,r0,inf,0,0,0,0,busy,\n");
  EXPECT_NE(m.find(log + ":3:"), std::string::npos) << m;
  m = ReadError(dir, "0,r0,0,0,0,0,0,busy,\n", false);
  EXPECT_NE(m.find(log + ":2:"), std::string::npos) << m;
  EXPECT_NE(m.find("header"), std::string::npos) << m;
  EXPECT_NE(ReadError(dir, ""), "");  // header but no samples
  EXPECT_FALSE(ReadRunLog((dir / "missing.csv").string()).ok());
}

// 4 x 2 cells of 1 m from (0, 0): row 0 free, free, obstacle, outside; row 1 all free.
FloorPlan SmallPlan() {
  FloorPlan plan;
  plan.resolution_m = 1.f;
  plan.width = 4;
  plan.height = 2;
  plan.cells = {PlanCell::kFree, PlanCell::kFree, PlanCell::kObstacle, PlanCell::kOutside,
                PlanCell::kFree, PlanCell::kFree, PlanCell::kFree,     PlanCell::kFree};
  return plan;
}

TEST(FloorCoverage, CountsKnownFreeCellsAcrossResolutions) {
  const FloorPlan plan = SmallPlan();
  EXPECT_DOUBLE_EQ(FloorArea(plan), 7.0);
  // Observed at 0.5 m from (0.5, 0): covers x in [0.5, 3.5), y in [0, 2); a plan cell is known
  // where the observed cell holding its centre is non-zero.
  ObservedRaster observed;
  observed.origin_W = {0.5, 0.0};
  observed.resolution_m = 0.5;
  observed.width = 6;
  observed.height = 4;
  observed.cells.assign(24, kUnknownCell);
  const auto set = [&](double x, double y, uint8_t v) {
    observed.cells[size_t((y - 0.0) / 0.5) * 6 + size_t((x - 0.5) / 0.5)] = v;
  };
  set(0.5, 0.5, 1);  // plan cell (0, 0): known free
  set(1.5, 0.5, 2);  // (1, 0): known occupied still counts as known
  set(2.5, 0.5, 1);  // (2, 0): an obstacle cell, not counted
  set(1.5, 1.5, 1);  // (1, 1)
  // Plan cells (0, 1), (2, 1) and (3, 1) unknown: 3 of 6 free cells known.
  auto coverage = FloorCoverage(plan, observed);
  ASSERT_TRUE(coverage.ok()) << coverage.status().message();
  EXPECT_DOUBLE_EQ(*coverage, 3.0 / 6.0);

  // All known, but the centre of plan cell (3, 1), x = 3.5, lies past the raster.
  observed.cells.assign(24, 1);
  EXPECT_DOUBLE_EQ(*FloorCoverage(plan, observed), 5.0 / 6.0);

  observed.cells.pop_back();
  EXPECT_FALSE(FloorCoverage(plan, observed).ok());
  FloorPlan no_free = plan;
  std::fill(no_free.cells.begin(), no_free.cells.end(), PlanCell::kObstacle);
  observed.cells.push_back(1);
  EXPECT_FALSE(FloorCoverage(no_free, observed).ok());
}

}  // namespace
}  // namespace voxplan
