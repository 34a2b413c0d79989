// Micro-benchmarks of the fusion core on frames the simulator renders of the demo room:
// the block hash map, band allocation, the scalar and SIMD block kernels, whole-frame
// integration, marching cubes and ray casting. Run: build/bench/voxplan_microbench
// [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "core/block_map.h"
#include "core/parallel.h"
#include "core/raycast.h"
#include "fusion/integrate.h"
#include "fusion/integrate_kernel.h"
#include "fusion/mesh_extract.h"
#include "sim/demo_room.h"
#include "sim/raycaster.h"

namespace voxplan {
namespace {

struct Frames {
  PinholeCamera camera = DemoCamera();
  std::vector<RenderOutput> images;
  std::vector<Pose3f> poses;
};

// Every 8th pose of the demo trajectory, rendered once for all benchmarks.
const Frames& DemoFrames() {
  static const Frames frames = [] {
    Frames f;
    const DemoRoomParams room;
    auto raycaster = MeshRaycaster::Create(BuildDemoRoom(room));
    const auto poses = DemoTrajectory(room, kDemoFrames);
    for (size_t i = 0; i < poses.size(); i += 8) {
      f.poses.push_back(poses[i].cast<float>());
      f.images.push_back((*raycaster)->Render(f.camera, f.poses.back()));
    }
    return f;
  }();
  return frames;
}

TsdfVolume FusedVolume(float voxel_size_m) {
  const Frames& f = DemoFrames();
  TsdfVolume volume({voxel_size_m, 4 * voxel_size_m});
  for (size_t i = 0; i < f.poses.size(); ++i)
    (void)IntegrateFrame(f.images[i].depth, f.images[i].color, f.camera, f.poses[i], {}, volume);
  return volume;
}

void BM_BlockMapInsert(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> coord(-64, 64);
  std::vector<BlockIndex> keys(size_t(state.range(0)));
  for (auto& k : keys) k = {coord(rng), coord(rng), coord(rng)};
  for (auto _ : state) {
    BlockMap map;
    for (size_t i = 0; i < keys.size(); ++i) map.Insert(keys[i], uint32_t(i));
    benchmark::DoNotOptimize(map.size());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
}
BENCHMARK(BM_BlockMapInsert)->Arg(1 << 12)->Arg(1 << 16);

void BM_BlockMapFind(benchmark::State& state) {
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> coord(-64, 64);
  BlockMap map;
  std::vector<BlockIndex> keys(size_t(state.range(0)));
  for (size_t i = 0; i < keys.size(); ++i) {
    keys[i] = {coord(rng), coord(rng), coord(rng)};
    map.Insert(keys[i], uint32_t(i));
  }
  for (auto _ : state)
    for (const auto& k : keys) benchmark::DoNotOptimize(map.Find(k));
  state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
}
BENCHMARK(BM_BlockMapFind)->Arg(1 << 12)->Arg(1 << 16);

void BM_BandAllocation(benchmark::State& state) {
  const Frames& f = DemoFrames();
  const VolumeParams params{float(state.range(0)) / 1000.f, 4 * float(state.range(0)) / 1000.f};
  size_t blocks = 0;
  for (auto _ : state) {
    const auto band = BlocksInTruncationBand(f.images[3].depth, f.camera, f.poses[3], {}, params);
    blocks = band.size();
  }
  state.counters["blocks"] = double(blocks);
}
BENCHMARK(BM_BandAllocation)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond);

// The block update alone over one frame's band blocks: scalar vs SIMD, one thread.
void BM_BlockKernel(benchmark::State& state) {
  const bool simd = state.range(0) == 1;
  if (simd && !SimdKernelAvailable()) {
    state.SkipWithError("no AVX2");
    return;
  }
  const Frames& f = DemoFrames();
  TsdfVolume volume({0.01f, 0.04f});
  const auto band =
      BlocksInTruncationBand(f.images[3].depth, f.camera, f.poses[3], {}, volume.params());
  std::vector<TsdfBlock*> blocks;
  for (const auto& b : band) blocks.push_back(&volume.FindOrAllocate(b));
  internal::FrameView view;
  view.depth = f.images[3].depth.data.data();
  view.color = f.images[3].color.data.data();
  view.width = f.camera.width;
  view.height = f.camera.height;
  view.fx = f.camera.fx;
  view.fy = f.camera.fy;
  view.cx = f.camera.cx;
  view.cy = f.camera.cy;
  const Pose3f T_C_W = f.poses[3].inverse();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) view.r[3 * r + c] = T_C_W.linear()(r, c);
    view.t[r] = T_C_W.translation()[r];
  }
  view.min_depth_m = 0.1f;
  view.max_depth_m = 3.0f;
  view.trunc_m = 0.04f;
  view.inv_trunc = 25.f;
  view.voxel_size_m = 0.01f;
  view.max_weight = 64.f;
  const auto kernel = simd ? internal::IntegrateBlockSimd : internal::IntegrateBlockScalar;
  for (auto _ : state)
    for (size_t i = 0; i < band.size(); ++i) kernel(view, band[i], *blocks[i]);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(band.size()) * kBlockVoxels);
  state.SetLabel(simd ? "avx2" : "scalar");
}
BENCHMARK(BM_BlockKernel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_IntegrateFrame(benchmark::State& state) {
  const Frames& f = DemoFrames();
  ThreadLimit limit(int(state.range(1)));
  const float voxel = float(state.range(0)) / 1000.f;
  TsdfVolume volume({voxel, 4 * voxel});
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % f.poses.size();
    benchmark::DoNotOptimize(
        IntegrateFrame(f.images[k].depth, f.images[k].color, f.camera, f.poses[k], {}, volume));
  }
}
BENCHMARK(BM_IntegrateFrame)
    ->Args({10, 1})
    ->Args({10, 2})
    ->Args({5, 1})
    ->Args({5, 2})
    ->Unit(benchmark::kMillisecond);

void BM_ExtractMesh(benchmark::State& state) {
  ThreadLimit limit(int(state.range(1)));
  const TsdfVolume volume = FusedVolume(float(state.range(0)) / 1000.f);
  size_t triangles = 0;
  for (auto _ : state) triangles = ExtractMesh(volume).num_triangles();
  state.counters["triangles"] = double(triangles);
  state.counters["blocks"] = double(volume.num_blocks());
}
BENCHMARK(BM_ExtractMesh)->Args({10, 1})->Args({10, 2})->Unit(benchmark::kMillisecond);

// Ray casting the fused demo room from the demo poses: {voxel mm, threads}. Images are reused,
// as a tracker or viewer does.
void BM_RaycastFrame(benchmark::State& state) {
  const Frames& f = DemoFrames();
  ThreadLimit limit(int(state.range(1)));
  const TsdfVolume volume = FusedVolume(float(state.range(0)) / 1000.f);
  RaycastImages images;
  size_t i = 0, hits = 0, pixels = 0;
  for (auto _ : state) {
    const size_t k = i++ % f.poses.size();
    Raycast(volume, f.camera, f.poses[k], {}, images);
    pixels += images.status.data.size();
    hits += size_t(
        std::count(images.status.data.begin(), images.status.data.end(), uint8_t(RayStatus::kHit)));
  }
  state.counters["hit_fraction"] = pixels ? double(hits) / double(pixels) : 0.0;
}
BENCHMARK(BM_RaycastFrame)->Args({10, 1})->Args({10, 2})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace voxplan

BENCHMARK_MAIN();
