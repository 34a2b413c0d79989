// The closed exploration loop (explore/explore.h) on a small generated apartment with the greedy
// planner plugin: it terminates on its own with most of the floor known and the surface
// reconstructed, it is deterministic, and robots are placed on free floor or refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "eval/eval_mesh.h"
#include "explore/explore.h"
#include "explore/explore_world.h"
#include "fusion/mesh_extract.h"
#include "planning/integrate_planning.h"
#include "sim/apartment.h"
#include "sim/floor_plan.h"
#include "sim/raycaster.h"

namespace voxplan {
namespace {

// Coarse and small so a whole run takes a few seconds.
ExploreParams FastParams() {
  ExploreParams p;
  p.voxel_size_m = 0.1f;
  p.image_width = 160;
  p.image_height = 120;
  p.noise = false;
  p.max_time_s = 900.0;
  p.seed = 3;
  return p;
}

struct Scene {
  World world;
  FloorPlan plan;
};

const Scene& SmallApartment() {
  static const Scene scene = [] {
    ApartmentParams ap;
    ap.size = ApartmentSize::kS;
    ap.seed = 2;
    Scene s;
    s.world = GenerateApartment(ap).value();
    s.plan = RasterizeFloorPlan(s.world).value();
    return s;
  }();
  return scene;
}

std::unique_ptr<LoadedPlanner> Greedy() {
  Result<std::unique_ptr<LoadedPlanner>> planner =
      LoadPlanner(VOXPLAN_EXPLORE_TEST_PLANNER,
                  {.config_json = "{}", .seed = 3, .search_path = {}, .limits = {}});
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

Result<ExploreResult> RunGreedy(const ExploreParams& params, int robots) {
  const Scene& s = SmallApartment();
  Result<std::vector<Eigen::Vector2f>> starts =
      ChooseStarts(s.plan, s.world.rooms, robots, params.robot.radius_m);
  if (!starts.ok()) return starts.status();
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  if (!planner) return Status(StatusCode::kInternal, "no planner");
  return RunExplore(s.world, s.plan, *starts, *planner, params, {});
}

TEST(Explore, SmallApartmentTerminatesWithTheFloorKnownAndTheSurfaceReconstructed) {
  // Bounds with room below what the run reaches: the greedy planner stops when no frontier
  // view is left, which leaves corners behind furniture; completeness is scored within one
  // voxel (the map's resolution) on the whole ground-truth mesh, outer wall faces included.
  constexpr double kMinCoverage = 0.9;      // reached: 1.00 (greedy's default, "best_view")
  constexpr double kMinCompleteness = 0.5;  // reached: 0.61
  const ExploreParams params = FastParams();
  Result<ExploreResult> run = RunGreedy(params, 2);
  ASSERT_TRUE(run.ok()) << run.status().message();
  EXPECT_EQ(run->terminated, "done") << "stopped at t=" << run->time_s;
  EXPECT_LT(run->time_s, params.max_time_s);
  ASSERT_FALSE(run->series.empty());
  EXPECT_GE(run->series.back().coverage, kMinCoverage);
  ASSERT_EQ(run->tracks.size(), 2u);
  for (const RobotTrack& t : run->tracks) EXPECT_GE(t.samples.size(), 2u);

  MeshEvalParams ep;
  ep.threshold_m = params.voxel_size_m;
  ep.samples_per_m2 = 200.f;
  Result<MeshEvalResult> q =
      EvaluateMesh(ExtractMesh(*run->volume), SmallApartment().world.mesh, ep);
  ASSERT_TRUE(q.ok()) << q.status().message();
  EXPECT_GE(q->completeness, kMinCompleteness);

  Result<RunMetrics> metrics = EvaluateRun(run->tracks);
  ASSERT_TRUE(metrics.ok()) << metrics.status().message();
  EXPECT_GT(metrics->distance_total_m, 1.0);  // the robots did drive
}

TEST(Explore, ViewsTiltTheCameraTowardsUnknownFloorAndDriveLevel) {
  // A 58° x 45° camera (an Xtion) 1.2 m up sees no floor nearer than 2.9 m when level: views of
  // unknown floor tilt it down. OMT hands over a camera trajectory (level); on the move the
  // camera follows it, not the last view's tilt.
  ExploreParams params = FastParams();
  params.robot.explorer.horizontal_fov_deg = 58.f;
  params.robot.explorer.max_range_m = 3.f;
  params.max_time_s = 120.0;
  const Scene& s = SmallApartment();
  Result<std::vector<Eigen::Vector2f>> starts =
      ChooseStarts(s.plan, s.world.rooms, 2, params.robot.radius_m);
  ASSERT_TRUE(starts.ok()) << starts.status().message();
  Result<std::unique_ptr<LoadedPlanner>> omt = LoadPlanner(
      VOXPLAN_OMT_TEST_PLANNER, {.config_json = "{}", .seed = 3, .search_path = {}, .limits = {}});
  ASSERT_TRUE(omt.ok()) << omt.status().message();
  Result<ExploreResult> run = RunExplore(s.world, s.plan, *starts, **omt, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  int tilted = 0, moving = 0;
  for (const RobotTrack& t : run->tracks) {
    for (size_t k = 1; k < t.samples.size(); ++k) {
      const RobotSample &a = t.samples[k - 1], &b = t.samples[k];
      tilted += b.cam_pitch_rad < -1e-3;
      if (a.x_m == b.x_m && a.y_m == b.y_m) continue;
      ++moving;
      EXPECT_EQ(b.cam_pitch_rad, 0.0) << t.robot << " at t=" << b.t_s;
    }
  }
  EXPECT_GT(tilted, 0);
  EXPECT_GT(moving, 0);
}

TEST(Explore, DepthBeyondTheRangeClearsTheFloorInFrontOfIt) {
  // A 3 m camera in rooms whose walls stand farther: after the start sweep, the floor the far
  // returns crossed is known free only when they clear.
  constexpr double kMinGain = 1.5;  // coverage with clearing / without; reached: 0.283 / 0.136
  ExploreParams params = FastParams();
  params.robot.explorer.horizontal_fov_deg = 58.f;
  params.robot.explorer.max_range_m = 3.f;
  params.max_time_s = 20.0;
  double coverage[2] = {0.0, 0.0};
  for (int clear = 0; clear < 2; ++clear) {
    params.clear_beyond_range = clear == 1;
    Result<ExploreResult> run = RunGreedy(params, 1);
    ASSERT_TRUE(run.ok()) << run.status().message();
    ASSERT_FALSE(run->series.empty());
    coverage[clear] = run->series.back().coverage;
  }
  EXPECT_GE(coverage[1], kMinGain * coverage[0]) << coverage[0] << " -> " << coverage[1];
}

TEST(Explore, SameSeedGivesTheSameRun) {
  ExploreParams params = FastParams();
  params.max_time_s = 40.0;  // the start sweep and some driving
  params.noise = true;       // the noise is seeded per robot and frame too
  Result<ExploreResult> a = RunGreedy(params, 2), b = RunGreedy(params, 2);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->tracks.size(), b->tracks.size());
  for (size_t i = 0; i < a->tracks.size(); ++i) {
    ASSERT_EQ(a->tracks[i].samples.size(), b->tracks[i].samples.size());
    for (size_t k = 0; k < a->tracks[i].samples.size(); ++k) {
      const RobotSample &sa = a->tracks[i].samples[k], &sb = b->tracks[i].samples[k];
      EXPECT_EQ(sa.t_s, sb.t_s);
      EXPECT_EQ(sa.x_m, sb.x_m);
      EXPECT_EQ(sa.y_m, sb.y_m);
      EXPECT_EQ(sa.cam_yaw_rad, sb.cam_yaw_rad);
    }
  }
  EXPECT_EQ(a->frames_fused, b->frames_fused);
  EXPECT_EQ(a->plan_calls.size(), b->plan_calls.size());
  EXPECT_EQ(a->volume->num_blocks(), b->volume->num_blocks());
  ASSERT_EQ(a->series.size(), b->series.size());
  for (size_t i = 0; i < a->series.size(); ++i)
    EXPECT_EQ(a->series[i].coverage, b->series[i].coverage);
}

// Time-based capture (ModeParams::capture_hz): the faster the camera runs, the more frames the
// same 40 s fuse; dwells give several frames at one pose. Rates past the bound are refused.
TEST(Explore, TimeBasedCaptureFusesMoreFramesTheFasterItRuns) {
  ExploreParams params = FastParams();
  params.max_time_s = 40.0;
  std::vector<size_t> frames;
  for (float hz : {1.f, 4.f, 20.f}) {
    params.robot.explorer.capture_hz = params.robot.reconstructor.capture_hz = hz;
    Result<ExploreResult> run = RunGreedy(params, 1);
    ASSERT_TRUE(run.ok()) << run.status().message();
    frames.push_back(run->frames_fused);
  }
  EXPECT_LT(frames[0], frames[1]);
  EXPECT_LT(frames[1], frames[2]);
  for (float bad : {-1.f, kMaxCaptureHz + 1.f, std::nanf("")}) {
    params.robot.reconstructor.capture_hz = bad;
    EXPECT_FALSE(params.Validate().ok()) << bad;
  }
}

TEST(Explore, ColourOffLeavesTheRunAndTheGeometryUnchanged) {
  // fuse_color only saves work: the robots, the frames and the fused surface stay the same.
  ExploreParams params = FastParams();
  params.max_time_s = 40.0;
  params.noise = true;
  ExploreParams grey = params;
  grey.fuse_color = false;
  Result<ExploreResult> a = RunGreedy(params, 2), b = RunGreedy(grey, 2);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->tracks.size(), b->tracks.size());
  for (size_t i = 0; i < a->tracks.size(); ++i) {
    ASSERT_EQ(a->tracks[i].samples.size(), b->tracks[i].samples.size());
    for (size_t k = 0; k < a->tracks[i].samples.size(); ++k) {
      EXPECT_EQ(a->tracks[i].samples[k].x_m, b->tracks[i].samples[k].x_m);
      EXPECT_EQ(a->tracks[i].samples[k].y_m, b->tracks[i].samples[k].y_m);
    }
  }
  EXPECT_EQ(a->frames_fused, b->frames_fused);
  const Mesh ma = ExtractMesh(*a->volume), mb = ExtractMesh(*b->volume);
  ASSERT_GT(ma.num_triangles(), 0u);
  EXPECT_EQ(ma.positions, mb.positions);
  EXPECT_EQ(ma.triangles, mb.triangles);
  EXPECT_NE(ma.colors, mb.colors);  // the rendered colours did reach the coloured run
}

TEST(Explore, StartsAreFreeSideBySideAndBadOnesAreRefused) {
  const Scene& s = SmallApartment();
  const float radius = 0.2f, spacing = 0.6f;
  Result<std::vector<Eigen::Vector2f>> starts = ChooseStarts(s.plan, s.world.rooms, 3, radius);
  ASSERT_TRUE(starts.ok()) << starts.status().message();
  ASSERT_EQ(starts->size(), 3u);
  EXPECT_TRUE(CheckStarts(s.plan, *starts, radius).ok());
  constexpr float kTol = 1e-4f;
  EXPECT_NEAR(((*starts)[1] - (*starts)[0]).norm(), spacing, kTol);
  EXPECT_NEAR(((*starts)[2] - (*starts)[1]).norm(), spacing, kTol);
  // Deterministic.
  EXPECT_EQ(*starts, ChooseStarts(s.plan, s.world.rooms, 3, radius).value());

  // A start outside the building, and one on a wall (an obstacle cell of the true plan).
  Eigen::Vector2f wall = Eigen::Vector2f::Constant(-100.f);
  for (int y = 0; y < s.plan.height && wall.x() < -99.f; ++y)
    for (int x = 0; x < s.plan.width; ++x)
      if (s.plan.at(x, y) == PlanCell::kObstacle) {
        wall = s.plan.CellCenter(x, y);
        break;
      }
  for (const Eigen::Vector2f& bad : {Eigen::Vector2f(-100.f, -100.f), wall}) {
    const Status st = CheckStarts(s.plan, {(*starts)[0], bad}, radius);
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(st.message().find("robot 1"), std::string::npos) << st.message();
  }
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  ASSERT_TRUE(planner);
  Result<ExploreResult> run = RunExplore(s.world, s.plan, {wall}, *planner, FastParams(), {});
  EXPECT_FALSE(run.ok());
}

// `extra`: more of goto's config keys, e.g. "\"mode\": 1, \"height\": 0.6".
std::unique_ptr<LoadedPlanner> Goto(const Eigen::Vector2f& goal_W, const std::string& extra = "") {
  const std::string config = "{\"x\": " + std::to_string(goal_W.x()) +
                             ", \"y\": " + std::to_string(goal_W.y()) +
                             (extra.empty() ? "" : ", " + extra) + "}";
  Result<std::unique_ptr<LoadedPlanner>> planner =
      LoadPlanner(VOXPLAN_GOTO_TEST_PLANNER,
                  {.config_json = config, .seed = 1, .search_path = {}, .limits = {}});
  EXPECT_TRUE(planner.ok()) << planner.status().message();
  return planner.ok() ? std::move(planner).value() : nullptr;
}

TEST(Explore, BumperPutsAnObstacleTheCameraNeverSeesOnTheMap) {
  // The robot is sent 1.6 m across its room; the true plan has a 0.4 m bar across the way that the
  // scene (what the camera renders) lacks. Each refused drive puts what it ran into on the floor
  // map, so the host's next route bends around the bar and the robot arrives; without that it
  // is routed into the bar again and again until the time limit.
  constexpr float kLegM = 1.6f, kBarHalfM = 0.2f, kDetourM = 0.5f;
  const Scene& s = SmallApartment();
  ExploreParams params = FastParams();
  params.max_time_s = 240.0;
  const float radius = params.robot.radius_m;
  // The first leg (cells in row-major order, then directions) whose corridor is free wide
  // enough for a detour round either end of the bar.
  Eigen::Vector2f start = Eigen::Vector2f::Zero(), goal = start, dir = start;
  for (int i = 0; i < s.plan.width * s.plan.height && dir.isZero(); ++i) {
    const Eigen::Vector2f c = s.plan.CellCenter(i % s.plan.width, i / s.plan.width);
    for (const Eigen::Vector2f& d : {Eigen::Vector2f(1.f, 0.f), Eigen::Vector2f(0.f, 1.f)}) {
      if (SegmentFree(s.plan, c, c + kLegM * d, kBarHalfM + kDetourM)) {
        start = c;
        goal = c + kLegM * d;
        dir = d;
        break;
      }
    }
  }
  ASSERT_FALSE(dir.isZero()) << "no room for the leg";
  FloorPlan plan = s.plan;
  const Eigen::Vector2f middle = 0.5f * (start + goal), side(-dir.y(), dir.x());
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x) {
      const Eigen::Vector2f c = plan.CellCenter(x, y) - middle;
      if (std::abs(c.dot(dir)) <= 0.5f * plan.resolution_m && std::abs(c.dot(side)) <= kBarHalfM)
        plan.cells[size_t(y) * size_t(plan.width) + size_t(x)] = PlanCell::kObstacle;
    }
  ASSERT_FALSE(SegmentFree(plan, start, goal, radius));
  std::unique_ptr<LoadedPlanner> planner = Goto(goal);
  ASSERT_TRUE(planner);
  Result<ExploreResult> run = RunExplore(s.world, plan, {start}, *planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  EXPECT_EQ(run->terminated, "done") << "stopped at t=" << run->time_s;
  EXPECT_GE(run->failed_tasks, 1u);  // it did run into the bar
  const RobotSample& end = run->tracks[0].samples.back();
  EXPECT_LT((Eigen::Vector2f(float(end.x_m), float(end.y_m)) - goal).norm(), 1e-3f);
  // The bar is on the floor map where the robot touched it (the camera never sees any of it).
  size_t marked = 0;
  for (int y = 0; y < plan.height; ++y)
    for (int x = 0; x < plan.width; ++x)
      if (plan.at(x, y) != s.plan.at(x, y))
        marked += run->floor->AtPoint(plan.CellCenter(x, y)) == FloorCell::kObstacle;
  EXPECT_GE(marked, 1u);
  size_t bumps = 0;
  for (const std::string& line : run->plan_log) bumps += line.find("bumped into") != line.npos;
  EXPECT_GE(bumps, 1u);
  EXPECT_LE(run->failed_tasks, bumps);  // each failure here is a bump that marked something new
}

// A 1.2 m leg at 45° (the robot starts heading along +x) with room on both sides.
bool DiagonalLeg(const FloorPlan& plan, float clearance_m, Eigen::Vector2f* start,
                 Eigen::Vector2f* goal) {
  const Eigen::Vector2f dir = Eigen::Vector2f(1.f, 1.f).normalized();
  for (int i = 0; i < plan.width * plan.height; ++i) {
    const Eigen::Vector2f c = plan.CellCenter(i % plan.width, i / plan.width);
    if (SegmentFree(plan, c, c + 1.2f * dir, clearance_m)) {
      *start = c;
      *goal = c + 1.2f * dir;
      return true;
    }
  }
  return false;
}

// Intervals of the track where the base both moved and turned.
int TurningMoves(const RobotTrack& track) {
  int n = 0;
  for (size_t i = 0; i + 1 < track.samples.size(); ++i) {
    const RobotSample& a = track.samples[i];
    const RobotSample& b = track.samples[i + 1];
    n += std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) > 0.02 && std::abs(b.yaw_rad - a.yaw_rad) > 0.05;
  }
  return n;
}

TEST(Explore, ContinuousPathTurnsWhileDrivingAtItsSpeedAndEndsWithoutAStop) {
  // vp.motion: the same leg driven stop-and-go (a task, routed by the host) and as a continuous
  // path. Continuous, the 45° turn happens while driving; it arrives heading along the path, and
  // each piece takes its length at the path's speed (the mode's, or the one given).
  const Scene& s = SmallApartment();
  ExploreParams params = FastParams();
  params.max_time_s = 120.0;
  Eigen::Vector2f start, goal;
  ASSERT_TRUE(DiagonalLeg(s.plan, params.robot.radius_m + 0.3f, &start, &goal));
  auto drive = [&](const std::string& extra) {
    std::unique_ptr<LoadedPlanner> planner = Goto(goal, extra);
    EXPECT_TRUE(planner);
    Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, params, {});
    EXPECT_TRUE(run.ok()) << run.status().message();
    return std::move(run).value();
  };
  const ExploreResult stop_and_go = drive("");
  const ExploreResult continuous = drive("\"continuous\": 1");
  const ExploreResult slow = drive("\"continuous\": 1, \"speed\": 0.1");
  for (const ExploreResult* run : {&stop_and_go, &continuous, &slow}) {
    EXPECT_EQ(run->terminated, "done");
    const RobotSample& end = run->tracks[0].samples.back();
    EXPECT_LT((Eigen::Vector2f(float(end.x_m), float(end.y_m)) - goal).norm(), 1e-3f);
    EXPECT_NEAR(end.yaw_rad, M_PI / 4, 1e-3);
    EXPECT_EQ(run->blocked_paths, 0u);
  }
  EXPECT_EQ(TurningMoves(stop_and_go.tracks[0]), 0);  // turns in place, then drives
  EXPECT_GE(TurningMoves(continuous.tracks[0]), 1);
  // After the first piece (which also brings the base and camera round from the start sweep,
  // the slowest of those moves setting its time) every piece takes its length at its speed.
  auto off_speed = [](const RobotTrack& track, double speed_mps, int* pieces) {
    int off = 0;
    bool first = true;
    *pieces = 0;
    for (size_t i = 0; i + 1 < track.samples.size(); ++i) {
      const RobotSample& a = track.samples[i];
      const RobotSample& b = track.samples[i + 1];
      const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
      if (length == 0.0) continue;
      if (first) {
        first = false;
        continue;
      }
      ++*pieces;
      off += std::abs((b.t_s - a.t_s) - length / speed_mps) > 1e-3;
    }
    return off;
  };
  int pieces = 0;
  EXPECT_EQ(off_speed(continuous.tracks[0], params.robot.explorer.max_speed_mps, &pieces), 0);
  EXPECT_GE(pieces, 4);  // 1.2 m in 0.2 m pieces, the first aside
  EXPECT_EQ(off_speed(slow.tracks[0], 0.1, &pieces), 0);
  EXPECT_GE(pieces, 4);
}

// A 2 m leg along +x (the robot starts heading that way) with room on both sides.
bool StraightLeg(const FloorPlan& plan, float clearance_m, Eigen::Vector2f* start,
                 Eigen::Vector2f* goal) {
  for (int i = 0; i < plan.width * plan.height; ++i) {
    const Eigen::Vector2f c = plan.CellCenter(i % plan.width, i / plan.width);
    if (SegmentFree(plan, c, c + Eigen::Vector2f(2.f, 0.f), clearance_m)) {
      *start = c;
      *goal = c + Eigen::Vector2f(2.f, 0.f);
      return true;
    }
  }
  return false;
}

// The camera's offset from the base (forward, left, height) at the robot's last frame.
Eigen::Vector3f LastFrameOffset(const ExploreResult& run) {
  const ExploreFrame& f = run.frames[0].back();
  const std::vector<RobotSample>& samples = run.tracks[0].samples;
  // Each frame is taken right after the sample of its time.
  const auto at = std::find_if(samples.rbegin(), samples.rend(),
                               [&](const RobotSample& s) { return s.t_s == f.t_s; });
  EXPECT_NE(at, samples.rend());
  if (at == samples.rend()) return Eigen::Vector3f::Constant(NAN);
  const Eigen::Vector3f p = f.T_W_C.translation();
  const float dx = p.x() - float(at->x_m), dy = p.y() - float(at->y_m);
  const float c = std::cos(float(at->yaw_rad)), sn = std::sin(float(at->yaw_rad));
  return {c * dx + sn * dy, -sn * dx + c * dy, p.z()};
}

TEST(Explore, AnArmCameraFollowsTheTrajectorysPositionsAlongAContinuousPath) {
  // goto's continuous path with a camera trajectory that holds the camera 0.8 m up at (0.5, 0.2)
  // from the base. On an arm the camera gets there from its rest (0.3 m ahead at head height,
  // 0.49 m away) at the arm's 0.25 m/s: held back by its speed for the first pieces (the first,
  // 1 s long while the camera turns round from the start sweep, then 0.1 m per 0.4 s piece),
  // then on the offset to the end, the delay not putting it ahead (positions keyed by the
  // distance driven). Outside the workspace (2 m up) it is clamped to the arm's 1.5 m. Without
  // positions (NaN) and on a head the positions are ignored.
  const Scene& s = SmallApartment();
  ExploreParams params = FastParams();
  params.max_time_s = 120.0;
  params.robot.explorer.mount = MountKind::kArm;  // a path without tasks drives as the explorer
  params.robot.explorer.capture_hz = 10.f;        // a frame after every piece
  Eigen::Vector2f start, goal;
  ASSERT_TRUE(StraightLeg(s.plan, params.robot.radius_m + 0.3f, &start, &goal));
  auto drive = [&](const ExploreParams& p, const std::string& camera) {
    std::unique_ptr<LoadedPlanner> planner =
        Goto(goal, "\"continuous\": 1, \"camera_position\": 1" + camera);
    EXPECT_TRUE(planner);
    Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, p, {});
    EXPECT_TRUE(run.ok()) << run.status().message();
    EXPECT_EQ(run->terminated, "done");
    EXPECT_EQ(run->rejected_tasks, 0u);
    return std::move(run).value();
  };
  auto logged = [](const ExploreResult& run, const std::string& what) {
    int n = 0;
    for (const std::string& line : run.plan_log) n += line.find(what) != std::string::npos;
    return n;
  };
  constexpr float kAt_m = 1e-3f;
  const std::string offset = ", \"offset_x\": 0.5, \"offset_y\": 0.2";
  const ExploreResult held = drive(params, ", \"height\": 0.8" + offset);
  EXPECT_TRUE(LastFrameOffset(held).isApprox(Eigen::Vector3f(0.5f, 0.2f, 0.8f), kAt_m))
      << LastFrameOffset(held).transpose();
  EXPECT_EQ(held.camera_position_clamped_workspace, 0u);
  EXPECT_GE(held.camera_position_clamped_speed, 3u);  // 0.26 m, then 0.1 m a piece, of 0.49
  EXPECT_LE(held.camera_position_clamped_speed, 5u);
  EXPECT_EQ(logged(held, "held back by the arm's speed"), 1);  // the first only

  const ExploreResult high = drive(params, ", \"height\": 2.0" + offset);
  EXPECT_TRUE(LastFrameOffset(high).isApprox(Eigen::Vector3f(0.5f, 0.2f, 1.5f), kAt_m))
      << LastFrameOffset(high).transpose();
  EXPECT_GE(high.camera_position_clamped_workspace, 9u);  // every piece: 2 m in 0.2 m pieces
  EXPECT_EQ(logged(high, "moved into the arm's workspace (camera height 2 m"), 1);

  const ExploreResult none = drive(params, offset);  // no height: NaN positions
  EXPECT_TRUE(LastFrameOffset(none).isApprox(
      Eigen::Vector3f(params.robot.explorer.arm.reach_min_m, 0.f, params.robot.camera_height_m),
      kAt_m))
      << LastFrameOffset(none).transpose();
  EXPECT_EQ(none.camera_position_clamped_workspace + none.camera_position_clamped_speed, 0u);

  ExploreParams head = params;
  head.robot.explorer.mount = MountKind::kHead;
  const ExploreResult on_head = drive(head, ", \"height\": 0.8" + offset);
  EXPECT_TRUE(LastFrameOffset(on_head).isApprox(
      Eigen::Vector3f(0.f, 0.f, params.robot.camera_height_m), kAt_m))
      << LastFrameOffset(on_head).transpose();
  EXPECT_EQ(on_head.camera_position_clamped_workspace + on_head.camera_position_clamped_speed, 0u);
}

TEST(Explore, TheUnobservedVolumeOnlyFallsAndTheSurfaceUncertaintyIsMeasured) {
  // Every series row measures the scene's interior (floor to the floor map's band top, over the
  // true plan's floor) the planning map has not observed: positive after the start sweep, below
  // the interior's volume, never rising (fused weights never fall), lower at the end.
  ExploreParams params = FastParams();
  params.max_time_s = 60.0;
  Result<ExploreResult> run = RunGreedy(params, 1);
  ASSERT_TRUE(run.ok()) << run.status().message();
  const std::vector<RunTimePoint>& series = run->series;
  ASSERT_GE(series.size(), 5u);
  const double interior_m3 = FloorArea(SmallApartment().plan) * params.floor.band_max_m;
  EXPECT_GT(series.front().unobserved_m3, 0.0);
  EXPECT_LT(series.front().unobserved_m3, interior_m3);
  for (size_t i = 1; i < series.size(); ++i) {
    EXPECT_LE(series[i].unobserved_m3, series[i - 1].unobserved_m3) << "row " << i;
    EXPECT_GT(series[i].mean_uncertainty, 0.0);
    EXPECT_LE(series[i].mean_uncertainty, 1.0);
  }
  EXPECT_LT(series.back().unobserved_m3, 0.8 * series.front().unobserved_m3);
  const double area = UnobservedAreaFraction(series, params.max_time_s);
  EXPECT_GT(area, series.back().unobserved_m3 / series.front().unobserved_m3);
  EXPECT_LT(area, 1.0);
}

TEST(Explore, RequestedCallsComeAtTheFirstStepAfterTheirTime) {
  // vp.schedule: goto asks to be called 1.3 s after each call; the loop steps by step_s, so each
  // wakeup comes in [1.3, 1.3 + step_s) after the call before it. A request past 600 s ahead is
  // refused with a log line.
  const Scene& s = SmallApartment();
  ExploreParams params = FastParams();
  params.max_time_s = 30.0;
  Eigen::Vector2f start, goal;
  ASSERT_TRUE(DiagonalLeg(s.plan, params.robot.radius_m + 0.3f, &start, &goal));
  // A slow drive keeps the robot busy (goto is done once it stands at the goal).
  std::unique_ptr<LoadedPlanner> planner =
      Goto(goal, "\"wakeup\": 1.3, \"speed\": 0.02, \"continuous\": 1");
  ASSERT_TRUE(planner);
  Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  int wakeups = 0;
  const std::vector<PlanCallRecord>& calls = run->plan_calls;
  for (size_t k = 1; k < calls.size(); ++k) {
    const double gap = calls[k].t_s - calls[k - 1].t_s;
    // Every call asks for the next 1.3 s on: no call waits longer than that and a step.
    EXPECT_LT(gap, 1.3 + params.step_s + 1e-9) << "call " << k;
    if (calls[k].event != PlanEvent::kWakeup) continue;
    ++wakeups;
    EXPECT_GE(gap, 1.3 - 1e-9) << "call " << k;
  }
  EXPECT_GE(wakeups, 5);

  std::unique_ptr<LoadedPlanner> far = Goto(goal, "\"wakeup\": 700");
  ASSERT_TRUE(far);
  params.max_time_s = 5.0;
  Result<ExploreResult> refused = RunExplore(s.world, s.plan, {start}, *far, params, {});
  ASSERT_TRUE(refused.ok()) << refused.status().message();
  int refusals = 0;
  for (const std::string& line : refused->plan_log)
    refusals += line.find("request_call refused") != std::string::npos;
  EXPECT_GE(refusals, 1);
  for (const PlanCallRecord& c : refused->plan_calls) EXPECT_NE(c.event, PlanEvent::kWakeup);
}

// The loop's own map and image size for tracked poses (FastParams' 10 cm and 160 x 120 are too
// coarse to track), with sensor noise.
ExploreParams TrackedLoopParams(double max_time_s) {
  ExploreParams params = FastParams();
  params.voxel_size_m = 0.05f;
  params.image_width = 320;
  params.image_height = 240;
  params.max_time_s = max_time_s;
  params.noise = true;
  return params;
}

// The greedy planner's run of one robot in the small apartment.
ExploreResult RunGreedy(const ExploreParams& params) {
  const Scene& s = SmallApartment();
  const std::vector<Eigen::Vector2f> starts =
      ChooseStarts(s.plan, s.world.rooms, 1, params.robot.radius_m).value();
  std::unique_ptr<LoadedPlanner> planner = Greedy();
  EXPECT_TRUE(planner);
  Result<ExploreResult> r = RunExplore(s.world, s.plan, starts, *planner, params, {});
  EXPECT_TRUE(r.ok()) << r.status().message();
  return r.ok() ? std::move(r).value() : ExploreResult{};
}

TEST(Explore, TrackedPosesFuseAtTheEstimateAndCountLostFrames) {
  // --poses tracked: the start sweep is fused at the truth, every later frame at the tracker's
  // estimate (close to the truth, not equal) or not at all (lost, counted); at the truth every
  // frame is fused where it was taken.
  ExploreParams params = TrackedLoopParams(60.0);
  auto run = [&](ExploreParams::Poses poses) {
    params.poses = poses;
    return RunGreedy(params);
  };
  const ExploreResult truth = run(ExploreParams::Poses::kTruth);
  for (const ExploreFrame& f : truth.frames[0]) EXPECT_TRUE(f.T_W_C_fused.isApprox(f.T_W_C, 0.f));
  EXPECT_EQ(truth.frames_lost, 0u);

  const ExploreResult tracked = run(ExploreParams::Poses::kTracked);
  size_t anchored = 0, estimated = 0, odometry = 0;
  for (const ExploreFrame& f : tracked.frames[0]) {
    const float error_m = (f.T_W_C_fused.translation() - f.T_W_C.translation()).norm();
    if (f.odometry) {  // no model in view: the noisy odometry's pose
      EXPECT_LT(error_m, 0.25f);
      ++odometry;
    } else if (f.residual_rms_m == 0.f) {
      EXPECT_EQ(error_m, 0.f);  // the sweep
      ++anchored;
    } else {
      EXPECT_LT(error_m, 0.25f);  // odometry at 2 % and ICP against a 5 cm map
      EXPECT_LT(f.residual_rms_m, params.tracking.max_residual_rms_m + 1e-6f);
      ++estimated;
    }
  }
  EXPECT_GE(anchored, 12u);  // a full turn of the sweep at least
  EXPECT_GE(estimated, 10u);
  EXPECT_LT(tracked.frames_lost, estimated);  // most frames track
  EXPECT_EQ(odometry, tracked.frames_odometry);
  EXPECT_EQ(truth.frames_odometry, 0u);
  const TrackedPoseSummary summary = SummarizeTrackedPoses(tracked.frames);
  EXPECT_EQ(summary.frames, tracked.frames_fused);
  EXPECT_GT(summary.ate_rms_m, 0.0);
  EXPECT_LT(summary.ate_rms_m, 0.15);
  EXPECT_GT(summary.residual_mean_m, 0.0);
  EXPECT_LE(summary.residual_mean_m, summary.residual_p90_m + 1e-12);
}

// A start sweep looking down only, with the Xtion's 58° / 3 m camera, leaves the walls out of the
// map: a frame that sees no model at all is fused at the odometry prior (its error is the
// odometry's, no residual); with the option off no frame is.
TEST(Explore, TrackedFramesWithoutAModelInViewAreFusedAtTheOdometry) {
  ExploreParams params = TrackedLoopParams(40.0);
  params.poses = ExploreParams::Poses::kTracked;
  params.sweep_pitches_deg = {-55.f};
  params.sweep_step_deg = 30.f;
  params.robot.explorer.horizontal_fov_deg = 58.f;
  params.robot.explorer.max_range_m = 3.f;
  auto run = [&](bool odometry_without_model) {
    params.odometry_without_model = odometry_without_model;
    return RunGreedy(params);
  };
  const ExploreResult on = run(true), off = run(false);
  RecordProperty("frames_odometry", std::to_string(on.frames_odometry));
  RecordProperty("frames_fused_on", std::to_string(on.frames_fused));
  RecordProperty("frames_fused_off", std::to_string(off.frames_fused));
  EXPECT_EQ(off.frames_odometry, 0u);
  EXPECT_GT(on.frames_odometry, 0u);
  size_t odometry = 0;
  for (const ExploreFrame& f : on.frames[0]) {
    if (!f.odometry) continue;
    ++odometry;
    EXPECT_EQ(f.residual_rms_m, 0.f);
    EXPECT_LT((f.T_W_C_fused.translation() - f.T_W_C.translation()).norm(), 0.25f);
  }
  EXPECT_EQ(odometry, on.frames_odometry);
}

TEST(Explore, PlannersSeeTheExplorerCamera) {
  const Scene& s = SmallApartment();
  ExploreParams params = FastParams();
  params.max_time_s = 20.0;
  params.robot.explorer.horizontal_fov_deg = 58.f;
  params.robot.explorer.max_range_m = 3.f;
  const Eigen::Vector2f start =
      ChooseStarts(s.plan, s.world.rooms, 1, params.robot.radius_m).value()[0];
  std::unique_ptr<LoadedPlanner> planner = Goto(start);
  ASSERT_TRUE(planner);
  Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  ASSERT_FALSE(run->plan_calls.empty());
  std::map<std::string, double> seen(run->plan_calls[0].diagnostics.begin(),
                                     run->plan_calls[0].diagnostics.end());
  EXPECT_NEAR(seen["explorer_fov_rad"], 58.0 * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(seen["explorer_max_range_m"], 3.0, 1e-6);
}

// The reconstructor on an arm (Guo 2022), switched into at a cost.
ExploreParams ArmExplore(float switch_s) {
  ExploreParams params = FastParams();
  params.max_time_s = 120.0;
  params.robot.reconstructor.mount = MountKind::kArm;
  params.robot.reconstructor.switch_s = switch_s;
  return params;
}

// A goal 0.6 m from the start along +x or -x whose footprint the true plan leaves free.
Eigen::Vector2f NearGoal(const Scene& s, const Eigen::Vector2f& start, float radius_m) {
  for (float dx : {0.6f, -0.6f}) {
    const Eigen::Vector2f goal = start + Eigen::Vector2f(dx, 0.f);
    if (SegmentFree(s.plan, start, goal, radius_m + 0.1f)) return goal;
  }
  return start;
}

TEST(Explore, TheArmCameraTakesTheTasksHeightOffsetAndAimAndTheSwitchTakesItsTime) {
  const Scene& s = SmallApartment();
  const ExploreParams params = ArmExplore(2.f);
  const Eigen::Vector2f start =
      ChooseStarts(s.plan, s.world.rooms, 1, params.robot.radius_m).value()[0];
  const Eigen::Vector2f goal = NearGoal(s, start, params.robot.radius_m);
  ASSERT_NE(goal, start);
  const Eigen::Vector3f look(goal.x() + 2.f * (goal.x() - start.x()), goal.y() + 0.5f, 0.3f);
  const std::string camera =
      "\"mode\": 1, \"height\": 0.6, \"offset_x\": 0.5, \"offset_y\": 0.2, "
      "\"look_x\": " +
      std::to_string(look.x()) + ", \"look_y\": " + std::to_string(look.y()) +
      ", \"look_z\": " + std::to_string(look.z());
  std::unique_ptr<LoadedPlanner> planner = Goto(goal, camera);
  ASSERT_TRUE(planner);
  Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  ASSERT_EQ(run->terminated, "done");
  ASSERT_EQ(run->task_views[0].size(), 1u);
  // The view's frame: the camera 0.6 m up, at (0.5, 0.2) in the base frame of the task's pose,
  // its optical axis on the look-at point.
  const PlannerTask& view = run->task_views[0][0];
  const float c = std::cos(view.theta_rad), sn = std::sin(view.theta_rad);
  const Eigen::Vector3f expected(goal.x() + 0.5f * c - 0.2f * sn, goal.y() + 0.5f * sn + 0.2f * c,
                                 0.6f);
  constexpr float kPlace_m = 1e-3f, kAim_rad = 0.02f;
  bool at_view = false;
  for (const ExploreFrame& f : run->frames[0]) {
    if ((f.T_W_C.translation() - expected).norm() > kPlace_m) continue;
    const Eigen::Vector3f axis = f.T_W_C.linear().col(2);
    const Eigen::Vector3f to = (look - expected).normalized();
    at_view = at_view || std::acos(std::clamp(axis.dot(to), -1.f, 1.f)) < kAim_rad;
  }
  EXPECT_TRUE(at_view);
  // The same run without the switch's 2 s is 2 s shorter: one switch, into the reconstructor.
  Result<ExploreResult> free_switch =
      RunExplore(s.world, s.plan, {start}, *Goto(goal, camera), ArmExplore(0.f), {});
  ASSERT_TRUE(free_switch.ok()) << free_switch.status().message();
  EXPECT_NEAR(run->time_s - free_switch->time_s, 2.0, 0.26);  // a loop step: 0.25 s
}

TEST(Explore, AHeadSweepsItsPitchAtTheViewAndBadCameraPartsAreRejected) {
  const Scene& s = SmallApartment();
  ExploreParams params = ArmExplore(0.f);
  const Eigen::Vector2f start =
      ChooseStarts(s.plan, s.world.rooms, 1, params.robot.radius_m).value()[0];
  const Eigen::Vector2f goal = NearGoal(s, start, params.robot.radius_m);
  std::unique_ptr<LoadedPlanner> planner =
      Goto(goal, "\"sweep_min\": -0.5, \"sweep_max\": 0.5, \"sweep_step\": 0.25");
  Result<ExploreResult> run = RunExplore(s.world, s.plan, {start}, *planner, params, {});
  ASSERT_TRUE(run.ok()) << run.status().message();
  ASSERT_EQ(run->terminated, "done");
  // Frames at the view, one per sweep pitch: -0.5, -0.25, 0, 0.25, 0.5.
  std::vector<float> pitches;
  for (const ExploreFrame& f : run->frames[0]) {
    if ((f.T_W_C.translation().head<2>() - goal).norm() > 1e-3f) continue;
    pitches.push_back(std::asin(f.T_W_C.linear().col(2).z()));
  }
  for (float want : {-0.5f, -0.25f, 0.f, 0.25f, 0.5f}) {
    bool seen = false;
    for (float p : pitches) seen = seen || std::abs(p - want) < 1e-3f;
    EXPECT_TRUE(seen) << want;
  }
  // Refused: an arm height for the head-mounted explorer; an arm height out of its range; a
  // sweep past the head's pitch limit. The planner sends them again after each rejection.
  for (const std::string bad : {"\"height\": 0.6", "\"mode\": 1, \"height\": 2.5",
                                "\"sweep_min\": -1.5, \"sweep_max\": 0, \"sweep_step\": 0.5"}) {
    Result<ExploreResult> refused =
        RunExplore(s.world, s.plan, {start}, *Goto(goal, bad), params, {});
    ASSERT_TRUE(refused.ok()) << refused.status().message();
    EXPECT_GE(refused->rejected_tasks, 1u) << bad;
    EXPECT_TRUE(refused->task_views[0].empty()) << bad;
  }
}

// One frame of the small apartment from the first start, fused into `map` and `floor`.
void FuseFirstFrame(const Eigen::Vector2f& start, TsdfVolume& volume, PlanningMap& map,
                    FloorMap& floor) {
  RobotState state;
  state.position_W = start;
  const Pose3f T_W_C = CameraPoseFromState(state, FastParams().robot.camera_height_m);
  const PinholeCamera camera = CameraWithFov(160, 120, 90.f);
  std::unique_ptr<MeshRaycaster> raycaster = MeshRaycaster::Create(SmallApartment().world).value();
  const RenderOutput frame = raycaster->Render(camera, T_W_C, {.max_range_m = 5.f});
  Result<PlanningFrameStats> stats =
      IntegratePlanningFrame(frame.depth, frame.color, nullptr, camera, T_W_C, {}, volume, map);
  ASSERT_TRUE(stats.ok()) << stats.status().message();
  ASSERT_TRUE(floor.Update(volume, stats->integrate.touched_blocks).ok());
  ASSERT_GT(floor.width(), 0);
}

// The small apartment's volume, planning map and floor map after one frame from the first start.
struct OneFrame {
  const Scene& s = SmallApartment();
  const ExploreParams params = FastParams();
  const Eigen::Vector2f start =
      ChooseStarts(s.plan, s.world.rooms, 1, params.robot.radius_m).value()[0];
  TsdfVolume volume{VolumeParams{0.05f, 0.15f}};
  PlanningMap map{volume};
  FloorMap floor{0.05f, params.floor};
  OneFrame() { FuseFirstFrame(start, volume, map, floor); }
};

// A plain heap Dijkstra over the 16 moves of planning/geodesic.h (the cells a move crosses must be
// traversable too), summing float move costs in cells and scaling at the end as GeodesicField
// does: the same arithmetic, so its distances are the exact ones to expect.
std::vector<float> ReferenceField(const PlannerFloor& f, float min_clearance_m,
                                  Eigen::Vector2i source) {
  struct Move {
    int dx, dy;
    float cost;
    Eigen::Vector2i via0, via1;
  };
  std::vector<Move> moves;
  for (int s = -1; s <= 1; s += 2) {
    moves.push_back({s, 0, 1.f, {s, 0}, {s, 0}});
    moves.push_back({0, s, 1.f, {0, s}, {0, s}});
    for (int t = -1; t <= 1; t += 2) {
      moves.push_back({s, t, std::sqrt(2.f), {s, 0}, {0, t}});
      moves.push_back({2 * s, t, std::sqrt(5.f), {s, 0}, {s, t}});
      moves.push_back({s, 2 * t, std::sqrt(5.f), {0, t}, {s, t}});
    }
  }
  const auto open = [&](Eigen::Vector2i c) { return f.Traversable(c.x(), c.y(), min_clearance_m); };
  std::vector<float> dist(f.cells.size(), std::numeric_limits<float>::infinity());
  using Entry = std::pair<float, size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
  dist[f.Linear(source.x(), source.y())] = 0.f;
  heap.push({0.f, f.Linear(source.x(), source.y())});
  while (!heap.empty()) {
    const auto [d, i] = heap.top();
    heap.pop();
    if (d > dist[i]) continue;
    const Eigen::Vector2i c(int(i % size_t(f.width)), int(i / size_t(f.width)));
    for (const Move& m : moves) {
      const Eigen::Vector2i to = c + Eigen::Vector2i(m.dx, m.dy);
      if (!open(to) || !open(c + m.via0) || !open(c + m.via1)) continue;
      const size_t j = f.Linear(to.x(), to.y());
      if (d + m.cost < dist[j]) {
        dist[j] = d + m.cost;
        heap.push({dist[j], j});
      }
    }
  }
  for (float& d : dist) d *= f.cell_size_m;
  return dist;
}

TEST(ExploreWorld, PadsTheFloorWithUnknownAndFreesCellsUnderRobots) {
  OneFrame one;
  const ExploreParams& params = one.params;
  const Eigen::Vector2f start = one.start;
  PlanningMap& map = one.map;
  FloorMap& floor = one.floor;

  ExploreWorldParams wp;
  wp.unknown_margin_m = 1.0f;
  ExploreWorld world(map, floor, wp);
  world.Refresh();
  const PlannerFloor& f = world.Floor();
  const int pad = 20;  // 1 m of 5 cm cells
  ASSERT_EQ(f.width, floor.width() + 2 * pad);
  ASSERT_EQ(f.height, floor.height() + 2 * pad);
  EXPECT_EQ(f.cells[f.Linear(0, 0)], FloorCell::kUnknown);
  size_t free_cells = 0;
  for (int y = 0; y < floor.height(); ++y)
    for (int x = 0; x < floor.width(); ++x) {
      ASSERT_EQ(f.cells[f.Linear(x + pad, y + pad)], floor.At(x, y));
      free_cells += IsFree(floor.At(x, y)) ? 1 : 0;
    }
  ASSERT_GT(free_cells, 100u);  // the camera saw floor in front of it

  // The robot's own cells are never seen (the camera looks ahead, level): unknown until marked.
  const Eigen::Vector2i under = f.CellOf(start);
  ASSERT_TRUE(f.Contains(under.x(), under.y()));
  EXPECT_EQ(f.cells[f.Linear(under.x(), under.y())], FloorCell::kUnknown);
  world.MarkFootprint(start, params.robot.radius_m);
  world.Refresh();
  EXPECT_TRUE(IsFree(world.Floor().cells[f.Linear(under.x(), under.y())]));

  // Geodesic fields come on the padded raster: finite around a free source, +inf in the
  // margin. (From the robot itself nothing is reachable yet: one level frame leaves ~1.5 m in
  // front of it unseen, which is what the start sweep is for.)
  const float radius = params.robot.radius_m;
  size_t source = 0;
  while (source < f.cells.size() &&
         !(f.cells[source] == FloorCell::kFree && f.clearance_m[source] >= 2.f * radius))
    ++source;
  ASSERT_LT(source, f.cells.size());
  const Eigen::Vector2f source_m =
      f.CellCenter(int(source % size_t(f.width)), int(source / size_t(f.width)));
  Result<std::vector<float>> field = world.GeodesicField(source_m, radius);
  ASSERT_TRUE(field.ok()) << field.status().message();
  ASSERT_EQ(field->size(), world.Floor().cells.size());
  EXPECT_EQ((*field)[source], 0.f);
  EXPECT_FALSE(std::isfinite((*field)[f.Linear(0, 0)]));
  size_t reachable = 0;
  for (float d : *field) reachable += std::isfinite(d) ? 1 : 0;
  EXPECT_GT(reachable, 50u);
}

TEST(ExploreWorld, GeodesicFieldsOfRobotsAreExactDijkstraDistances) {
  OneFrame one;
  const ExploreParams& params = one.params;
  ExploreWorld world(one.map, one.floor, {});
  world.Refresh();
  const PlannerFloor& f = world.Floor();

  // Robots on the first and the last traversable cell: the first asked for computes both fields
  // at once, in parallel; each must still be its own robot's.
  const float radius = params.robot.radius_m;
  std::vector<size_t> traversable;
  for (size_t i = 0; i < f.cells.size(); ++i)
    if (f.Traversable(int(i % size_t(f.width)), int(i / size_t(f.width)), radius))
      traversable.push_back(i);
  ASSERT_GT(traversable.size(), 100u);
  std::vector<PlannerRobot> robots(2);
  const size_t cells[2] = {traversable.front(), traversable.back()};
  for (size_t r = 0; r < 2; ++r)
    robots[r].position_m =
        f.CellCenter(int(cells[r] % size_t(f.width)), int(cells[r] / size_t(f.width)));
  world.SetRobots(robots);
  for (size_t r = 0; r < 2; ++r) {
    Result<std::vector<float>> field = world.GeodesicField(robots[r].position_m, radius);
    ASSERT_TRUE(field.ok()) << field.status().message();
    const Eigen::Vector2i source = f.CellOf(robots[r].position_m);
    const std::vector<float> expected = ReferenceField(f, radius, source);
    ASSERT_EQ(field->size(), expected.size());
    size_t reachable = 0, mismatches = 0;
    for (size_t i = 0; i < expected.size(); ++i) {
      reachable += std::isfinite(expected[i]) ? 1 : 0;
      // Bit-exact: the same float sums in any order of settling.
      mismatches += (*field)[i] == expected[i] ? 0 : 1;
    }
    EXPECT_GT(reachable, 50u) << "robot " << r;
    EXPECT_EQ(mismatches, 0u) << "robot " << r;
  }
}

}  // namespace
}  // namespace voxplan
