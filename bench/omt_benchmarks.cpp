// OMT planner (Dong et al. 2019) timing: one full planning pass (task views, geodesics, OMT
// assignment, per-robot TSP, eq. 5 smoothing, yaw) with R = 10 robots and κ = 6 on a 20 × 12 m
// raster at 5 cm, plus its stages. Target: <= 100 ms per pass on 2 threads.
// Run: build/bench/voxplan_omtbench --benchmark_repetitions=10 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include "plugins/omt/algorithms/planner.h"
#include "plugins/omt/algorithms/raster_ops.h"
#include "plugins/omt/algorithms/task_views.h"
#include "tests/plugins/omt/omt_scenes.h"

namespace voxplan::omt {
namespace {

// 20 × 12 m floor, the first 12 m explored; ten robots spread over the explored rooms.
struct Scene {
  OccupancyRaster raster = testing::MakeApartment(20.0, 12.0, 0.05, /*known_x_m=*/12.0);
  ClearanceRaster clearance = ComputeClearance(raster);
  std::vector<RobotState> robots;
  Scene() {
    const Eigen::Vector2d at[10] = {{1.0, 3.0}, {3.0, 3.0}, {1.0, 5.5},  {3.5, 5.5},  {6.5, 3.0},
                                    {8.5, 4.0}, {7.0, 6.0}, {11.0, 3.0}, {11.0, 6.0}, {7.0, 10.0}};
    for (const auto& p : at) {
      RobotState r;
      r.position_m = p;
      robots.push_back(r);
    }
  }
};

const Scene& GetScene() {
  static const Scene scene;
  return scene;
}

void BM_OmtPlanningPass(benchmark::State& state) {
  const Scene& s = GetScene();
  PlannerOptions options;
  options.num_threads = static_cast<int>(state.range(0));
  PlanResult result;
  for (auto _ : state) {
    const Status status = PlanOmt(s.raster, &s.clearance, s.robots, options, &result);
    if (!status.ok()) state.SkipWithError(status.message.c_str());
    benchmark::DoNotOptimize(result);
  }
  int assigned = 0;
  for (int r : result.assignment.task_robot) assigned += r >= 0;
  state.counters["views"] = static_cast<double>(result.views.size());
  state.counters["assigned"] = assigned;
}
BENCHMARK(BM_OmtPlanningPass)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same pass computing the clearance raster itself (host gives none).
void BM_OmtPlanningPassWithClearance(benchmark::State& state) {
  const Scene& s = GetScene();
  PlannerOptions options;
  PlanResult result;
  for (auto _ : state) {
    PlanOmt(s.raster, nullptr, s.robots, options, &result);
    benchmark::DoNotOptimize(result);
  }
}
BENCHMARK(BM_OmtPlanningPassWithClearance)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OmtClearance(benchmark::State& state) {
  const Scene& s = GetScene();
  for (auto _ : state) benchmark::DoNotOptimize(ComputeClearance(s.raster));
}
BENCHMARK(BM_OmtClearance)->Unit(benchmark::kMillisecond);

void BM_OmtTaskViews(benchmark::State& state) {
  const Scene& s = GetScene();
  TaskViewParams params;
  params.max_views = 60;
  for (auto _ : state) benchmark::DoNotOptimize(ExtractTaskViews(s.raster, s.clearance, params));
}
BENCHMARK(BM_OmtTaskViews)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace voxplan::omt

BENCHMARK_MAIN();
