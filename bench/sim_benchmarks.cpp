// Simulator benchmarks (Google Benchmark): one 640x480 frame of the AWS small house rendered
// with depth + labels (+ colour, + normals), on 1 and 2 threads, and the Kinect noise model.
// The house comes from $VOXPLAN_SHARED_DATA or ../shared/data beside the source tree.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include "core/parallel.h"
#include "sim/raycaster.h"
#include "sim/scene_loader.h"
#include "sim/sensor_noise.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

fs::path SharedData() {
  if (const char* env = std::getenv("VOXPLAN_SHARED_DATA")) return env;
  return fs::path(VOXPLAN_SOURCE_DIR) / ".." / "shared" / "data";
}

// Loaded once: building the BVH takes far longer than a frame.
const MeshRaycaster* House() {
  static std::unique_ptr<MeshRaycaster> raycaster = [] {
    const fs::path ply =
        SharedData() / "scenes" / "aws_small_house" / "derived" / "small_house_visual.ply";
    // The house with its instance table (small_house_visual_instances.tsv beside the PLY).
    auto world = LoadWorld(ply.string());
    if (!world.ok()) return std::unique_ptr<MeshRaycaster>();
    auto r = MeshRaycaster::Create(*world);
    return r.ok() ? std::move(r).value() : std::unique_ptr<MeshRaycaster>();
  }();
  return raycaster.get();
}

PinholeCamera Kinect() { return {640, 480, 525.f, 525.f, 319.5f, 239.5f}; }

// Living room of the house, camera 1.2 m up looking along +x (most of the house in view).
Pose3f LivingRoomView() {
  return LookAt(Eigen::Vector3f(-6.f, 0.5f, 1.2f), Eigen::Vector3f(2.f, 0.f, 1.0f));
}

// range(0): threads; range(1): 0 depth + labels, 1 + colour, 2 + colour + normals.
void BM_RenderHouse(benchmark::State& state) {
  const MeshRaycaster* house = House();
  if (!house) {
    state.SkipWithError("small_house_visual.ply not found (set VOXPLAN_SHARED_DATA)");
    return;
  }
  ThreadLimit limit(int(state.range(0)));
  RenderParams params;
  params.labels = true;
  params.color = state.range(1) >= 1;
  params.normals = state.range(1) >= 2;
  const PinholeCamera camera = Kinect();
  const Pose3f T_W_C = LivingRoomView();
  size_t hits = 0, labelled = 0;
  for (auto _ : state) {
    RenderOutput out = house->Render(camera, T_W_C, params);
    benchmark::DoNotOptimize(out);
    state.PauseTiming();
    hits = labelled = 0;
    for (float d : out.depth.data) hits += d > 0.f;
    for (uint32_t id : out.labels.data) labelled += id != kNoInstance;
    state.ResumeTiming();
  }
  state.counters["hit_fraction"] = double(hits) / (640.0 * 480.0);
  state.counters["labelled_fraction"] = double(labelled) / (640.0 * 480.0);
}
BENCHMARK(BM_RenderHouse)
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Args({2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_KinectNoise(benchmark::State& state) {
  const MeshRaycaster* house = House();
  if (!house) {
    state.SkipWithError("small_house_visual.ply not found (set VOXPLAN_SHARED_DATA)");
    return;
  }
  ThreadLimit limit(int(state.range(0)));
  RenderParams params;
  params.color = false;
  params.normals = true;
  const PinholeCamera camera = Kinect();
  const RenderOutput clean = house->Render(camera, LivingRoomView(), params);
  const KinectNoiseParams noise;
  uint64_t frame = 0;
  for (auto _ : state) {
    auto noisy = ApplyKinectNoise(clean.depth, clean.normals_C, camera, noise, frame++);
    benchmark::DoNotOptimize(noisy);
  }
}
BENCHMARK(BM_KinectNoise)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace voxplan

BENCHMARK_MAIN();
